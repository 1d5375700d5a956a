#include "daemon/request_policy.h"

#include "core/util/printable.h"

namespace selfcal::daemon {
namespace {

using Request_t = selfcal::calibration_request_t;

std::string BusyReason(const Situation& situation) {
  const bool idle = situation.state == State::kIdle;
  return std::string("busy (") + StateName(situation.state) +
         (situation.session_id.empty() || idle ? "" : " session " + situation.session_id) +
         (idle ? ", previous computation still stopping" : "") + ")";
}

}  // namespace

RequestDecision DecideRequest(Verdict verdict, const Request_t& request, const Situation& situation,
                              const std::string& default_plan,
                              const std::map<std::string, std::string>& plan_files) {
  RequestDecision decision;
  decision.verdict = verdict;
  decision.reason = VerdictReason(verdict);
  if (!decision.authentic()) return decision;
  const bool busy = situation.state != State::kIdle || situation.computation_stopping;
  if (request.action == Request_t::ABORT) {
    if (situation.state == State::kIdle) {
      decision.refusal = Refusal::kNothingToAbort;
      decision.reason = "nothing to abort (idle)";
    }
  } else if (busy) {
    decision.refusal = Refusal::kBusy;
    decision.reason = BusyReason(situation);
  } else if (request.action == Request_t::START) {
    decision.plan = request.plan_name.empty() ? default_plan : request.plan_name;
    if (!plan_files.count(decision.plan)) {
      decision.refusal = Refusal::kUnknownPlan;
      decision.reason = "unknown plan '" + Printable(decision.plan) + "'";
    }
  }
  return decision;
}

RequestDecision MalformedRequest(const std::string& why) {
  RequestDecision decision;
  decision.verdict = Verdict::kMalformed;
  decision.reason = "malformed request (" + why + ")";
  return decision;
}

std::string DescribeRequest(const Request_t& request) {
  return std::string(ActionName(request.action)) + " robot=" + Printable(request.robot_id) +
         " nonce=" + Printable(request.nonce) + " by='" + Printable(request.requested_by) +
         "' plan='" + Printable(request.plan_name) + "' utime=" + std::to_string(request.utime);
}

bool RateLimit::Take(std::int64_t now) {
  if (!started_ || now - since_ >= interval_us_ || now < since_) {
    started_ = true;
    since_ = now;
    taken_ = 0;
  }
  if (taken_ >= per_interval_) return false;
  ++taken_;
  return true;
}

const char* RefusalName(Refusal refusal) {
  switch (refusal) {
    case Refusal::kNone:
      return "accepted";
    case Refusal::kUnrecorded:
      return "cannot record the request in the history";
    case Refusal::kNothingToAbort:
      return "nothing to abort";
    case Refusal::kBusy:
      return "busy";
    case Refusal::kUnknownPlan:
      return "unknown plan";
  }
  return "refused";
}

const char* ActionName(std::int8_t action) {
  switch (action) {
    case Request_t::START:
      return "START";
    case Request_t::ABORT:
      return "ABORT";
    case Request_t::ROLLBACK:
      return "ROLLBACK";
  }
  return "UNKNOWN";
}

}  // namespace selfcal::daemon
