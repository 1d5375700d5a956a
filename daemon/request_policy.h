// What the daemon does with a calibration request: the authenticator's verdict, then whether the
// daemon's situation allows the action (an ABORT needs a session, a START or ROLLBACK needs an
// idle daemon whose last computation has stopped, a START a known plan). Pure: the daemon logs
// the decision, writes it to the history and acts on it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

#include "daemon/auth.h"
#include "daemon/state.h"
#include "selfcal/calibration_request_t.hpp"

namespace selfcal::daemon {

// The most bytes a calibration request may have on the wire: larger ones are refused before they
// are decoded. A request is a few short strings and a 32-byte tag, a few hundred bytes.
inline constexpr std::size_t kMaxRequestBytes = 4096;

// Why an authentic request is refused: what the daemon's situation does not allow. Refusals of
// the authenticator are its Verdict.
enum class Refusal {
  kNone,
  kUnrecorded,  // its nonce could not be written to the history
  kNothingToAbort,
  kBusy,
  kUnknownPlan,
};

// A short fixed name per refusal ("busy"), for counting refusals per reason in the log.
const char* RefusalName(Refusal refusal);

struct Situation {
  State state = State::kIdle;
  std::string session_id;             // the running session, if any
  bool computation_stopping = false;  // an aborted engine run has not returned yet
};

struct RequestDecision {
  Verdict verdict = Verdict::kMalformed;
  Refusal refusal = Refusal::kNone;
  std::string plan;    // START: the plan to run (the request's, or the default)
  std::string reason;  // why it is refused ("busy (MOVING)"); empty when accepted
  // Signed with our key and fresh: its nonce is used up, even when the situation refuses it.
  bool authentic() const { return verdict == Verdict::kAccepted; }
  bool accepted() const { return authentic() && refusal == Refusal::kNone; }
  // "accepted", or "refused: " and the reason: what the requester is answered.
  std::string text() const { return accepted() ? "accepted" : RefusedText(reason); }
};

RequestDecision DecideRequest(Verdict verdict, const selfcal::calibration_request_t& request,
                              const Situation& situation, const std::string& default_plan,
                              const std::map<std::string, std::string>& plan_files);
// A request that did not decode: refused as malformed, naming the decoder's error.
RequestDecision MalformedRequest(const std::string& why);

const char* ActionName(std::int8_t action);

// At most `per_interval` events per interval (answers to refused requests: a forger cannot make
// the daemon flood the status channel for him).
class RateLimit {
 public:
  RateLimit(int per_interval, std::int64_t interval_us)
      : per_interval_(per_interval), interval_us_(interval_us) {}
  bool Take(std::int64_t now);  // [us, monotonic]

 private:
  int per_interval_;
  std::int64_t interval_us_;
  std::int64_t since_ = 0;
  int taken_ = 0;
  bool started_ = false;
};
// A request for the log: action and fields, escaped and cut (they come from anyone).
std::string DescribeRequest(const selfcal::calibration_request_t& request);

}  // namespace selfcal::daemon
