// config/daemon.yaml: everything selfcald needs to know, read strictly (unknown keys are errors).
// Relative paths are resolved against the folder of the configuration file.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "core/util/expected.h"
#include "protocols/lcm/channels.h"

namespace selfcal::program {
class Program;
}

namespace selfcal::daemon {

struct ChannelConfig {
  std::string joint_state = channels::kJointState;
  std::string sensor = channels::kRangeScan;  // the one sensor channel the daemon records
  std::string scan_marker = channels::kScanMarker;
  std::string calibration_request = channels::kCalibrationRequest;
  std::string calibration_status = channels::kCalibrationStatus;
  std::string calibration_result = channels::kCalibrationResult;
  // The session's motion as selfcal.joint_trajectory_t, executed by the arm's driver.
  std::string joint_trajectory = channels::kJointTrajectory;
  // The driver's selfcal.robot_driver_status_t: its refusals and stops fail the session.
  std::string robot_status = channels::kRobotStatus;
};

struct CheckConfig {
  double joint_state_max_age = 0.1;  // s: older joint states are stale
  double sensor_max_age = 1.0;       // s: no sensor message for longer is a dropout
  double max_deviation = 0.05;       // rad (m): measured vs planned position during motion
  double max_lag = 0.1;              // s: how far the arm may trail its plan
  double limit_margin = 0.01;        // rad (m): waypoints must stay this far inside the limits
};

struct MotionConfig {
  double speed_fraction = 0.5;  // of each joint's velocity and acceleration limit, for moves
  double settle_time = 0.3;     // s, standing still before and after each scan
};

struct AcceptanceConfig {
  // The sensor position error the engine's covariance predicts (RMS over the workspace, 1 sigma)
  // must be at most this: the site's accuracy bound. The default is the top of the paper's
  // real-hardware range (1.7-4.1 mm); the shipped sensor files' intrinsics uncertainty alone
  // predicts 2-4 mm for a unit off the shelf (docs/engine.md, deviation 21).
  double max_predicted_error = 0.005;  // m
  // Optional (0 = off): the held-out scans, each registered rigidly onto the fit scans, may move
  // their sensor origins at most this far, RMS over the scans (core/calib/held_out_registration.h):
  // the model's error where it was not fitted, which the covariance does not see.
  double max_held_out_offset = 0;  // m
  // Optional (0 = off): the part of the validation RMS above `noise_floor` (daemon/gate.h) must
  // drop to at most (1 - min_improvement) of the current model's, unless the current model is
  // already at the floor. Without it a new model must only be not worse than the current one
  // beyond the comparison's noise.
  double min_improvement = 0;
  double noise_floor = 0;  // m: validation RMS of a correct model; 0 = plain RMS
  // Per link (base, each segment, tool): how far its transform may turn and move (daemon/gate.cc).
  double max_angle_change = 0.05;        // rad
  double max_translation_change = 0.05;  // m
};

struct StorageConfig {
  std::string folder;                      // sessions, models and history live here
  std::uint64_t quota_bytes = 2ull << 30;  // sessions beyond this are removed, oldest first
  std::int64_t requests_kept = 10'000;     // rows of the request history (about 200 B each)
};

struct DaemonConfig {
  std::string path;  // the file this came from
  // The robot this daemon calibrates; requests must name it (signed). Letters, digits, '.', '_',
  // '-'; at most 64 characters.
  std::string robot_id;
  // A large receive buffer: depth-camera clouds are megabytes and liblcm's default (the kernel's
  // 208 KiB) drops most of them (docs/cameras.md, "Large messages over LCM").
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";
  ChannelConfig channels;
  std::string robot_model;  // the nominal model, installed when the storage has none yet
  std::string sensor;       // sensor file (Table I parameters)
  std::map<std::string, std::string> plans;  // plan name -> plan file
  std::string default_plan;
  StorageConfig storage;
  std::string key_file;
  double request_window = 30;  // s: requests whose utime is further from now are stale
  CheckConfig checks;
  MotionConfig motion;
  AcceptanceConfig acceptance;
  int calibration_threads = 1;
  int calibration_nice = 10;  // added niceness of the calibration worker
  double status_rate_hz = 2;
};

// The installed daemon.yaml (program::InstalledConfig): the default of selfcald and its clients.
std::string InstalledDaemonConfig();
Expected<DaemonConfig> ReadDaemonConfig(const std::string& path);

// A robot id as requests and the fleet history carry it (DaemonConfig::robot_id).
bool IsValidRobotId(const std::string& id);
inline constexpr const char* kRobotIdRule = "must be 1 to 64 letters, digits, '.', '_' or '-'";
Expected<DaemonConfig> ParseDaemonConfig(const std::string& text, const std::string& path);

// Adds every setting of `config` to the program's configuration echo, under its key path in the
// file ("checks.max_lag_s", "plans.smoke"; relative paths resolved), so that selfcald logs its
// effective configuration in one line with its options; `config` must outlive the echo.
void DescribeSettings(program::Program& program, const DaemonConfig& config);

}  // namespace selfcal::daemon
