#include "protocols/report/report_data.h"

#include <cmath>
#include <cstring>

#include "protocols/report/fused_cloud.h"
#include "protocols/report/json_text.h"

namespace selfcal::report {
namespace {

double Number(const YAML::Node& node) {
  if (!node || !node.IsScalar()) return std::nan("");
  try {
    return node.as<double>();
  } catch (const YAML::Exception&) {
    return std::nan("");
  }
}

// "rad", "m", ...: the suffix of a parameter entry's keys (calibration_yaml.cc writes one of them).
std::string UnitOf(const YAML::Node& parameter) {
  if (parameter["nominal_rad_per_nm"]) return "rad_per_nm";  // a joint's compliance
  if (parameter["nominal_s"]) return "s";                    // the sensor latency
  if (parameter["nominal_relative"]) return "relative";      // the sensor's measure scale
  return parameter["nominal_m"] ? "m" : "rad";
}

std::string FloatsBase64(const std::vector<float>& values) {
  return Base64(std::string_view(reinterpret_cast<const char*>(values.data()),
                                 values.size() * sizeof(float)));
}

}  // namespace

std::string IterationsJson(const YAML::Node& calibration) {
  std::string out = "\"iterations\": [";
  const YAML::Node iterations = calibration["per_iteration"];
  const YAML::Node matches = calibration["valid_matches_per_iteration"];
  for (std::size_t i = 0; iterations && i < iterations.size(); ++i) {
    const YAML::Node it = iterations[i];
    out += std::string(i ? ", " : "") +
           "{\"rms_before_m\": " + JsonNumber(Number(it["rms_before_m"])) +
           ", \"rms_after_m\": " + JsonNumber(Number(it["rms_after_m"])) +
           ", \"delta_k\": " + JsonNumber(Number(it["delta_k"])) +
           ", \"step\": " + JsonNumber(Number(it["step"])) +
           ", \"lm_iterations\": " + JsonNumber(Number(it["lm_iterations"])) +
           ", \"time_s\": " + JsonNumber(Number(it["time_s"])) + ", \"valid_matches\": " +
           JsonNumber(matches && i < matches.size() ? Number(matches[i]) : std::nan("")) + "}";
  }
  return out + "]";
}

std::string ParametersJson(const YAML::Node& calibration) {
  std::string out = "\"parameters\": [";
  const YAML::Node parameters = calibration["parameters"];
  for (std::size_t i = 0; parameters && i < parameters.size(); ++i) {
    const YAML::Node p = parameters[i];
    const std::string unit = UnitOf(p);
    out += std::string(i ? ", " : "") + "{\"name\": " + JsonString(p["name"].as<std::string>("")) +
           ", \"unit\": " + JsonString(unit) +
           ", \"nominal\": " + JsonNumber(Number(p["nominal_" + unit])) +
           ", \"calibrated\": " + JsonNumber(Number(p["calibrated_" + unit])) +
           ", \"std_dev\": " + JsonNumber(Number(p["std_dev_" + unit])) + "}";
  }
  return out + "]";
}

std::string ErrorMapJson(const YAML::Node& calibration) {
  std::string out = "\"error_map\": [";
  const YAML::Node predicted = calibration["predicted_error"];
  const YAML::Node map = predicted.IsMap() ? predicted["map"] : YAML::Node();
  const auto numbers = [](const YAML::Node& list) {
    std::string text;
    for (std::size_t i = 0; list.IsSequence() && i < list.size(); ++i) {
      text += i ? "," : "";
      text += JsonNumber(Number(list[i]));
    }
    return "[" + text + "]";
  };
  for (std::size_t j = 0; map.IsSequence() && j < map.size(); ++j) {
    const YAML::Node joint = map[j];
    if (!joint.IsMap()) continue;
    const std::string unit = joint["lower_m"] ? "_m" : "_rad";
    out += std::string(out.back() == '[' ? "" : ", ") +
           "{\"joint\": " + JsonString(joint["joint"].as<std::string>("")) +
           ", \"prismatic\": " + (unit == "_m" ? "true" : "false") +
           ", \"lower\": " + JsonNumber(Number(joint["lower" + unit])) +
           ", \"upper\": " + JsonNumber(Number(joint["upper" + unit])) +
           ", \"samples\": " + numbers(joint["samples"]) +
           ", \"sensor_rms_position_m\": " + numbers(joint["sensor_rms_position_m"]) + "}";
  }
  return out + "]";
}

std::string HistogramJson(const std::vector<float>& before_m, const std::vector<float>& after_m,
                          double d_max_m) {
  // Matches lie within d_max, so [-d_max, d_max] holds every residual.
  constexpr int kBins = 40;
  const auto counts = [&](const std::vector<float>& residuals) {
    std::vector<int> bins(kBins, 0);
    for (float r : residuals) {
      const int bin = static_cast<int>(std::floor((r + d_max_m) / (2 * d_max_m) * kBins));
      ++bins[static_cast<std::size_t>(std::clamp(bin, 0, kBins - 1))];
    }
    std::string text;
    for (int bin = 0; bin < kBins; ++bin) {
      text += bin ? "," : "";
      text += std::to_string(bins[static_cast<std::size_t>(bin)]);
    }
    return "[" + text + "]";
  };
  const auto rms = [](const std::vector<float>& residuals) {
    double sum = 0;
    for (float r : residuals) sum += static_cast<double>(r) * r;
    return residuals.empty() ? std::nan("")
                             : std::sqrt(sum / static_cast<double>(residuals.size()));
  };
  std::string centres;
  for (int bin = 0; bin < kBins; ++bin) {
    centres += bin ? "," : "";
    centres += JsonNumber((-d_max_m + (bin + 0.5) * 2 * d_max_m / kBins) * 1e3);
  }
  return "\"histogram\": {\"centres_mm\": [" + centres + "], \"before\": " + counts(before_m) +
         ", \"after\": " + counts(after_m) + ", \"rms_before_m\": " + JsonNumber(rms(before_m)) +
         ", \"rms_after_m\": " + JsonNumber(rms(after_m)) +
         ", \"matches_before\": " + std::to_string(before_m.size()) +
         ", \"matches_after\": " + std::to_string(after_m.size()) + "}";
}

std::string CoverageJson(const std::vector<calib::Dataset>& datasets, const RobotModel& model) {
  std::string out = "\"joints\": [";
  for (std::size_t j = 0; j < model.JointCount(); ++j) {
    const JointSpec& joint = model.joints[j];
    out += std::string(j ? ", " : "") + "{\"name\": " + JsonString(joint.name) +
           ", \"revolute\": " + (joint.type == JointType::kRevolute ? "true" : "false") +
           ", \"lower\": " + JsonNumber(joint.lower) + ", \"upper\": " + JsonNumber(joint.upper) +
           "}";
  }
  out += "], \"scans\": [";
  for (std::size_t d = 0; d < datasets.size(); ++d) {
    const calib::Dataset& dataset = datasets[d];
    // The middle pose: the whole scan for a camera, the middle of the sweep for the others.
    std::vector<double> buffer(dataset.joint_count);
    const double* joints = dataset.JointsOfPose(dataset.PoseCount() / 2, buffer.data());
    out += std::string(d ? ", " : "") + "{\"scan\": " + std::to_string(dataset.scan_index) +
           ", \"validation\": " + (dataset.validation ? "true" : "false") + ", \"joints\": [";
    for (std::size_t j = 0; j < dataset.joint_count; ++j) {
      out += j ? "," : "";
      out += JsonNumber(joints[j]);
    }
    out += "]}";
  }
  return out + "]";
}

std::string CloudsJson(const std::vector<calib::Dataset>& datasets, const RobotModel& before,
                       const RobotModel& after, std::size_t max_points) {
  const auto old_points = FuseScans(datasets, before, ScanSelection::kValidation, max_points);
  const auto new_points = FuseScans(datasets, after, ScanSelection::kValidation, max_points);
  // Centred on the new cloud: float positions near the origin, and the cameras aim there.
  double centre[3] = {0, 0, 0};
  for (const FusedPoint& p : new_points) {
    centre[0] += p.x;
    centre[1] += p.y;
    centre[2] += p.z;
  }
  for (double& c : centre) c /= static_cast<double>(std::max<std::size_t>(new_points.size(), 1));
  double radius = 0;
  const auto cloud = [&](const std::vector<FusedPoint>& points) {
    std::vector<float> positions;
    std::string colours;
    for (const FusedPoint& p : points) {
      const double offset[3] = {p.x - centre[0], p.y - centre[1], p.z - centre[2]};
      radius = std::max(
          radius, std::sqrt(offset[0] * offset[0] + offset[1] * offset[1] + offset[2] * offset[2]));
      for (double o : offset) positions.push_back(static_cast<float>(o));
      const Rgb colour = ScanColour(p.scan);
      colours += {static_cast<char>(colour.red), static_cast<char>(colour.green),
                  static_cast<char>(colour.blue)};
    }
    return "{\"count\": " + std::to_string(points.size()) + ", \"positions\": \"" +
           FloatsBase64(positions) + "\", \"colours\": \"" + Base64(colours) + "\"}";
  };
  const std::string old_cloud = cloud(old_points), new_cloud = cloud(new_points);
  return "\"clouds\": {\"centre_m\": [" + JsonNumber(centre[0]) + "," + JsonNumber(centre[1]) +
         "," + JsonNumber(centre[2]) + "], \"radius_m\": " + JsonNumber(radius) +
         ", \"before\": " + old_cloud + ", \"after\": " + new_cloud + "}";
}

}  // namespace selfcal::report
