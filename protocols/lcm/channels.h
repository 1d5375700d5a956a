// Default LCM channel names. Channels are configuration (config/channels.yaml and each
// program's flags); these are the defaults every program agrees on.
#pragma once

#include <string>

namespace selfcal::channels {

inline constexpr const char* kJointState = "SELFCAL_JOINT_STATE";    // selfcal.joint_state_t
inline constexpr const char* kRangeScan = "SELFCAL_RANGE_SCAN";      // selfcal.range_scan_t
inline constexpr const char* kLineProfile = "SELFCAL_LINE_PROFILE";  // selfcal.line_profile_t
inline constexpr const char* kDepthImage = "SELFCAL_DEPTH_IMAGE";    // selfcal.depth_image_t
inline constexpr const char* kOrganizedCloud =
    "SELFCAL_ORGANIZED_CLOUD";                                     // selfcal.organized_cloud_t
inline constexpr const char* kScanMarker = "SELFCAL_SCAN_MARKER";  // selfcal.scan_marker_t
inline constexpr const char* kCalibrationRequest = "SELFCAL_CALIBRATION_REQUEST";
inline constexpr const char* kCalibrationStatus = "SELFCAL_CALIBRATION_STATUS";
inline constexpr const char* kCalibrationResult = "SELFCAL_CALIBRATION_RESULT";
// Robot driver: trajectories to execute, driver status and refusals, simulator truth.
inline constexpr const char* kJointTrajectory =
    "SELFCAL_JOINT_TRAJECTORY";  // selfcal.joint_trajectory_t
inline constexpr const char* kRobotStatus =
    "SELFCAL_ROBOT_STATUS";  // selfcal.robot_driver_status_t
inline constexpr const char* kSimJointTruth = "SELFCAL_SIM_JOINT_TRUTH";  // selfcal.joint_state_t
// Drake's iiwa driver channels (drake.lcmt_iiwa_status / drake.lcmt_iiwa_command).
inline constexpr const char* kIiwaStatus = "IIWA_STATUS";
inline constexpr const char* kIiwaCommand = "IIWA_COMMAND";

// The channels a recording's messages travel on (docs/recording.md): what the simulator writes
// and the recording reader reads, with the defaults above.
struct RecordingChannels {
  std::string joint_state = kJointState;
  std::string scan_marker = kScanMarker;
  std::string range_scan = kRangeScan;
  std::string line_profile = kLineProfile;
  std::string depth_image = kDepthImage;
  std::string organized_cloud = kOrganizedCloud;
};

}  // namespace selfcal::channels
