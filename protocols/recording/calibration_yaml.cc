// The `calibration:` section of a result model file.
#include <yaml-cpp/yaml.h>

#include "protocols/recording/recording.h"

namespace selfcal::recording {

std::string FormatCalibrationYaml(const calib::CalibrationResult& result) {
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  out << YAML::BeginMap;
  out << YAML::Key << "search" << YAML::Value << calib::SearchName(result.search);
  out << YAML::Key << "solver" << YAML::Value << calib::SolverName(result.solver);
  out << YAML::Key << "threads" << YAML::Value << result.threads;
  out << YAML::Key << "termination" << YAML::Value << calib::TerminationName(result.termination);
  out << YAML::Key << "message" << YAML::Value << YAML::DoubleQuoted << result.message;
  out << YAML::Key << "converged" << YAML::Value << result.converged;
  out << YAML::Key << "usable" << YAML::Value << result.usable;
  out << YAML::Key << "iterations" << YAML::Value << result.iterations.size();
  out << YAML::Key << "runtime_s" << YAML::Value << result.runtime_s;
  out << YAML::Key << "scale_m" << YAML::Value << result.scale_m;
  out << YAML::Key << "fit_scans" << YAML::Value << result.fit_scans;
  out << YAML::Key << "validation_scans" << YAML::Value << result.validation_scans;
  out << YAML::Key << "points" << YAML::Value << result.points;
  out << YAML::Key << "valid_matches_per_iteration" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& iteration : result.iterations) out << iteration.valid_matches;
  out << YAML::EndSeq;
  out << YAML::Key << "rms_per_iteration_m" << YAML::Value << YAML::BeginSeq;
  for (const auto& iteration : result.iterations) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "before" << YAML::Value
        << iteration.rms_before_m << YAML::Key << "after" << YAML::Value << iteration.rms_after_m
        << YAML::Key << "delta" << YAML::Value << iteration.delta << YAML::Key << "lm_iterations"
        << YAML::Value << iteration.lm_iterations << YAML::Key << "seconds" << YAML::Value
        << iteration.seconds << YAML::Key << "matching_seconds" << YAML::Value
        << iteration.matching_seconds << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "validation" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "available" << YAML::Value << result.validation.available;
  out << YAML::Key << "matches_before" << YAML::Value << result.validation.matches_before;
  out << YAML::Key << "rms_before_m" << YAML::Value << result.validation.rms_before_m;
  out << YAML::Key << "matches_after" << YAML::Value << result.validation.matches_after;
  out << YAML::Key << "rms_after_m" << YAML::Value << result.validation.rms_after_m;
  out << YAML::EndMap;
  out << YAML::Key << "parameters" << YAML::Value << YAML::BeginSeq;
  for (const auto& parameter : result.parameters) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << parameter.name
        << YAML::Key << "nominal" << YAML::Value << parameter.nominal << YAML::Key << "calibrated"
        << YAML::Value << parameter.calibrated << YAML::Key << "std_dev" << YAML::Value
        << parameter.std_dev << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "poorly_observable" << YAML::Value << YAML::BeginSeq;
  for (const auto& entry : result.poorly_observable) out << YAML::DoubleQuoted << entry;
  out << YAML::EndSeq;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace selfcal::recording
