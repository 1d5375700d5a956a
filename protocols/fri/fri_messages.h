// FRI (KUKA Sunrise.FRI) monitoring and command messages as plain structs: the subset of
// fri.proto that selfcal reads and writes. Field numbers and meanings: ../shared/protocols.md 3.3.
// Not supported (skipped when decoding, never encoded): I/O values, Cartesian transformations.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace selfcal::fri {

inline constexpr std::uint32_t kMonitorMessageId = 0x245142;  // LBR monitoring message
inline constexpr std::uint32_t kCommandMessageId = 0x34001;   // LBR command message
inline constexpr std::size_t kMaxMessageBytes = 1500;         // both directions
// Bound on the values of one JointValues / CartesianVector, so bad input cannot allocate much.
inline constexpr std::size_t kMaxJointValues = 32;

enum class SessionState : std::int32_t {
  kIdle = 0,
  kMonitoringWait = 1,
  kMonitoringReady = 2,
  kCommandingWait = 3,
  kCommandingActive = 4,
};
enum class ConnectionQuality : std::int32_t { kPoor = 0, kFair = 1, kGood = 2, kExcellent = 3 };
enum class SafetyState : std::int32_t {
  kNormalOperation = 0,
  kSafetyStopLevel0 = 1,
  kSafetyStopLevel1 = 2,
  kSafetyStopLevel2 = 3,
};
enum class OperationMode : std::int32_t { kTestMode1 = 0, kTestMode2 = 1, kAutomatic = 2 };
enum class DriveState : std::int32_t { kOff = 0, kTransitioning = 1, kActive = 2 };
enum class ControlMode : std::int32_t {
  kPosition = 0,
  kCartesianImpedance = 1,
  kJointImpedance = 2,
  kNone = 3,
};
enum class ClientCommandMode : std::int32_t { kNone = 0, kPosition = 1, kWrench = 2, kTorque = 3 };
enum class OverlayType : std::int32_t { kNone = 0, kJoint = 1, kCartesian = 2 };

const char* ToString(SessionState state);
const char* ToString(ConnectionQuality quality);

struct MessageHeader {
  std::uint32_t message_identifier = 0;
  std::uint32_t sequence_counter = 0;
  std::uint32_t reflected_sequence_counter = 0;
};

struct TimeStamp {
  std::uint32_t sec = 0;
  std::uint32_t nanosec = 0;
};

struct ConnectionInfo {
  SessionState session_state = SessionState::kIdle;
  ConnectionQuality quality = ConnectionQuality::kPoor;
  std::optional<std::uint32_t> send_period_ms;
  std::optional<std::uint32_t> receive_multiplier;
};

struct RobotInfo {
  std::optional<std::int32_t> number_of_joints;
  std::optional<SafetyState> safety_state;
  std::vector<DriveState> drive_state;
  std::optional<OperationMode> operation_mode;
  std::optional<ControlMode> control_mode;
};

// Joint values in rad (positions) or N m (torques), base to tip.
using JointValues = std::vector<double>;

struct MonitorData {
  std::optional<JointValues> measured_joint_position;
  std::optional<JointValues> measured_torque;
  std::optional<JointValues> commanded_joint_position;
  std::optional<JointValues> commanded_torque;
  std::optional<JointValues> external_torque;
  std::optional<TimeStamp> timestamp;  // the controller's clock
};

struct IpoData {
  std::optional<JointValues> joint_position;
  std::optional<ClientCommandMode> client_command_mode;
  std::optional<OverlayType> overlay_type;
  std::optional<double> tracking_performance;
};

struct EndOfMessage {
  std::optional<std::int32_t> message_length;
  bool has_checksum = false;  // MessageEndOf.messageChecksum present
  std::optional<std::int32_t> crc32;
};

struct MonitoringMessage {
  MessageHeader header;
  std::optional<RobotInfo> robot_info;
  std::optional<MonitorData> monitor_data;
  std::optional<ConnectionInfo> connection_info;
  std::optional<IpoData> ipo_data;
  std::optional<EndOfMessage> end_of_message;
};

struct CommandData {
  std::optional<JointValues> joint_position;
  std::optional<std::vector<double>> cartesian_wrench_feed_forward;
  std::optional<JointValues> joint_torque;
};

struct CommandMessage {
  MessageHeader header;
  std::optional<CommandData> command_data;
  std::optional<EndOfMessage> end_of_message;
};

}  // namespace selfcal::fri
