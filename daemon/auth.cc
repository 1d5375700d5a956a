#include "daemon/auth.h"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <set>

#include "core/util/atomic_file.h"

namespace selfcal::daemon {
namespace {

constexpr char kDomain[] = "selfcal.calibration_request_t/v2";

void InitSodium() {
  // sodium_init is idempotent and thread-safe; failure means no usable randomness (tier 1).
  if (sodium_init() < 0) {
    std::fprintf(stderr, "selfcal: sodium_init failed\n");
    std::abort();
  }
}

void AppendUint(std::vector<std::uint8_t>& out, std::uint64_t value, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}

void AppendString(std::vector<std::uint8_t>& out, const std::string& text) {
  AppendUint(out, text.size(), 4);
  out.insert(out.end(), text.begin(), text.end());
}

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

std::vector<std::uint8_t> CanonicalRequestBytes(const selfcal::calibration_request_t& request) {
  std::vector<std::uint8_t> out(kDomain, kDomain + sizeof(kDomain) - 1);
  AppendUint(out, static_cast<std::uint64_t>(request.utime), 8);
  AppendUint(out, static_cast<std::uint8_t>(request.action), 1);
  AppendString(out, request.robot_id);
  AppendString(out, request.nonce);
  AppendString(out, request.plan_name);
  AppendString(out, request.requested_by);
  return out;
}

void SignRequest(selfcal::calibration_request_t& request, const Key& key) {
  InitSodium();
  const auto bytes = CanonicalRequestBytes(request);
  request.tag.assign(kTagBytes, 0);
  crypto_auth_hmacsha256(reinterpret_cast<unsigned char*>(request.tag.data()), bytes.data(),
                         bytes.size(), key.data());
  request.tag_length = static_cast<std::int32_t>(kTagBytes);
}

std::string RandomNonce() {
  InitSodium();
  unsigned char raw[16];
  randombytes_buf(raw, sizeof(raw));
  char hex[2 * sizeof(raw) + 1];
  sodium_bin2hex(hex, sizeof(hex), raw, sizeof(raw));
  return hex;
}

Expected<Key> ReadKeyFile(const std::string& path, bool require_private) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    return Error{path + ": cannot read the key file: " + std::strerror(errno)};
  }
  if (!S_ISREG(info.st_mode)) return Error{path + ": the key file is not a regular file"};
  if (require_private && (info.st_mode & (S_IRWXG | S_IRWXO)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(info.st_mode & 07777));
    return Error{path + ": the key file has mode " + mode +
                 "; group or others may access it (run chmod 600 " + path + ")"};
  }
  auto text = ReadFile(path, 4096);
  if (!text) return text.error();
  std::string hex = *text;
  if (!hex.empty() && hex.back() == '\n') hex.pop_back();
  if (hex.size() != 2 * kKeyBytes) {
    return Error{path + ": a key file holds " + std::to_string(2 * kKeyBytes) +
                 " hex characters, this one has " + std::to_string(hex.size())};
  }
  Key key{};
  for (std::size_t i = 0; i < kKeyBytes; ++i) {
    const int high = HexValue(hex[2 * i]);
    const int low = HexValue(hex[2 * i + 1]);
    if (high < 0 || low < 0) {
      return Error{path + ": byte " + std::to_string(2 * i) + " of the key is not a hex digit"};
    }
    key[i] = static_cast<std::uint8_t>(high * 16 + low);
  }
  std::set<std::uint8_t> distinct(key.begin(), key.end());
  if (static_cast<int>(distinct.size()) < kMinDistinctKeyBytes) {
    return Error{path + ": the key is weak (" + std::to_string(distinct.size()) +
                 " distinct byte values: all zero or repeated bytes); write a random one with "
                 "selfcald --generate-key"};
  }
  return key;
}

Status GenerateKeyFile(const std::string& path) {
  InitSodium();
  Key key;
  randombytes_buf(key.data(), key.size());
  char hex[2 * kKeyBytes + 1];
  sodium_bin2hex(hex, sizeof(hex), key.data(), key.size());
  sodium_memzero(key.data(), key.size());
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return Error{path + ": cannot create the key file: " + std::strerror(errno)};
  std::string text = std::string(hex) + "\n";
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const bool synced = ::fsync(fd) == 0;
  ::close(fd);
  sodium_memzero(hex, sizeof(hex));
  if (!written || !synced) {
    ::unlink(path.c_str());
    return Error{path + ": cannot write the key file: " + std::strerror(errno)};
  }
  return OkStatus();
}

const char* VerdictText(Verdict verdict) {
  switch (verdict) {
    case Verdict::kAccepted:
      return "accepted";
    case Verdict::kUnsigned:
      return "refused: unsigned request (no tag)";
    case Verdict::kBadSignature:
      return "refused: wrong signature (tag does not match the key)";
    case Verdict::kStale:
      return "refused: stale request (utime outside the time window)";
    case Verdict::kReplayed:
      return "refused: replayed request (nonce already used)";
    case Verdict::kMalformed:
      return "refused: malformed request";
    case Verdict::kOtherRobot:
      return "refused: the request is for another robot (robot_id)";
    case Verdict::kTooOld:
      return "refused: signed before the oldest request the daemon remembers (a replay, or the "
             "sender's clock is behind)";
  }
  return "refused";
}

Verdict RequestAuthenticator::Check(const selfcal::calibration_request_t& request,
                                    std::int64_t now_utime) {
  if (request.nonce.size() > kMaxNonceChars || request.plan_name.size() > kMaxFieldChars ||
      request.requested_by.size() > kMaxFieldChars || request.robot_id.size() > kMaxFieldChars) {
    return Verdict::kMalformed;
  }
  if (request.tag_length == 0) return Verdict::kUnsigned;
  if (request.tag_length != static_cast<std::int32_t>(kTagBytes) ||
      request.tag.size() != kTagBytes) {
    return Verdict::kBadSignature;
  }
  InitSodium();
  const auto bytes = CanonicalRequestBytes(request);
  if (crypto_auth_hmacsha256_verify(reinterpret_cast<const unsigned char*>(request.tag.data()),
                                    bytes.data(), bytes.size(), key_.data()) != 0) {
    return Verdict::kBadSignature;
  }
  // Only authentic requests reach the checks below, so a forger cannot fill the nonce cache.
  if (request.nonce.empty()) return Verdict::kMalformed;
  if (request.action != selfcal::calibration_request_t::START &&
      request.action != selfcal::calibration_request_t::ABORT &&
      request.action != selfcal::calibration_request_t::ROLLBACK) {
    return Verdict::kMalformed;
  }
  // Authentic, but for another daemon sharing the key: its nonce is not ours to use up.
  if (request.robot_id != robot_id_) return Verdict::kOtherRobot;
  // The sender chose utime: a difference that overflows is as stale as one beyond the window.
  std::int64_t age = 0;
  if (__builtin_sub_overflow(now_utime, request.utime, &age) || age > window_us_ ||
      age < -window_us_) {
    return Verdict::kStale;
  }
  if (request.utime <= refused_up_to_) return Verdict::kTooOld;
  if (seen_.count(request.nonce)) return Verdict::kReplayed;
  RememberNonce(request.nonce, request.utime);
  return Verdict::kAccepted;
}

void RequestAuthenticator::RememberNonce(const std::string& nonce, std::int64_t utime) {
  if (!seen_.insert(nonce).second) return;
  by_utime_.emplace(utime, nonce);
  while (by_utime_.size() > capacity_) {
    const auto oldest = by_utime_.begin();
    RefuseUpTo(oldest->first);
    seen_.erase(oldest->second);
    by_utime_.erase(oldest);
  }
}

void RequestAuthenticator::RefuseUpTo(std::int64_t utime) {
  refused_up_to_ = std::max(refused_up_to_, utime);
}

}  // namespace selfcal::daemon
