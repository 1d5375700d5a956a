#include "protocols/auth/key.h"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>

#include "core/util/atomic_file.h"

namespace selfcal::auth {
namespace {

void InitSodium() {
  // sodium_init is idempotent and thread-safe; failure means no usable randomness (tier 1).
  if (sodium_init() < 0) {
    std::fprintf(stderr, "selfcal: sodium_init failed\n");
    std::abort();
  }
}

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

void Hmac(const Key& key, std::string_view domain, std::span<const std::uint8_t> message,
          unsigned char out[kTagBytes]) {
  InitSodium();
  crypto_auth_hmacsha256_state state;
  crypto_auth_hmacsha256_init(&state, key.data(), key.size());
  crypto_auth_hmacsha256_update(&state, reinterpret_cast<const unsigned char*>(domain.data()),
                                domain.size());
  crypto_auth_hmacsha256_update(&state, message.data(), message.size());
  crypto_auth_hmacsha256_final(&state, out);
  sodium_memzero(&state, sizeof(state));
}

}  // namespace

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

std::vector<std::uint8_t> Tag(const Key& key, std::string_view domain,
                              std::span<const std::uint8_t> message) {
  std::vector<std::uint8_t> tag(kTagBytes);
  Hmac(key, domain, message, tag.data());
  return tag;
}

bool TagMatches(const Key& key, std::string_view domain, std::span<const std::uint8_t> message,
                std::span<const std::uint8_t> tag) {
  if (tag.size() != kTagBytes) return false;
  unsigned char expected[kTagBytes];
  Hmac(key, domain, message, expected);
  return sodium_memcmp(expected, tag.data(), kTagBytes) == 0;
}

std::string RandomHex(std::size_t bytes) {
  InitSodium();
  std::vector<unsigned char> raw(bytes);
  randombytes_buf(raw.data(), raw.size());
  std::string hex(2 * bytes + 1, '\0');
  sodium_bin2hex(hex.data(), hex.size(), raw.data(), raw.size());
  hex.pop_back();
  return hex;
}

void AppendUint(std::vector<std::uint8_t>& out, std::uint64_t value, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}

void AppendString(std::vector<std::uint8_t>& out, std::string_view text) {
  AppendUint(out, text.size(), 4);
  out.insert(out.end(), text.begin(), text.end());
}

void AppendDouble(std::vector<std::uint8_t>& out, double value) {
  AppendUint(out, std::bit_cast<std::uint64_t>(value), 8);
}

}  // namespace selfcal::auth
