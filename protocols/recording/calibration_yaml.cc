// The `calibration:` section of a result model file. Every key carries its unit (or is a count,
// a name or a flag); numbers are rounded to what they mean: 1e-9 m and 1e-9 rad for geometry
// (a nanometre and a nanoradian, far below any sensor's resolution), 1e-3 s for times.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "protocols/recording/recording.h"

namespace selfcal::recording {
namespace {

constexpr int kGeometryDecimals = 9;
constexpr int kTimeDecimals = 3;

// `value` with `decimals` digits after the point, trailing zeros dropped, never "-0".
std::string Fixed(double value, int decimals) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  std::string out = text;
  if (out.find('.') != std::string::npos) {
    out.erase(out.find_last_not_of('0') + 1);
    if (out.back() == '.') out.pop_back();
  }
  return out == "-0" ? "0" : out;
}

std::string Geometry(double value) { return Fixed(value, kGeometryDecimals); }
std::string Seconds(double value) { return Fixed(value, kTimeDecimals); }

// "rad" for the angles of a parameter name (alpha, beta, gamma), "m" for its translations.
const char* ParameterUnit(const std::string& name) {
  const std::string axis = name.substr(name.rfind('.') + 1);
  if (axis == "compliance") return "rad_per_nm";  // joint elasticity (docs/engine.md, dev. 15)
  if (axis == "latency") return "s";              // sensor latency (docs/engine.md, dev. 16)
  // The sensor's measure (docs/engine.md, deviation 17): its scale is a ratio, its offset in m.
  if (axis.ends_with("_scale")) return "relative";
  if (axis.ends_with("_offset")) return "m";
  return axis == "x" || axis == "y" || axis == "z" ? "m" : "rad";
}

void EmitProvenance(YAML::Emitter& out, const Provenance& provenance) {
  out << YAML::Key << "software" << YAML::Value << provenance.software;
  out << YAML::Key << "command_line" << YAML::Value << YAML::DoubleQuoted
      << provenance.command_line;
  out << YAML::Key << "inputs" << YAML::Value << YAML::BeginSeq;
  for (const auto& input : provenance.inputs) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "role" << YAML::Value << input.role
        << YAML::Key << "path" << YAML::Value << input.path << YAML::Key << "sha256" << YAML::Value
        << input.sha256 << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

void EmitIterations(YAML::Emitter& out, const calib::CalibrationResult& result) {
  out << YAML::Key << "valid_matches_per_iteration" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& iteration : result.iterations) out << iteration.valid_matches;
  out << YAML::EndSeq;
  out << YAML::Key << "per_iteration" << YAML::Value << YAML::BeginSeq;
  for (const auto& iteration : result.iterations) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "rms_before_m" << YAML::Value << Geometry(iteration.rms_before_m);
    out << YAML::Key << "rms_after_m" << YAML::Value << Geometry(iteration.rms_after_m);
    out << YAML::Key << "delta_k" << YAML::Value << Geometry(iteration.delta);
    out << YAML::Key << "step" << YAML::Value << Geometry(iteration.step);
    out << YAML::Key << "lm_iterations" << YAML::Value << iteration.lm_iterations;
    out << YAML::Key << "time_s" << YAML::Value << Seconds(iteration.seconds);
    out << YAML::Key << "matching_time_s" << YAML::Value << Seconds(iteration.matching_seconds);
    if (iteration.noise_fraction > 0) {
      out << YAML::Key << "noise_fraction" << YAML::Value << Fixed(iteration.noise_fraction, 4);
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

// How far each validation scan moves when registered onto the fit scans
// (core/calib/held_out_registration.h).
void EmitHeldOut(YAML::Emitter& out, const calib::HeldOutRegistration& held_out) {
  out << YAML::Key << "held_out_registration" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "rms_position_m" << YAML::Value << Geometry(held_out.rms_position_m);
  out << YAML::Key << "worst_position_m" << YAML::Value << Geometry(held_out.worst_position_m);
  out << YAML::Key << "scans" << YAML::Value << YAML::BeginSeq;
  for (const calib::HeldOutOffset& scan : held_out.scans) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "scan" << YAML::Value << scan.scan_index;
    out << YAML::Key << "matches" << YAML::Value << scan.matches;
    out << YAML::Key << "position_m" << YAML::Value << Geometry(scan.position_m);
    out << YAML::Key << "angle_rad" << YAML::Value << Geometry(scan.angle_rad);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
}

void EmitValidation(YAML::Emitter& out, const calib::CalibrationResult& result) {
  out << YAML::Key << "validation" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "available" << YAML::Value << result.validation.available;
  out << YAML::Key << "matches_before" << YAML::Value << result.validation.matches_before;
  out << YAML::Key << "rms_before_m" << YAML::Value << Geometry(result.validation.rms_before_m);
  out << YAML::Key << "matches_after" << YAML::Value << result.validation.matches_after;
  out << YAML::Key << "rms_after_m" << YAML::Value << Geometry(result.validation.rms_after_m);
  EmitHeldOut(out, result.held_out);
  out << YAML::EndMap;
}

void EmitParameters(YAML::Emitter& out, const calib::CalibrationResult& result) {
  out << YAML::Key << "parameters" << YAML::Value << YAML::BeginSeq;
  for (const auto& parameter : result.parameters) {
    const std::string unit = ParameterUnit(parameter.name);
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << parameter.name;
    out << YAML::Key << "nominal_" + unit << YAML::Value << Geometry(parameter.nominal);
    out << YAML::Key << "calibrated_" + unit << YAML::Value << Geometry(parameter.calibrated);
    out << YAML::Key << "std_dev_" + unit << YAML::Value << Geometry(parameter.std_dev);
    out << YAML::Key << "naive_std_dev_" + unit << YAML::Value << Geometry(parameter.naive_std_dev);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "poorly_observable" << YAML::Value << YAML::BeginSeq;
  for (const auto& entry : result.poorly_observable) out << YAML::DoubleQuoted << entry;
  out << YAML::EndSeq;
  out << YAML::Key << "unobservable" << YAML::Value << YAML::BeginSeq;
  for (const auto& entry : result.unobservable) out << YAML::DoubleQuoted << entry;
  out << YAML::EndSeq;
}

void EmitPredictedPoseError(YAML::Emitter& out, const char* key,
                            const calib::PredictedPoseError& error) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "rms_position_m" << YAML::Value << Geometry(error.rms_position_m);
  out << YAML::Key << "max_position_m" << YAML::Value << Geometry(error.max_position_m);
  out << YAML::Key << "rms_orientation_rad" << YAML::Value << Geometry(error.rms_orientation_rad);
  out << YAML::Key << "max_orientation_rad" << YAML::Value << Geometry(error.max_orientation_rad);
  out << YAML::EndMap;
}

// The map over the joint space: per joint its range, and per bin the samples and the RMS.
void EmitErrorMap(YAML::Emitter& out, const calib::PredictedErrorMap& map) {
  out << YAML::Key << "map" << YAML::Value << YAML::BeginSeq;
  for (const auto& joint : map.joints) {
    const std::string unit = joint.prismatic ? "_m" : "_rad";
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "joint" << YAML::Value << joint.joint;
    out << YAML::Key << "lower" + unit << YAML::Value << Geometry(joint.lower);
    out << YAML::Key << "upper" + unit << YAML::Value << Geometry(joint.upper);
    out << YAML::Key << "samples" << YAML::Value << YAML::Flow << joint.samples;
    out << YAML::Key << "sensor_rms_position_m" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (double value : joint.sensor_rms_position_m) out << Geometry(value);
    out << YAML::EndSeq;
    out << YAML::Key << "flange_rms_position_m" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (double value : joint.flange_rms_position_m) out << Geometry(value);
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "worst_regions" << YAML::Value << YAML::BeginSeq;
  for (const auto& region : map.worst) {
    const auto& joint = map.joints[region.joint];
    const std::string unit = joint.prismatic ? "_m" : "_rad";
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "joint" << YAML::Value << joint.joint;
    out << YAML::Key << "lower" + unit << YAML::Value << Geometry(region.lower);
    out << YAML::Key << "upper" + unit << YAML::Value << Geometry(region.upper);
    out << YAML::Key << "samples" << YAML::Value << joint.samples[region.bin];
    out << YAML::Key << "sensor_rms_position_m" << YAML::Value
        << Geometry(region.sensor_rms_position_m);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
}

void EmitPredicted(YAML::Emitter& out, const calib::CalibrationResult& result) {
  out << YAML::Key << "predicted_error" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "covariance" << YAML::Value
      << (result.jackknife_scans > 0 ? "jackknife" : "naive");
  out << YAML::Key << "jackknife_scans" << YAML::Value << result.jackknife_scans;
  out << YAML::Key << "samples" << YAML::Value << result.predicted.samples;
  out << YAML::Key << "seed" << YAML::Value << result.predicted.seed;
  EmitPredictedPoseError(out, "sensor", result.predicted.sensor);
  EmitPredictedPoseError(out, "flange", result.predicted.flange);
  // The part of it what the calibration holds accounts for (docs/engine.md, deviation 21).
  if (result.predicted_held.samples > 0)
    EmitPredictedPoseError(out, "sensor_from_held", result.predicted_held.sensor);
  out << YAML::Key << "bins" << YAML::Value << calib::kErrorMapBins;
  EmitErrorMap(out, result.predicted.map);
  out << YAML::EndMap;
}

// One number of a finding in the unit its text uses ("deg" or "mm"), as `name_unit`, and its
// standard deviation as `name_std_dev_unit` (null without a covariance).
void EmitFindingNumber(YAML::Emitter& out, const std::string& name, bool degrees, double value,
                       double std_dev) {
  const std::string unit = degrees ? "_deg" : "_mm";
  // The geometry's rounding (1e-9 rad or m) in that unit.
  const auto shown = [&](double si) {
    return degrees ? Fixed(si * 180 / M_PI, kGeometryDecimals - 1)
                   : Fixed(si * 1e3, kGeometryDecimals - 3);
  };
  out << YAML::Key << name + unit << YAML::Value << shown(value);
  out << YAML::Key << name + "_std_dev" + unit << YAML::Value;
  if (std_dev > 0) {
    out << shown(std_dev);
  } else {
    out << YAML::Null;
  }
}

void EmitFinding(YAML::Emitter& out, const ChangeFinding& finding,
                 const std::vector<JointSpec>& joints) {
  out << YAML::Flow << YAML::BeginMap << YAML::Key << "kind" << YAML::Value
      << ChangeKindName(finding.kind);
  switch (finding.kind) {
    case ChangeKind::kJointZero: {
      out << YAML::Key << "joint" << YAML::Value << finding.joint;
      const auto joint = std::find_if(joints.begin(), joints.end(),
                                      [&](const JointSpec& j) { return j.name == finding.joint; });
      const bool prismatic = joint != joints.end() && joint->type == JointType::kPrismatic;
      EmitFindingNumber(out, "moved", !prismatic, finding.value, finding.std_dev);
      break;
    }
    case ChangeKind::kSensorMount:
      EmitFindingNumber(out, "shift", false, finding.value, finding.std_dev);
      EmitFindingNumber(out, "turn", true, finding.turn_rad, finding.turn_std_dev_rad);
      break;
    case ChangeKind::kLinkGeometry:
      EmitFindingNumber(out, "unexplained_rms", false, finding.value, finding.std_dev);
      break;
  }
  out << YAML::Key << "text" << YAML::Value << YAML::DoubleQuoted << finding.text << YAML::EndMap;
}

// What changed against the starting model, in words and in numbers (core/model/model_change.h).
void EmitChange(YAML::Emitter& out, const ModelChange& change,
                const std::vector<JointSpec>& joints) {
  out << YAML::Key << "change" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "summary" << YAML::Value << YAML::DoubleQuoted << change.Summary();
  out << YAML::Key << "findings" << YAML::Value << YAML::BeginSeq;
  for (const ChangeFinding& finding : change.findings) EmitFinding(out, finding, joints);
  out << YAML::EndSeq;
  out << YAML::Key << "joint_offsets" << YAML::Value << YAML::Flow << YAML::BeginMap;
  for (std::size_t j = 0; j < joints.size() && j < change.fit.offsets.size(); ++j) {
    const bool prismatic = joints[j].type == JointType::kPrismatic;
    out << YAML::Key << joints[j].name + (prismatic ? "_m" : "_rad") << YAML::Value
        << Geometry(change.fit.offsets[j]);
  }
  out << YAML::EndMap;
  out << YAML::Key << "mount_shift_m" << YAML::Value << Geometry(change.fit.mount_shift_m);
  out << YAML::Key << "mount_turn_rad" << YAML::Value << Geometry(change.fit.mount_turn_rad);
  out << YAML::Key << "unexplained_rms_position_m" << YAML::Value
      << Geometry(change.fit.rms_position_m);
  out << YAML::Key << "keeping_the_start_model" << YAML::Value << YAML::BeginMap;
  EmitPredictedPoseError(out, "sensor", change.kept_installed.sensor);
  EmitPredictedPoseError(out, "flange", change.kept_installed.flange);
  out << YAML::EndMap << YAML::EndMap;
}

}  // namespace

double AsWritten(double value) {
  if (!std::isfinite(value)) return value;
  return std::strtod(Geometry(value).c_str(), nullptr);
}

std::string FormatCalibrationYaml(const calib::CalibrationResult& result,
                                  const Provenance* provenance) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  if (provenance) EmitProvenance(out, *provenance);
  out << YAML::Key << "search" << YAML::Value << calib::SearchName(result.search);
  out << YAML::Key << "solver" << YAML::Value << calib::SolverName(result.solver);
  out << YAML::Key << "step_measure" << YAML::Value
      << calib::kStepMeasureNames.Name(result.step_measure);
  out << YAML::Key << "accelerated" << YAML::Value << result.accelerated;
  out << YAML::Key << "acceleration_dropped" << YAML::Value << result.acceleration_dropped;
  out << YAML::Key << "threads" << YAML::Value << result.threads;
  out << YAML::Key << "termination" << YAML::Value << calib::TerminationName(result.termination);
  out << YAML::Key << "message" << YAML::Value << YAML::DoubleQuoted << result.message;
  out << YAML::Key << "converged" << YAML::Value << result.converged;
  out << YAML::Key << "usable" << YAML::Value << result.usable;
  out << YAML::Key << "iterations" << YAML::Value << result.iterations.size();
  out << YAML::Key << "runtime_s" << YAML::Value << Seconds(result.runtime_s);
  out << YAML::Key << "scale_m" << YAML::Value << Geometry(result.scale_m);
  out << YAML::Key << "fit_scans" << YAML::Value << result.fit_scans;
  out << YAML::Key << "validation_scans" << YAML::Value << result.validation_scans;
  out << YAML::Key << "points" << YAML::Value << result.points;
  EmitIterations(out, result);
  EmitValidation(out, result);
  EmitParameters(out, result);
  EmitPredicted(out, result);
  if (result.change_known) EmitChange(out, result.change, result.model.joints);
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace selfcal::recording
