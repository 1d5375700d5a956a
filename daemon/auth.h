// Authentication of calibration requests: LCM is unauthenticated multicast and a request moves
// the arm, so every request carries an HMAC-SHA256 tag (protocols/auth/key.h, the request's own
// domain string) over a canonical encoding of all its other fields, a timestamp and a single-use
// nonce.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/util/expected.h"
#include "protocols/auth/key.h"
#include "selfcal/calibration_request_t.hpp"

namespace selfcal::daemon {

inline constexpr std::size_t kMaxNonceChars = 128;
inline constexpr std::size_t kMaxFieldChars = 256;  // robot_id, plan_name, requested_by
// The bytes the tag covers after the domain string "selfcal.calibration_request_t/v2": utime (8
// bytes big-endian), action (1 byte), and robot_id, nonce, plan_name, requested_by, each as a
// 4-byte big-endian length and its bytes. Independent of LCM's encoding, so a change of the wire
// type cannot silently change what is signed.
std::vector<std::uint8_t> CanonicalRequestBytes(const selfcal::calibration_request_t& request);

// Fills tag_length and tag.
void SignRequest(selfcal::calibration_request_t& request, const auth::Key& key);

// A fresh random nonce (32 hex characters).
std::string RandomNonce();

// Why a request was refused; kAccepted when it may be acted on.
enum class Verdict {
  kAccepted,
  kUnsigned,
  kBadSignature,
  kStale,
  kReplayed,
  kMalformed,
  kTooOld,
  kOtherRobot,
};
// Why a request is refused ("wrong signature (...)"), empty for kAccepted.
const char* VerdictReason(Verdict verdict);
// What a request is answered: "accepted", or "refused: " and the reason.
std::string VerdictText(Verdict verdict);
inline std::string RefusedText(const std::string& reason) { return "refused: " + reason; }

// How many used nonces the authenticator remembers.
inline constexpr std::size_t kNonceCapacity = 10'000;

// Checks the fields' lengths (before the signature: a forged request costs no more than its
// bytes), the signature, the time window and the nonce. The time window compares the request's
// utime with the wall clock (the sender signed wall time); nothing expires by time: the nonces of
// authentic, fresh requests are remembered up to `capacity`, and when one must be forgotten (the
// oldest request's), every request signed at or before it is refused from then on (kTooOld). So
// no used nonce is ever accepted again, whatever the wall clock does.
class RequestAuthenticator {
 public:
  // Accepts requests for `robot_id` only.
  RequestAuthenticator(auth::Key key, std::string robot_id, double window_s,
                       std::size_t capacity = kNonceCapacity)
      : key_(key),
        robot_id_(std::move(robot_id)),
        window_us_(static_cast<std::int64_t>(window_s * 1e6)),
        capacity_(capacity) {}
  Verdict Check(const selfcal::calibration_request_t& request, std::int64_t now_utime);
  // Nonces used before a restart (from the history), so a restart does not open a replay window.
  void RememberNonce(const std::string& nonce, std::int64_t utime);
  // Refuses every request signed at or before `utime` (their nonces are forgotten).
  void RefuseUpTo(std::int64_t utime);
  std::int64_t window_us() const { return window_us_; }

 private:
  auth::Key key_;
  std::string robot_id_;
  std::int64_t window_us_;
  std::size_t capacity_;
  // The used nonces with their request's utime, and the same oldest first: a min-heap of
  // pointers to the map's keys (they stay put when the map rehashes), so that each nonce is held
  // once (10,000 nonces of 32 characters take 1.5 MB of heap; 2.5 MB with a second copy in an
  // ordered set).
  using UtimeAndNonce = std::pair<std::int64_t, const std::string*>;
  std::unordered_map<std::string, std::int64_t> seen_;
  std::priority_queue<UtimeAndNonce, std::vector<UtimeAndNonce>, std::greater<>> by_utime_;
  std::int64_t refused_up_to_ = std::numeric_limits<std::int64_t>::min();
};

}  // namespace selfcal::daemon
