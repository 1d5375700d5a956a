// The report's data block (JSON): what the page's scripts draw. Internal to protocols/report.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "protocols/report/report.h"

namespace selfcal::report {

// The members of the JSON object, each "key": value, joined by commas.
std::string IterationsJson(const YAML::Node& calibration);
std::string ParametersJson(const YAML::Node& calibration);
std::string ErrorMapJson(const YAML::Node& calibration);  // `predicted_error: map:`
std::string HistogramJson(const std::vector<float>& before_m, const std::vector<float>& after_m,
                          double d_max_m);
std::string CoverageJson(const std::vector<calib::Dataset>& datasets, const RobotModel& model);
std::string CloudsJson(const std::vector<calib::Dataset>& datasets, const RobotModel& before,
                       const RobotModel& after, std::size_t max_points);

}  // namespace selfcal::report
