// CalibrationOptions::IsValid: the ranges of the engine's options, in one place: Calibrate(), the
// CLI and the daemon ask it. The sensor-file reader (protocols/model_file, which does not link the
// engine) still rejects a bad Table I value itself, to name the YAML key it came from.
#include <cmath>
#include <sstream>

#include "core/calib/calibrate.h"

namespace selfcal::calib {

namespace {

// Sets *error to "name = value unit, must be requirement" and returns false.
template <typename T>
bool Invalid(std::string* error, const char* name, T value, const char* unit,
             const char* requirement) {
  if (error != nullptr) {
    std::ostringstream out;
    out << name << " = " << value << unit << ", must be " << requirement;
    *error = out.str();
  }
  return false;
}

bool InRange(double value, double low, double high) { return value >= low && value <= high; }

}  // namespace

bool CalibrationOptions::IsValid(std::string* error) const {
  if (filter_n < 0) return Invalid(error, "filter_n", filter_n, "", "at least 0");
  if (filter_m < 0) return Invalid(error, "filter_m", filter_m, "", "at least 0");
  if (!InRange(g_min, 0.0, 1.0)) return Invalid(error, "g_min", g_min, "", "in [0, 1]");
  if (!(d_max > 0) || !std::isfinite(d_max))
    return Invalid(error, "d_max", d_max, " m", "positive and finite");
  if (!InRange(f_min, -1.0, 1.0)) return Invalid(error, "f_min", f_min, "", "in [-1, 1]");
  if (!(epsilon >= 0) || !std::isfinite(epsilon))
    return Invalid(error, "epsilon", epsilon, "", "finite and not negative");
  if (i_max < 1) return Invalid(error, "i_max", i_max, "", "at least 1");
  if (query_stride < 1) return Invalid(error, "query_stride", query_stride, "", "at least 1");
  if (threads < 0) return Invalid(error, "threads", threads, "", "at least 0 (0 = all cores)");
  if (lm_max_iterations < 1)
    return Invalid(error, "lm_max_iterations", lm_max_iterations, "", "at least 1");
  if (search != SearchStrategy::kFast && search != SearchStrategy::kReference)
    return Invalid(error, "search", static_cast<int>(search), "", "fast or reference");
  if (solver != SolverKind::kFast && solver != SolverKind::kReference)
    return Invalid(error, "solver", static_cast<int>(solver), "", "fast or reference");
  return true;
}

}  // namespace selfcal::calib
