// Sensor files (config/sensors/*.yaml): the paper's Table I per sensor, plus the geometry the
// simulator and the dataset assembly need. SI units unless a key says otherwise.
#pragma once

#include <optional>
#include <string>

#include "core/camera/pinhole_intrinsics.h"
#include "core/model/sensor_layout.h"
#include "core/util/enum_names.h"
#include "core/util/expected.h"

namespace selfcal {

// The sensor files' spelling of each layout.
inline constexpr EnumNames<SensorLayout, 3> kSensorLayoutNames{{
    {SensorLayout::kRotatingLidar, "rotating_lidar"},
    {SensorLayout::kLineScanner, "line_scanner"},
    {SensorLayout::kDepthCamera, "depth_camera"},
}};

struct SensorConfig {
  std::string name;
  SensorLayout layout = SensorLayout::kDepthCamera;

  // Table I: resolution, view range [m], noise (sigma = sigma_abs + sigma_rel * range).
  int resolution_x = 0;
  int resolution_y = 0;
  double range_closest = 0;   // m
  double range_farthest = 0;  // m
  double sigma_abs = 0;       // m
  double sigma_rel = 0;       // fraction of the range

  // Table I: edge/noise filter window (n x m) and threshold, match validation, stop criteria.
  int filter_n = 0;
  int filter_m = 0;
  double g_min = 0;
  double flying_pixel_angle_deg = 0;  // flying pixels removed before matching (0 = kept)
  double d_max = 0;                   // m
  double f_min = 0;                   // cosine of the angle between normals
  int query_stride = 1;   // match from every s-th grid row and column of a scan (1 = every point)
  int coarse_stride = 1;  // coarse to fine: the ICP loop's first stride (1 = off, the paper's)
  // Matches to the border of the other scan's coverage: "off", "exact" (deviation 10), "surface"
  // (deviation 12); empty = the layout's (exact for line scanners, off otherwise).
  std::string border_rule;
  double epsilon = 0;  // on |delta k| of the normalized parameters
  int i_max = 0;
  // kg, the sensor with its mount: its gravity load at the tool point for `selfcal calibrate
  // --elasticity` (docs/engine.md, deviation 15); 0 = not given.
  double mass = 0;
  // The sensor's latency against the joint states [s]: where the engine starts from, and whether
  // it estimates it (docs/engine.md, deviation 16); unset = the layout's (sweeping sensors do).
  double latency_s = 0;
  std::optional<bool> estimate_latency;
  // How far its intrinsics may be off (1 sigma: the measure's scale and the focal length's,
  // relative; the measure's offset in m): what the engine's covariance adds where it holds them
  // (docs/engine.md, deviation 21). 0 = exact.
  struct IntrinsicsUncertainty {
    double scale = 0, offset_m = 0, focal = 0;
  } intrinsics_uncertainty;
  // Which intrinsics the engine calibrates by default (docs/engine.md, deviation 17): "none",
  // "auto" or a '+'-list of scale, offset and focal; empty = the layout's (LiDARs: offset).
  std::string calibrate_intrinsics;

  // Geometry, by layout.
  struct RotatingLidar {
    int steps = 0;               // rays per rotation within the scan window
    double angle_first = 0;      // rad
    double angle_increment = 0;  // rad
    double rotation_rate_hz = 0;
    int steps_per_rotation = 0;  // steps of a full 360 degree rotation (sets the time per ray)
  } lidar;
  struct LineScanner {
    int points = 0;        // points per line
    double fan_angle = 0;  // rad, full opening angle of the laser fan
    double line_rate_hz = 0;
  } line;
  struct DepthCamera {
    PinholeIntrinsics intrinsics;
    double frame_rate_hz = 0;
  } camera;
};

Expected<SensorConfig> ReadSensorConfig(const std::string& path);
Expected<SensorConfig> ParseSensorConfig(const std::string& text, const std::string& name);

}  // namespace selfcal
