// FRI codec against golden bytes encoded by protoc from our own fri.proto (an independent
// encoder), both directions; then every truncation, corruptions and oversized input.
#include "protocols/fri/fri_codec.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace selfcal::fri {
namespace {

std::string SourceDir() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return dir ? dir : ".";
}

std::vector<std::uint8_t> ReadHex(const std::string& name) {
  std::ifstream in(SourceDir() + "/tests/fri/golden/" + name);
  EXPECT_TRUE(in.good()) << name;
  std::vector<std::uint8_t> bytes;
  std::string hex;
  char c;
  while (in.get(c)) {
    if (std::isxdigit(static_cast<unsigned char>(c))) hex.push_back(c);
  }
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2) {
    bytes.push_back(static_cast<std::uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  }
  return bytes;
}

MonitoringMessage CommandingActive() {
  MonitoringMessage m;
  m.header = {kMonitorMessageId, 4711, 4710};
  RobotInfo info;
  info.number_of_joints = 7;
  info.safety_state = SafetyState::kNormalOperation;
  info.drive_state = {DriveState::kActive, DriveState::kActive, DriveState::kActive,
                      DriveState::kActive, DriveState::kActive, DriveState::kTransitioning,
                      DriveState::kActive};
  info.operation_mode = OperationMode::kAutomatic;
  info.control_mode = ControlMode::kJointImpedance;
  m.robot_info = info;
  MonitorData d;
  d.measured_joint_position = JointValues{0.1, -0.2, 0.3, -1.4, 0.5, 0.6, -0.7};
  d.measured_torque = JointValues{1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5};
  d.commanded_joint_position = JointValues{0.11, -0.21, 0.31, -1.41, 0.51, 0.61, -0.71};
  d.commanded_torque = JointValues{-1.25, -2.25, -3.25, -4.25, -5.25, -6.25, -7.25};
  d.external_torque = JointValues{0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07};
  d.timestamp = TimeStamp{1700000123, 456789000};
  m.monitor_data = d;
  m.connection_info =
      ConnectionInfo{SessionState::kCommandingActive, ConnectionQuality::kExcellent, 5u, 1u};
  IpoData ipo;
  ipo.joint_position = JointValues{0.12, -0.22, 0.32, -1.42, 0.52, 0.62, -0.72};
  ipo.client_command_mode = ClientCommandMode::kPosition;
  ipo.overlay_type = OverlayType::kJoint;
  ipo.tracking_performance = 0.875;
  m.ipo_data = ipo;
  EndOfMessage end;
  end.message_length = 812;
  end.has_checksum = true;
  end.crc32 = -123456;
  m.end_of_message = end;
  return m;
}

CommandMessage PositionCommand() {
  CommandMessage c;
  c.header = {kCommandMessageId, 99, 4711};
  CommandData d;
  d.joint_position = JointValues{0.125, -0.25, 0.375, -1.5, 0.625, 0.75, -0.875};
  d.joint_torque = JointValues{};
  c.command_data = d;
  return c;
}

std::vector<std::uint8_t> Encode(const MonitoringMessage& m) {
  std::vector<std::uint8_t> out(kMaxMessageBytes);
  auto n = EncodeMonitoringMessage(m, out);
  EXPECT_TRUE(n.ok()) << n.error().message;
  out.resize(n.ok() ? *n : 0);
  return out;
}

std::vector<std::uint8_t> Encode(const CommandMessage& m) {
  std::vector<std::uint8_t> out(kMaxMessageBytes);
  auto n = EncodeCommandMessage(m, out);
  EXPECT_TRUE(n.ok()) << n.error().message;
  out.resize(n.ok() ? *n : 0);
  return out;
}

TEST(FriCodec, EncodesMonitoringMessageExactlyAsProtoc) {
  EXPECT_EQ(Encode(CommandingActive()), ReadHex("monitoring_commanding_active.hex"));
}

TEST(FriCodec, DecodesEveryFieldOfProtocsMonitoringMessage) {
  const auto decoded = DecodeMonitoringMessage(ReadHex("monitoring_commanding_active.hex"));
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  const MonitoringMessage& m = *decoded;
  const MonitoringMessage want = CommandingActive();
  EXPECT_EQ(m.header.message_identifier, 2380098u);
  EXPECT_EQ(m.header.sequence_counter, 4711u);
  EXPECT_EQ(m.header.reflected_sequence_counter, 4710u);
  ASSERT_TRUE(m.robot_info);
  EXPECT_EQ(m.robot_info->number_of_joints, 7);
  EXPECT_EQ(m.robot_info->drive_state, want.robot_info->drive_state);
  EXPECT_EQ(m.robot_info->operation_mode, OperationMode::kAutomatic);
  EXPECT_EQ(m.robot_info->control_mode, ControlMode::kJointImpedance);
  ASSERT_TRUE(m.monitor_data);
  EXPECT_EQ(m.monitor_data->measured_joint_position, want.monitor_data->measured_joint_position);
  EXPECT_EQ(m.monitor_data->measured_torque, want.monitor_data->measured_torque);
  EXPECT_EQ(m.monitor_data->commanded_joint_position, want.monitor_data->commanded_joint_position);
  EXPECT_EQ(m.monitor_data->commanded_torque, want.monitor_data->commanded_torque);
  EXPECT_EQ(m.monitor_data->external_torque, want.monitor_data->external_torque);
  ASSERT_TRUE(m.monitor_data->timestamp);
  EXPECT_EQ(m.monitor_data->timestamp->sec, 1700000123u);
  EXPECT_EQ(m.monitor_data->timestamp->nanosec, 456789000u);
  ASSERT_TRUE(m.connection_info);
  EXPECT_EQ(m.connection_info->session_state, SessionState::kCommandingActive);
  EXPECT_EQ(m.connection_info->quality, ConnectionQuality::kExcellent);
  EXPECT_EQ(m.connection_info->send_period_ms, 5u);
  EXPECT_EQ(m.connection_info->receive_multiplier, 1u);
  ASSERT_TRUE(m.ipo_data);
  EXPECT_EQ(m.ipo_data->joint_position, want.ipo_data->joint_position);
  EXPECT_EQ(m.ipo_data->client_command_mode, ClientCommandMode::kPosition);
  EXPECT_EQ(m.ipo_data->overlay_type, OverlayType::kJoint);
  EXPECT_EQ(m.ipo_data->tracking_performance, 0.875);
  ASSERT_TRUE(m.end_of_message);
  EXPECT_EQ(m.end_of_message->message_length, 812);
  EXPECT_EQ(m.end_of_message->crc32, -123456);
}

TEST(FriCodec, MinimalMonitoringWaitMessage) {
  const auto golden = ReadHex("monitoring_wait_minimal.hex");
  const auto decoded = DecodeMonitoringMessage(golden);
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->connection_info->session_state, SessionState::kMonitoringWait);
  EXPECT_EQ(decoded->connection_info->quality, ConnectionQuality::kPoor);
  EXPECT_FALSE(decoded->connection_info->send_period_ms);
  EXPECT_FALSE(decoded->ipo_data);
  EXPECT_FALSE(decoded->robot_info);
  EXPECT_EQ(decoded->monitor_data->measured_joint_position, JointValues(7, 0.0));
  EXPECT_EQ(decoded->monitor_data->timestamp->nanosec, 5000000u);
  EXPECT_EQ(Encode(*decoded), golden);
}

TEST(FriCodec, CommandMessageBothWays) {
  const auto golden = ReadHex("command_position.hex");
  EXPECT_EQ(Encode(PositionCommand()), golden);
  const auto decoded = DecodeCommandMessage(golden);
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->header.message_identifier, kCommandMessageId);
  EXPECT_EQ(decoded->header.sequence_counter, 99u);
  EXPECT_EQ(decoded->header.reflected_sequence_counter, 4711u);
  ASSERT_TRUE(decoded->command_data);
  EXPECT_EQ(decoded->command_data->joint_position, PositionCommand().command_data->joint_position);
  ASSERT_TRUE(decoded->command_data->joint_torque);
  EXPECT_TRUE(decoded->command_data->joint_torque->empty());
  EXPECT_FALSE(decoded->command_data->cartesian_wrench_feed_forward);
}

TEST(FriCodec, ProtocDecodesOurEncoding) {
  if (std::system("command -v protoc >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "protoc not installed (tools/setup-deps installs protobuf-compiler)";
  }
  const auto bytes = Encode(CommandingActive());
  const auto dir =
      std::filesystem::temp_directory_path() / ("selfcal_fri_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream((dir / "m.bin").string(), std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
  }
  const std::string command =
      "protoc --proto_path=" + SourceDir() +
      "/protocols/fri --decode=selfcal_fri.FRIMonitoringMessage fri.proto < " +
      (dir / "m.bin").string() + " > " + (dir / "m.txt").string();
  ASSERT_EQ(std::system(command.c_str()), 0);
  std::ifstream in((dir / "m.txt").string());
  std::stringstream text;
  text << in.rdbuf();
  std::filesystem::remove_all(dir);
  EXPECT_NE(text.str().find("sessionState: COMMANDING_ACTIVE"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("crc32: -123456"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("value: -1.41"), std::string::npos) << text.str();
}

TEST(FriCodec, EveryTruncationIsAnErrorOrAValidPrefix) {
  const auto golden = ReadHex("monitoring_commanding_active.hex");
  int errors = 0;
  for (std::size_t n = 0; n < golden.size(); ++n) {
    const auto decoded = DecodeMonitoringMessage({golden.data(), n});
    if (!decoded.ok()) {
      ++errors;
      EXPECT_EQ(decoded.error().message.rfind("byte ", 0), 0u) << decoded.error().message;
    }
  }
  // Cuts inside the top-level header or inside any nested message must fail; only cuts at the
  // boundaries between top-level fields can decode (protobuf has no length prefix).
  EXPECT_GE(errors, static_cast<int>(golden.size()) - 6);
}

TEST(FriCodec, CorruptionsNameTheByteAndField) {
  auto bytes = ReadHex("monitoring_commanding_active.hex");
  // Session state 4 -> 9: unknown enum value inside connectionInfo.
  const auto state = DecodeMonitoringMessage(bytes);
  ASSERT_TRUE(state.ok());
  {
    auto corrupted = Encode(CommandingActive());
    // Find the connectionInfo field (key 0x22) and its first value byte.
    std::size_t i = 0;
    for (; i < corrupted.size(); ++i) {
      if (corrupted[i] == 0x22 && corrupted[i + 2] == 0x08 && corrupted[i + 3] == 0x04) break;
    }
    ASSERT_LT(i, corrupted.size());
    corrupted[i + 3] = 9;
    const auto result = DecodeMonitoringMessage(corrupted);
    ASSERT_FALSE(result.ok());
    EXPECT_NE(result.error().message.find("connectionInfo.sessionState"), std::string::npos)
        << result.error().message;
    EXPECT_NE(result.error().message.find("byte " + std::to_string(i + 2)), std::string::npos)
        << result.error().message;
  }
  {
    // A nested length beyond the datagram.
    auto corrupted = bytes;
    corrupted[1] = 0x7f;
    const auto result = DecodeMonitoringMessage(corrupted);
    ASSERT_FALSE(result.ok());
    EXPECT_NE(result.error().message.find("header"), std::string::npos) << result.error().message;
  }
  {
    // Missing header.
    const std::vector<std::uint8_t> no_header = {0x22, 0x04, 0x08, 0x01, 0x10, 0x00};
    const auto result = DecodeMonitoringMessage(no_header);
    ASSERT_FALSE(result.ok());
    EXPECT_NE(result.error().message.find("header: required field missing"), std::string::npos)
        << result.error().message;
  }
  {
    // Wire type 3 (groups) is not FRI.
    const std::vector<std::uint8_t> group = {0x0b};
    ASSERT_FALSE(DecodeMonitoringMessage(group).ok());
  }
  {
    // Oversized and empty datagrams.
    std::vector<std::uint8_t> big(kMaxMessageBytes + 1, 0);
    ASSERT_FALSE(DecodeMonitoringMessage(big).ok());
    ASSERT_FALSE(DecodeCommandMessage({}).ok());
  }
  {
    // 33 joint values are refused on both sides.
    MonitoringMessage m = CommandingActive();
    m.monitor_data->measured_joint_position = JointValues(33, 1.0);
    std::vector<std::uint8_t> out(kMaxMessageBytes);
    ASSERT_FALSE(EncodeMonitoringMessage(m, out).ok());
    std::vector<std::uint8_t> values = {0x0a, 0x01 + 0};
    std::vector<std::uint8_t> inner;
    for (int i = 0; i < 33; ++i) {
      inner.push_back(0x09);
      for (int b = 0; b < 8; ++b) inner.push_back(0);
    }
    CommandMessage c = PositionCommand();
    auto encoded = Encode(c);
    std::vector<std::uint8_t> crafted(encoded.begin(), encoded.begin() + 11);  // header only
    crafted.push_back(0x12);
    crafted.push_back(static_cast<std::uint8_t>(0x80 | ((inner.size() + 3) & 0x7f)));
    crafted.push_back(static_cast<std::uint8_t>((inner.size() + 3) >> 7));
    crafted.push_back(0x0a);
    crafted.push_back(static_cast<std::uint8_t>(0x80 | (inner.size() & 0x7f)));
    crafted.push_back(static_cast<std::uint8_t>(inner.size() >> 7));
    crafted.insert(crafted.end(), inner.begin(), inner.end());
    const auto result = DecodeCommandMessage(crafted);
    ASSERT_FALSE(result.ok());
    EXPECT_NE(result.error().message.find("more than 32"), std::string::npos)
        << result.error().message;
  }
}

TEST(FriCodec, SmallOutputBufferIsAnError) {
  std::vector<std::uint8_t> out(40);
  const auto result = EncodeMonitoringMessage(CommandingActive(), out);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().message.find("40 bytes"), std::string::npos);
}

TEST(FriCodec, UnknownFieldsAreSkippedAndPackedDoublesAccepted) {
  CommandMessage c = PositionCommand();
  auto bytes = Encode(c);
  // Append an unknown varint field 7 and an unknown fixed32 field 8 at top level.
  bytes.insert(bytes.end(), {0x38, 0x96, 0x01, 0x45, 1, 2, 3, 4});
  auto decoded = DecodeCommandMessage(bytes);
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->command_data->joint_position, c.command_data->joint_position);
  // Packed form of jointPosition {1.0, 2.0}.
  std::vector<std::uint8_t> packed(bytes.begin(), bytes.begin() + 11);
  packed.insert(packed.end(), {0x12, 0x14, 0x0a, 0x12, 0x0a, 0x10});
  for (double v : {1.0, 2.0}) {
    const auto bits = std::bit_cast<std::uint64_t>(v);
    for (int b = 0; b < 8; ++b) packed.push_back(static_cast<std::uint8_t>(bits >> (8 * b)));
  }
  decoded = DecodeCommandMessage(packed);
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(decoded->command_data->joint_position, (JointValues{1.0, 2.0}));
}

}  // namespace
}  // namespace selfcal::fri
