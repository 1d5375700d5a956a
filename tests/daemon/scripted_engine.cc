#include "tests/daemon/scripted_engine.h"

#include <chrono>
#include <sstream>
#include <thread>

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
  result.model.tool.z += script_.shift;
  result.iterations = steps;
  result.runtime = script_.seconds;
  result.usable = script_.usable;
  result.message = script_.usable ? "converged" : "scripted: not usable";
  result.validation_rms_before = script_.rms_before;
  result.validation_rms_after =
      result.model.tool.z == job.current.tool.z ? script_.rms_before : script_.rms_after;
  result.predicted_error = script_.predicted_error;
  result.predicted_worst_error = 2 * script_.predicted_error;
  return result;
}

}  // namespace selfcal::daemon::testing
