// CalibrationOptions::IsValid: the ranges of the engine's options, in one place: Calibrate(), the
// CLI and the daemon ask it. The Table I parameters' limits are core/calib/parameter_limits.h's,
// which the sensor-file reader checks too.
#include <cmath>
#include <sstream>

#include "core/calib/calibrate.h"
#include "core/calib/intrinsics_choice.h"
#include "core/calib/parameter_limits.h"

namespace selfcal::calib {

namespace {

constexpr int kMaxAcceleration = 20;

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

// Invalid() unless `limit` allows `value`.
template <typename T>
bool Within(std::string* error, const char* name, T value, const char* unit,
            const ParameterLimit& limit) {
  if (limit.allows(static_cast<double>(value))) return true;
  return Invalid(error, name, value, unit, limit.requirement);
}

}  // namespace

bool CalibrationOptions::IsValid(std::string* error) const {
  if (!Within(error, "filter_n", filter_n, "", kFilterRadiusLimit) ||
      !Within(error, "filter_m", filter_m, "", kFilterRadiusLimit) ||
      !Within(error, "g_min", g_min, "", kGMinLimit) ||
      !Within(error, "d_max", d_max, " m", kDMaxLimit) ||
      !Within(error, "f_min", f_min, "", kFMinLimit) ||
      !Within(error, "epsilon", epsilon, "", kEpsilonLimit) ||
      !Within(error, "i_max", i_max, "", kIMaxLimit) ||
      !Within(error, "query_stride", query_stride, "", kQueryStrideLimit) ||
      !Within(error, "coarse_stride", coarse_stride, "", kQueryStrideLimit) ||
      !Within(error, "flying_pixel_angle", flying_pixel_angle_deg, " deg",
              kFlyingPixelAngleLimit) ||
      !Within(error, "link_margin", link_margin_m, " m", kLinkMarginLimit) ||
      !Within(error, "intrinsic_scale_sd", intrinsic_scale_sd, "", kIntrinsicSdLimit) ||
      !Within(error, "intrinsic_offset_sd", intrinsic_offset_sd_m, " m", kIntrinsicSdLimit) ||
      !Within(error, "intrinsic_focal_sd", intrinsic_focal_sd, "", kIntrinsicSdLimit)) {
    return false;
  }
  if (!(knot_max_joint_step > 0) || !std::isfinite(knot_max_joint_step))
    return Invalid(error, "knot_max_joint_step", knot_max_joint_step, "", "positive and finite");
  if (threads < 0) return Invalid(error, "threads", threads, "", "at least 0 (0 = all cores)");
  if (lm_max_iterations < 1)
    return Invalid(error, "lm_max_iterations", lm_max_iterations, "", "at least 1");
  if (search != SearchStrategy::kFast && search != SearchStrategy::kReference)
    return Invalid(error, "search", static_cast<int>(search), "", "fast or reference");
  if (solver != SolverKind::kFast && solver != SolverKind::kReference)
    return Invalid(error, "solver", static_cast<int>(solver), "", "fast or reference");
  if (cost != CostKind::kPaper && cost != CostKind::kTarget && cost != CostKind::kSymmetric)
    return Invalid(error, "cost", static_cast<int>(cost), "", "paper, target or symmetric");
  if (normals != NormalKind::kNeighbours && normals != NormalKind::kFit)
    return Invalid(error, "normals", static_cast<int>(normals), "", "neighbours or fit");
  if (step_measure != StepMeasure::kSensor && step_measure != StepMeasure::kParameters)
    return Invalid(error, "step_measure", static_cast<int>(step_measure), "",
                   "sensor or parameters");
  if (acceleration < 0 || acceleration > kMaxAcceleration)
    return Invalid(error, "acceleration", acceleration, "", "in [0, 20] (0 = off)");
  if (loss != LossKind::kSquared && loss != LossKind::kCauchy)
    return Invalid(error, "loss", static_cast<int>(loss), "", "squared or cauchy");
  if (!(loss_width > 0) || !std::isfinite(loss_width))
    return Invalid(error, "loss_width", loss_width, "", "positive and finite");
  if (elasticity && solver != SolverKind::kFast) {
    if (error != nullptr)
      *error = "elasticity needs solver fast (the reference solver has no compliance parameters)";
    return false;
  }
  if (estimate_latency && solver != SolverKind::kFast) {
    if (error != nullptr)
      *error = "estimate_latency needs solver fast (the reference solver has no latency parameter)";
    return false;
  }
  if (ray_noise_correction && solver != SolverKind::kFast) {
    if (error != nullptr)
      *error =
          "ray_noise_correction needs solver fast (the reference solver keeps the paper's cost)";
    return false;
  }
  if (AnyIntrinsic() && solver != SolverKind::kFast) {
    if (error != nullptr)
      *error = "intrinsics need solver fast (the reference solver has no intrinsic parameter)";
    return false;
  }
  return true;
}

std::string CalibrationOptions::ChooseIntrinsics(const std::string& choice) {
  return ParseIntrinsicsChoice(choice, &intrinsics);
}

std::string CalibrationOptions::IntrinsicsName() const {
  if (intrinsics.automatic) return "auto";
  std::string list;
  for (auto [chosen, name] :
       {std::pair{intrinsics.scale, "scale"}, std::pair{intrinsics.offset, "offset"},
        std::pair{intrinsics.focal, "focal"}}) {
    if (!chosen) continue;
    if (!list.empty()) list += '+';
    list += name;
  }
  return list.empty() ? "none" : list;
}

}  // namespace selfcal::calib
