#include "daemon/result_message.h"

namespace selfcal::daemon {
namespace {

using Result_t = selfcal::calibration_result_t;

std::int8_t ResultOutcome(State outcome) {
  switch (outcome) {
    case State::kAccepted:
      return Result_t::ACCEPTED;
    case State::kRejected:
      return Result_t::REJECTED;
    case State::kAborted:
      return Result_t::ABORTED;
    default:
      return Result_t::FAILED;
  }
}

void AddParameters(const RobotModel& before, const CalibratedModel& after, Result_t& result) {
  const auto k_before = ToParameterVector(before);
  const auto k_after = ToParameterVector(after.model);
  for (std::size_t i = 0; i < k_before.size() && i < k_after.size(); ++i) {
    if (!before.mask[i]) continue;
    result.parameter_names.push_back(ParameterName(before, i));
    result.parameters_before.push_back(k_before[i]);
    result.parameters_after.push_back(k_after[i]);
    result.parameter_stddev.push_back(i < after.stddev.size() ? after.stddev[i] : -1.0);
  }
  result.num_parameters = static_cast<std::int32_t>(result.parameter_names.size());
}

}  // namespace

const char* OutcomeWord(State outcome) {
  switch (outcome) {
    case State::kAccepted:
      return "accepted";
    case State::kRejected:
      return "rejected";
    case State::kAborted:
      return "aborted";
    default:
      return "failed";
  }
}

Result_t MakeResultMessage(const std::string& session_id, const SessionOutcome& outcome) {
  Result_t result;
  result.utime = outcome.utime;
  result.session_id = session_id;
  result.outcome = ResultOutcome(outcome.outcome);
  result.reason = outcome.reason;
  if (outcome.record) {
    result.validation_rms_before = outcome.record->rms_before;
    result.validation_rms_after = outcome.record->rms_after;
    result.iterations = outcome.record->iterations;
    result.runtime = outcome.record->runtime;
  } else {
    result.validation_rms_before = result.validation_rms_after = -1;
  }
  result.model_path = outcome.outcome == State::kAccepted ? outcome.model_path : "";
  result.change = outcome.after ? outcome.after->change : "";
  result.num_parameters = 0;
  if (outcome.before && outcome.after) AddParameters(*outcome.before, *outcome.after, result);
  return result;
}

}  // namespace selfcal::daemon
