// Authentication of calibration requests: LCM is unauthenticated multicast and a request moves
// the arm, so every request carries an HMAC-SHA256 tag (libsodium's crypto_auth_hmacsha256) over
// a canonical encoding of all its other fields, a timestamp and a single-use nonce.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/util/expected.h"
#include "selfcal/calibration_request_t.hpp"

namespace selfcal::daemon {

inline constexpr std::size_t kKeyBytes = 32;
inline constexpr std::size_t kTagBytes = 32;
inline constexpr std::size_t kMaxNonceChars = 128;
inline constexpr std::size_t kMaxFieldChars = 256;  // plan_name, requested_by
using Key = std::array<std::uint8_t, kKeyBytes>;

// The bytes the tag covers: a domain string, then utime (8 bytes big-endian), action (1 byte),
// and nonce, plan_name, requested_by, each as a 4-byte big-endian length and its bytes.
// Independent of LCM's encoding, so a change of the wire type cannot silently change what is
// signed.
std::vector<std::uint8_t> CanonicalRequestBytes(const selfcal::calibration_request_t& request);

// Fills tag_length and tag.
void SignRequest(selfcal::calibration_request_t& request, const Key& key);

// A fresh random nonce (32 hex characters).
std::string RandomNonce();

// Reads a key file: 64 hex characters (one optional trailing newline). With `require_private`,
// refuses a file that its group or others may read or write (the daemon's own key).
Expected<Key> ReadKeyFile(const std::string& path, bool require_private);
// Writes a new random key with mode 0600; refuses to overwrite an existing file.
Status GenerateKeyFile(const std::string& path);

// Why a request was refused; kAccepted when it may be acted on.
enum class Verdict { kAccepted, kUnsigned, kBadSignature, kStale, kReplayed, kMalformed };
const char* VerdictText(Verdict verdict);

// Checks the fields' lengths (before the signature: a forged request costs no more than its
// bytes), the signature, the time window and the nonce. Remembers the nonces of authentic, fresh
// requests for twice the window, so a replay is refused for as long as it would otherwise be fresh.
class RequestAuthenticator {
 public:
  RequestAuthenticator(Key key, double window_s)
      : key_(key), window_us_(static_cast<std::int64_t>(window_s * 1e6)) {}
  Verdict Check(const selfcal::calibration_request_t& request, std::int64_t now_utime);
  // Nonces seen before a restart (from the history), so a restart does not open a replay window.
  void RememberNonce(const std::string& nonce, std::int64_t utime);
  std::int64_t window_us() const { return window_us_; }

 private:
  void Forget(std::int64_t now_utime);
  Key key_;
  std::int64_t window_us_;
  std::unordered_map<std::string, std::int64_t> seen_;      // nonce -> request utime
  std::deque<std::pair<std::int64_t, std::string>> order_;  // by insertion, for expiry
};

}  // namespace selfcal::daemon
