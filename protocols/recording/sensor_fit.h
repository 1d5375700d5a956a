// The recording's sensor messages against the sensor file: the thresholds of Table I are a
// sensor's, and the file of another sensor calibrates with the wrong ones (the PhotoNeo file on a
// Kinect log, 1120 x 800 against 80 x 72 frames, was used silently). The engine never reads the
// file's resolution, intrinsics or view range (it unprojects with the frame's own intrinsics), so
// they are what tells the two apart (docs/formats.md, "Sensor file").
//
// A frame that is no binning of the file's resolution (the same integer factor in x and y, as
// `selfcal simulate` bins) is an error. The rest are warnings, said once per recording: a binned
// frame, intrinsics or rays that differ from the file's, points outside its view range. A
// SensorConfig without a resolution (built in code, not read from a file) is not checked.
#pragma once

#include <string>
#include <vector>

#include "core/calib/dataset.h"
#include "core/camera/pinhole_intrinsics.h"
#include "core/util/expected.h"
#include "protocols/model_file/sensor_config.h"

namespace selfcal::recording {

class SensorFit {
 public:
  explicit SensorFit(const SensorConfig& sensor) : sensor_(sensor) {}

  // A depth frame of `width` x `height` in scan `scan` (its name, "scan 3"); `intrinsics` are
  // the frame's own (null for an organized cloud, which has none).
  Status CheckFrame(int width, int height, const PinholeIntrinsics* intrinsics,
                    const std::string& scan);
  // A rotation of a rotating LiDAR.
  void CheckRays(std::size_t rays, double angle_first, double angle_increment,
                 const std::string& scan);
  // A line of a line scanner.
  void CheckLine(std::size_t points, const std::string& scan);
  // The valid points of all scans against the view range (z for cameras and line scanners, the
  // range along the ray for a LiDAR, as the simulator measures them).
  void CheckViewRange(const std::vector<calib::Dataset>& datasets);

  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  void CheckIntrinsics(const PinholeIntrinsics& frame, int binning, int width, int height,
                       const std::string& scan);

  const SensorConfig& sensor_;
  std::vector<std::string> warnings_;
  bool binning_said_ = false;
  bool intrinsics_said_ = false;
  bool rays_said_ = false;
};

}  // namespace selfcal::recording
