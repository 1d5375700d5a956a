#include "protocols/recording/sensor_fit.h"

#include <cmath>
#include <cstdio>

namespace selfcal::recording {

namespace {

// Intrinsics further apart than this (focal lengths relative, centres as a fraction of the
// frame) are another lens: a device's factory calibration is within a few percent of its
// nominal field of view.
constexpr double kIntrinsicsTolerance = 0.10;
// Points beyond the view range widened by this fraction are outside it; more than
// kOutsideFraction of them is another sensor (or a scene the sensor cannot see).
constexpr double kViewRangeMargin = 0.05;
constexpr double kOutsideFraction = 0.01;

constexpr const char* kAnotherSensor = ": the sensor file of another sensor?";

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

std::string Intrinsics(const PinholeIntrinsics& k) {
  return "fx " + Number(k.fx) + ", fy " + Number(k.fy) + ", cx " + Number(k.cx) + ", cy " +
         Number(k.cy);
}

std::string Size(int width, int height) {
  return std::to_string(width) + " x " + std::to_string(height);
}

}  // namespace

Status SensorFit::CheckFrame(int width, int height, const PinholeIntrinsics* intrinsics,
                             const std::string& scan) {
  if (sensor_.resolution_x <= 0 || sensor_.resolution_y <= 0 || width <= 0 || height <= 0) {
    return OkStatus();
  }
  const int binning = static_cast<int>(
      std::lround(static_cast<double>(sensor_.resolution_x) / static_cast<double>(width)));
  if (binning < 1 || sensor_.resolution_x / binning != width ||
      sensor_.resolution_y / binning != height) {
    return Error{scan + ": a " + Size(width, height) + " frame, but sensor file " + sensor_.name +
                 " is for " + Size(sensor_.resolution_x, sensor_.resolution_y) +
                 " frames (nor a binning of them)" + kAnotherSensor};
  }
  if (binning > 1 && !binning_said_) {
    binning_said_ = true;
    warnings_.push_back("sensor file " + sensor_.name + " is for " +
                        Size(sensor_.resolution_x, sensor_.resolution_y) +
                        " frames; the recording's are " + Size(width, height) + " (binned " +
                        Size(binning, binning) + "): its thresholds are used as they are");
  }
  if (intrinsics != nullptr) CheckIntrinsics(*intrinsics, binning, width, height, scan);
  return OkStatus();
}

void SensorFit::CheckIntrinsics(const PinholeIntrinsics& frame, int binning, int width, int height,
                                const std::string& scan) {
  if (intrinsics_said_ || !sensor_.camera.intrinsics.IsValid()) return;
  const PinholeIntrinsics file = sensor_.camera.intrinsics.Binned(binning);
  const auto relative = [](double a, double b) { return std::abs(a - b) / std::abs(b); };
  const bool differ = !(relative(frame.fx, file.fx) <= kIntrinsicsTolerance) ||
                      !(relative(frame.fy, file.fy) <= kIntrinsicsTolerance) ||
                      !(std::abs(frame.cx - file.cx) <= kIntrinsicsTolerance * width) ||
                      !(std::abs(frame.cy - file.cy) <= kIntrinsicsTolerance * height);
  if (!differ) return;
  intrinsics_said_ = true;
  warnings_.push_back(scan + ": the frame's intrinsics " + Intrinsics(frame) +
                      " differ from sensor file " + sensor_.name + "'s " + Intrinsics(file) +
                      (binning > 1 ? " (binned " + Size(binning, binning) + ")" : "") +
                      " by more than " + Number(kIntrinsicsTolerance * 100) + " %" +
                      kAnotherSensor);
}

void SensorFit::CheckRays(std::size_t rays, double angle_first, double angle_increment,
                          const std::string& scan) {
  const SensorConfig::RotatingLidar& lidar = sensor_.lidar;
  if (rays_said_ || lidar.steps <= 0) return;
  const bool differ = rays != static_cast<std::size_t>(lidar.steps) ||
                      !(std::abs(angle_first - lidar.angle_first) <= 1e-6) ||
                      !(std::abs(angle_increment - lidar.angle_increment) <=
                        1e-6 * std::abs(lidar.angle_increment));
  if (!differ) return;
  rays_said_ = true;
  warnings_.push_back(
      scan + ": range scans of " + std::to_string(rays) + " rays from " + Number(angle_first) +
      " rad in steps of " + Number(angle_increment) + " rad, but sensor file " + sensor_.name +
      " has " + std::to_string(lidar.steps) + " rays from " + Number(lidar.angle_first) +
      " rad in steps of " + Number(lidar.angle_increment) + " rad" + kAnotherSensor);
}

void SensorFit::CheckLine(std::size_t points, const std::string& scan) {
  if (rays_said_ || sensor_.line.points <= 0) return;
  if (points == static_cast<std::size_t>(sensor_.line.points)) return;
  rays_said_ = true;
  warnings_.push_back(scan + ": line profiles of " + std::to_string(points) +
                      " points, but sensor file " + sensor_.name + " has " +
                      std::to_string(sensor_.line.points) + " points per line" + kAnotherSensor);
}

void SensorFit::CheckViewRange(const std::vector<calib::Dataset>& datasets) {
  const double closest = sensor_.range_closest, farthest = sensor_.range_farthest;
  if (!(farthest > closest) || !(closest >= 0)) return;
  const bool along_ray = sensor_.layout == SensorLayout::kRotatingLidar;
  std::size_t valid = 0, outside = 0;
  for (const calib::Dataset& dataset : datasets) {
    for (std::size_t i = 0; i < dataset.PointCount(); ++i) {
      if (!std::isfinite(dataset.x[i]) || !std::isfinite(dataset.z[i])) continue;
      const double range = along_ray ? std::hypot(dataset.x[i], dataset.y[i], dataset.z[i])
                                     : static_cast<double>(dataset.z[i]);
      ++valid;
      if (range < closest * (1 - kViewRangeMargin) || range > farthest * (1 + kViewRangeMargin))
        ++outside;
    }
  }
  if (valid == 0 || static_cast<double>(outside) <= kOutsideFraction * static_cast<double>(valid))
    return;
  char percent[32];
  std::snprintf(percent, sizeof(percent), "%.1f %%",
                100.0 * static_cast<double>(outside) / static_cast<double>(valid));
  warnings_.push_back(std::string(percent) + " of the recording's " + std::to_string(valid) +
                      " valid points lie outside sensor file " + sensor_.name + "'s view range " +
                      Number(closest) + " .. " + Number(farthest) + " m" + kAnotherSensor);
}

}  // namespace selfcal::recording
