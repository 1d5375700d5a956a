#include "tests/daemon/scripted_engine.h"

#include <chrono>
#include <cmath>
#include <sstream>
#include <thread>

#include "core/model/joint_offsets.h"

namespace selfcal::daemon::testing {

Expected<Script> ParseScript(const std::string& text) {
  Script script;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    const auto equal = item.find('=');
    if (equal == std::string::npos) return Error{"script item '" + item + "' has no '='"};
    const std::string key = item.substr(0, equal);
    const double value = std::stod(item.substr(equal + 1));
    if (key == "seconds")
      script.seconds = value;
    else if (key == "rms_before")
      script.rms_before = value;
    else if (key == "rms_after")
      script.rms_after = value;
    else if (key == "shift")
      script.shift = value;
    else if (key == "fail")
      script.fail = value != 0;
    else if (key == "usable")
      script.usable = value != 0;
    else if (key == "predicted_error")
      script.predicted_error = value;
    else if (key == "offset_joint")
      script.offset_joint = static_cast<int>(value);
    else if (key == "offset_deg")
      script.offset_deg = value;
    else if (key == "nudge")
      script.nudge = value;
    else
      return Error{"unknown script key '" + key + "'"};
  }
  return script;
}

bool ScriptedEngine::Wait(double seconds, const std::atomic<bool>& stop) const {
  const std::int64_t end = clock_->Monotonic() + static_cast<std::int64_t>(seconds * 1e6);
  while (clock_->Monotonic() < end) {
    if (stop) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return !stop;
}

Expected<CalibratedModel> ScriptedEngine::Calibrate(const CalibrationJob& job,
                                                    const ProgressCallback& progress,
                                                    const std::atomic<bool>& stop) {
  const int steps = 20;
  for (int i = 0; i < steps; ++i) {
    if (stop) return Error{"stopped"};
    progress(Phase::kCalibrating, static_cast<double>(i) / steps,
             "iteration " + std::to_string(i + 1));
    if (!Wait(script_.seconds / steps, stop)) return Error{"stopped"};
  }
  if (script_.fail) return Error{"scripted failure"};
  progress(Phase::kValidating, 0.5, "validation");
  CalibratedModel result;
  result.model = job.current;
  if (script_.offset_joint > 0) {
    std::vector<double> offsets(job.current.JointCount(), 0.0);
    offsets.at(static_cast<std::size_t>(script_.offset_joint - 1)) =
        script_.offset_deg * M_PI / 180;
    auto turned = WithJointOffsets(job.current, offsets);
    if (!turned) return turned.error();
    result.model = std::move(*turned);
  }
  result.model.tool.z += script_.shift;
  // Only what the job frees moves, the nudge on top.
  std::vector<double> k = ToParameterVector(result.model);
  const std::vector<double> k_current = ToParameterVector(job.current);
  for (std::size_t i = 0; i < k.size(); ++i) {
    k[i] = job.current.mask[i] ? k[i] + script_.nudge : k_current[i];
  }
  FromParameterVector(k, result.model);
  result.iterations = steps;
  result.runtime = script_.seconds;
  result.usable = script_.usable;
  result.message = script_.usable ? "converged" : "scripted: not usable";
  result.validation_rms_before = script_.rms_before;
  result.validation_rms_after =
      ToParameterVector(result.model) == k_current ? script_.rms_before : script_.rms_after;
  result.predicted_error = script_.predicted_error;
  result.predicted_worst_error = 2 * script_.predicted_error;
  return result;
}

}  // namespace selfcal::daemon::testing
