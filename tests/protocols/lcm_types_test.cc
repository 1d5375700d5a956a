// Every message type round-trips through memq:// and a file:// log with a distinct value in every
// field; the Drake types keep Drake's wire fingerprints; bad bytes give errors.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "drake/lcmt_iiwa_command.hpp"
#include "drake/lcmt_iiwa_status.hpp"
#include "protocols/bus/bus.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/calibration_request_t.hpp"
#include "selfcal/calibration_result_t.hpp"
#include "selfcal/calibration_status_t.hpp"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/joint_trajectory_t.hpp"
#include "selfcal/line_profile_t.hpp"
#include "selfcal/organized_cloud_t.hpp"
#include "selfcal/range_scan_t.hpp"
#include "selfcal/robot_driver_status_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal {
namespace {

// Distinct values: every call returns a new one.
struct Counter {
  int next = 1;
  double D() { return 0.5 + next++; }
  float F() { return static_cast<float>(0.25 + next++); }
  int64_t I64() { return 1000000000000LL + next++; }
  int32_t I32() { return 10000 + next++; }
  int16_t I16() { return static_cast<int16_t>(100 + next++); }
  int8_t I8() { return static_cast<int8_t>(next++ % 100); }
  std::string S() { return "value" + std::to_string(next++); }
  template <typename V, typename F>
  std::vector<V> Vec(int n, F f) {
    std::vector<V> v;
    for (int i = 0; i < n; ++i) v.push_back(f());
    return v;
  }
};

selfcal::joint_state_t MakeJointState(Counter& c) {
  selfcal::joint_state_t m;
  m.utime = c.I64();
  m.device_utime = c.I64();
  m.num_joints = 3;
  m.names = c.Vec<std::string>(3, [&] { return c.S(); });
  m.positions = c.Vec<double>(3, [&] { return c.D(); });
  m.velocities = c.Vec<double>(3, [&] { return c.D(); });
  m.efforts = c.Vec<double>(3, [&] { return c.D(); });
  return m;
}
selfcal::range_scan_t MakeRangeScan(Counter& c) {
  selfcal::range_scan_t m;
  m.utime = c.I64();
  m.device_utime = c.I64();
  m.scan_counter = c.I64();
  m.time_per_ray = c.D();
  m.angle_first = c.D();
  m.angle_increment = c.D();
  m.num_ranges = 4;
  m.ranges = c.Vec<float>(4, [&] { return c.F(); });
  m.num_intensities = 2;
  m.intensities = c.Vec<float>(2, [&] { return c.F(); });
  return m;
}
selfcal::line_profile_t MakeLineProfile(Counter& c) {
  selfcal::line_profile_t m;
  m.utime = c.I64();
  m.device_utime = c.I64();
  m.device_counter = c.I64();
  m.num_points = 3;
  m.x = c.Vec<float>(3, [&] { return c.F(); });
  m.z = c.Vec<float>(3, [&] { return c.F(); });
  m.intensity = c.Vec<float>(3, [&] { return c.F(); });
  return m;
}
selfcal::depth_image_t MakeDepthImage(Counter& c) {
  selfcal::depth_image_t m;
  m.utime = c.I64();
  m.device_utime = c.I64();
  m.frame_counter = c.I64();
  m.width = 3;
  m.height = 2;
  m.depth_unit_m = c.D();
  m.fx = c.D();
  m.fy = c.D();
  m.cx = c.D();
  m.cy = c.D();
  m.num_pixels = 6;
  m.depth = c.Vec<int16_t>(6, [&] { return c.I16(); });
  return m;
}
selfcal::organized_cloud_t MakeOrganizedCloud(Counter& c) {
  selfcal::organized_cloud_t m;
  m.utime = c.I64();
  m.device_utime = c.I64();
  m.frame_counter = c.I64();
  m.width = 2;
  m.height = 2;
  m.num_points = 4;
  m.x = c.Vec<float>(4, [&] { return c.F(); });
  m.y = c.Vec<float>(4, [&] { return c.F(); });
  m.z = c.Vec<float>(4, [&] { return c.F(); });
  m.num_intensities = 4;
  m.intensity = c.Vec<float>(4, [&] { return c.F(); });
  return m;
}
selfcal::scan_marker_t MakeScanMarker(Counter& c) {
  selfcal::scan_marker_t m;
  m.utime = c.I64();
  m.event = selfcal::scan_marker_t::END;
  m.purpose = selfcal::scan_marker_t::VALIDATION;
  m.scan_index = c.I32();
  m.plan_name = c.S();
  m.session_id = c.S();
  return m;
}
selfcal::calibration_request_t MakeRequest(Counter& c) {
  selfcal::calibration_request_t m;
  m.utime = c.I64();
  m.action = selfcal::calibration_request_t::ABORT;
  m.nonce = c.S();
  m.plan_name = c.S();
  m.requested_by = c.S();
  m.tag_length = 32;
  m.tag = c.Vec<uint8_t>(32, [&] { return static_cast<uint8_t>(c.I8()); });
  return m;
}
selfcal::calibration_status_t MakeStatus(Counter& c) {
  selfcal::calibration_status_t m;
  m.utime = c.I64();
  m.state = selfcal::calibration_status_t::VALIDATING;
  m.session_id = c.S();
  m.request_nonce = c.S();
  m.progress = c.F();
  m.message = c.S();
  return m;
}
selfcal::calibration_result_t MakeResult(Counter& c) {
  selfcal::calibration_result_t m;
  m.utime = c.I64();
  m.session_id = c.S();
  m.outcome = selfcal::calibration_result_t::REJECTED;
  m.reason = c.S();
  m.validation_rms_before = c.D();
  m.validation_rms_after = c.D();
  m.iterations = c.I32();
  m.runtime = c.D();
  m.model_path = c.S();
  m.num_parameters = 2;
  m.parameter_names = c.Vec<std::string>(2, [&] { return c.S(); });
  m.parameters_before = c.Vec<double>(2, [&] { return c.D(); });
  m.parameters_after = c.Vec<double>(2, [&] { return c.D(); });
  m.parameter_stddev = c.Vec<double>(2, [&] { return c.D(); });
  return m;
}
drake::lcmt_iiwa_status MakeIiwaStatus(Counter& c) {
  drake::lcmt_iiwa_status m;
  m.utime = c.I64();
  m.num_joints = 7;
  for (auto* v : {&m.joint_position_measured, &m.joint_velocity_estimated,
                  &m.joint_position_commanded, &m.joint_position_ipo, &m.joint_torque_measured,
                  &m.joint_torque_commanded, &m.joint_torque_external}) {
    *v = c.Vec<double>(7, [&] { return c.D(); });
  }
  return m;
}
drake::lcmt_iiwa_command MakeIiwaCommand(Counter& c) {
  drake::lcmt_iiwa_command m;
  m.utime = c.I64();
  m.num_joints = 7;
  m.joint_position = c.Vec<double>(7, [&] { return c.D(); });
  m.num_torques = 2;
  m.joint_torque = c.Vec<double>(2, [&] { return c.D(); });
  return m;
}

selfcal::joint_trajectory_t MakeJointTrajectory(Counter& c) {
  selfcal::joint_trajectory_t m;
  m.utime = c.I64();
  m.trajectory_id = c.S();
  m.num_joints = 3;
  m.joint_names = c.Vec<std::string>(3, [&] { return c.S(); });
  m.num_points = 2;
  m.time_from_start = c.Vec<double>(2, [&] { return c.D(); });
  m.positions =
      c.Vec<std::vector<double>>(2, [&] { return c.Vec<double>(3, [&] { return c.D(); }); });
  m.velocities =
      c.Vec<std::vector<double>>(2, [&] { return c.Vec<double>(3, [&] { return c.D(); }); });
  m.valid_until = c.I64();
  m.tag_length = 32;
  m.tag = c.Vec<uint8_t>(32, [&] { return static_cast<uint8_t>(c.I8()); });
  return m;
}
selfcal::robot_driver_status_t MakeRobotDriverStatus(Counter& c) {
  selfcal::robot_driver_status_t m;
  m.utime = c.I64();
  m.session_state = c.I8();
  m.connection_quality = c.I8();
  m.command_source = selfcal::robot_driver_status_t::SOURCE_STOPPING;
  m.event = selfcal::robot_driver_status_t::EVENT_REFUSED;
  m.trajectory_id = c.S();
  m.trajectory_time = c.D();
  m.messages_received = c.I64();
  m.messages_lost = c.I64();
  m.messages_late = c.I64();
  m.decode_errors = c.I64();
  m.replies_sent = c.I64();
  m.clock_settled = true;
  m.clock_drift_ppm = c.D();
  m.message = c.S();
  return m;
}

template <typename Message>
struct Case {
  using Type = Message;
  Message (*make)(Counter&);
};

// Publishes `sent` on memq:// and through a file:// log; both must decode to the same bytes.
template <typename Message>
void ExpectRoundTrip(Message (*make)(Counter&)) {
  Counter counter;
  const Message sent = make(counter);
  const auto sent_bytes = EncodeLcm(sent);
  const std::string type = Message::getTypeName();

  // memq://
  auto bus = OpenLcmBus("memq://");
  ASSERT_TRUE(bus.ok()) << bus.error().message;
  std::vector<uint8_t> received;
  (*bus)->Subscribe("CHANNEL_" + type, [&](const BusMessage& message) {
    const auto decoded = DecodeLcm<Message>(message.data, message.channel);
    ASSERT_TRUE(decoded.ok()) << decoded.error().message;
    received = EncodeLcm(*decoded);
  });
  ASSERT_TRUE((*bus)->Publish("CHANNEL_" + type, sent).ok());
  ASSERT_TRUE((*bus)->HandleOnce(std::chrono::milliseconds(1000)).value());
  EXPECT_EQ(received, sent_bytes) << type << " via memq://";

  // file:// log, through our writer and reader.
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("selfcal_types_" + type + std::to_string(::getpid()) + ".lcmlog"))
                               .string();
  {
    auto writer = LcmLogWriter::Open(path);
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    ASSERT_TRUE(writer->Write("LOG_" + type, 123456, sent).ok());
    ASSERT_TRUE(writer->Commit().ok());
  }
  auto reader = LcmLogReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  LogEvent event;
  ASSERT_TRUE(reader->Next(event));
  EXPECT_EQ(event.channel, "LOG_" + type);
  EXPECT_EQ(event.utime, 123456);
  const auto decoded = DecodeLcm<Message>(event.data, path);
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(EncodeLcm(*decoded), sent_bytes) << type << " via file log";
  EXPECT_FALSE(reader->Next(event));
  std::filesystem::remove(path);
}

TEST(LcmTypes, EveryTypeRoundTripsThroughMemqAndAFileLog) {
  ExpectRoundTrip(&MakeJointState);
  ExpectRoundTrip(&MakeRangeScan);
  ExpectRoundTrip(&MakeLineProfile);
  ExpectRoundTrip(&MakeDepthImage);
  ExpectRoundTrip(&MakeOrganizedCloud);
  ExpectRoundTrip(&MakeScanMarker);
  ExpectRoundTrip(&MakeRequest);
  ExpectRoundTrip(&MakeStatus);
  ExpectRoundTrip(&MakeResult);
  ExpectRoundTrip(&MakeIiwaStatus);
  ExpectRoundTrip(&MakeIiwaCommand);
  ExpectRoundTrip(&MakeJointTrajectory);
  ExpectRoundTrip(&MakeRobotDriverStatus);
}

TEST(LcmTypes, FieldsSurviveByValue) {
  Counter counter;
  const auto sent = MakeJointState(counter);
  const auto decoded = DecodeLcm<selfcal::joint_state_t>(EncodeLcm(sent), "test").value();
  EXPECT_EQ(decoded.utime, sent.utime);
  EXPECT_EQ(decoded.device_utime, sent.device_utime);
  EXPECT_NE(decoded.utime, decoded.device_utime);
  EXPECT_EQ(decoded.names, sent.names);
  EXPECT_EQ(decoded.positions, sent.positions);
  EXPECT_EQ(decoded.velocities, sent.velocities);
  EXPECT_EQ(decoded.efforts, sent.efforts);
}

uint64_t WireFingerprint(const std::vector<uint8_t>& bytes) {
  uint64_t f = 0;
  for (int i = 0; i < 8; ++i) f = (f << 8) | bytes[static_cast<std::size_t>(i)];
  return f;
}

TEST(LcmTypes, DrakeFingerprintsMatchDrakesWire) {
  Counter counter;
  const auto status = EncodeLcm(MakeIiwaStatus(counter));
  EXPECT_EQ(WireFingerprint(status), 0xf16fb804284abca3ULL);
  EXPECT_EQ(status.size(), 412u);  // protocols.md: 7 joints
  drake::lcmt_iiwa_command command = MakeIiwaCommand(counter);
  command.num_torques = 0;
  command.joint_torque.clear();
  const auto command_bytes = EncodeLcm(command);
  EXPECT_EQ(WireFingerprint(command_bytes), 0xddc7c7738c815334ULL);
  EXPECT_EQ(command_bytes.size(), 80u);
}

TEST(LcmCodec, RejectsTruncatedCorruptedAndForeignBytes) {
  Counter counter;
  const auto bytes = EncodeLcm(MakeRangeScan(counter));
  // Truncated at every length.
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    const auto result = DecodeLcm<selfcal::range_scan_t>({bytes.data(), n}, "ch");
    ASSERT_FALSE(result.ok()) << "length " << n;
    EXPECT_NE(result.error().message.find("ch: "), std::string::npos);
  }
  // Trailing junk.
  auto longer = bytes;
  longer.push_back(0);
  const auto trailing = DecodeLcm<selfcal::range_scan_t>(longer, "ch");
  ASSERT_FALSE(trailing.ok());
  EXPECT_NE(trailing.error().message.find("trailing"), std::string::npos);
  // Wrong type.
  const auto foreign = DecodeLcm<selfcal::joint_state_t>(bytes, "ch");
  ASSERT_FALSE(foreign.ok());
  EXPECT_NE(foreign.error().message.find("fingerprint"), std::string::npos);
  // A corrupted array length (num_ranges) claiming two billion entries: an error, no allocation.
  auto corrupted = bytes;
  const std::size_t num_ranges_offset = 8 + 8 + 8 + 8 + 8 + 8 + 8;
  corrupted[num_ranges_offset] = 0x7f;
  const auto huge = DecodeLcm<selfcal::range_scan_t>(corrupted, "ch");
  ASSERT_FALSE(huge.ok());
  EXPECT_NE(huge.error().message.find("corrupted"), std::string::npos);
}

TEST(LcmLog, MissingFileAndUnopenableBusGiveErrors) {
  const auto reader = LcmLogReader::Open("/nonexistent/selfcal.lcmlog");
  ASSERT_FALSE(reader.ok());
  EXPECT_NE(reader.error().message.find("/nonexistent/selfcal.lcmlog"), std::string::npos);
  const auto bus = OpenLcmBus("nosuchprovider://");
  ASSERT_FALSE(bus.ok());
  EXPECT_NE(bus.error().message.find("nosuchprovider://"), std::string::npos);
}

TEST(LcmLog, UncommittedLogIsNotAtTheFinalPath) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("selfcal_partial_" + std::to_string(::getpid()) + ".lcmlog"))
                               .string();
  {
    auto writer = LcmLogWriter::Open(path);
    ASSERT_TRUE(writer.ok());
    ASSERT_TRUE(writer->Write("A", 1, std::vector<uint8_t>{1, 2, 3}).ok());
    // No Commit(): as after a crash.
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::exists(path + ".partial"));
  std::filesystem::remove(path + ".partial");
}

// Found by fuzz_lcm_log: liblcm allocates the data length an event header declares before it
// reads the data, and writes into the allocation unchecked. A header declaring 2 GB in a file of
// a few hundred bytes must end the log after the events before it, in a process that cannot map
// 2 GB (before: a segmentation fault on the failed allocation).
TEST(LcmLog, AnEventLongerThanTheFileEndsTheLogWithoutAllocatingIt) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("selfcal_oversized_" + std::to_string(::getpid()) + ".lcmlog"))
                               .string();
  {
    auto writer = LcmLogWriter::Open(path);
    ASSERT_TRUE(writer.ok());
    ASSERT_TRUE(writer->Write("A", 1, std::vector<uint8_t>{1, 2, 3}).ok());
    ASSERT_TRUE(writer->Commit().ok());
  }
  {
    // A second event: sync word, number 1, time 2, channel length 1, data length 0x7ffffff0.
    std::FILE* file = std::fopen(path.c_str(), "ab");
    ASSERT_NE(file, nullptr);
    const unsigned char header[] = {0xED, 0xA1, 0xDA, 0x01, 0,    0,    0,   0, 0, 0, 0,
                                    1,    0,    0,    0,    0,    0,    0,   0, 2, 0, 0,
                                    0,    1,    0x7F, 0xFF, 0xFF, 0xF0, 'B', 9, 9, 9};
    ASSERT_EQ(std::fwrite(header, 1, sizeof(header), file), sizeof(header));
    std::fclose(file);
  }
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // No room for 2 GB more than the process has now.
    long pages = 0;
    if (std::FILE* statm = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(statm, "%ld", &pages) != 1) pages = 0;
      std::fclose(statm);
    }
    const rlim_t limit = static_cast<rlim_t>(pages) * static_cast<rlim_t>(::sysconf(_SC_PAGESIZE)) +
                         (rlim_t{512} << 20);
    const rlimit address_space{limit, limit};
    if (pages == 0 || ::setrlimit(RLIMIT_AS, &address_space) != 0) ::_exit(3);
    auto reader = LcmLogReader::Open(path);
    if (!reader.ok()) ::_exit(4);
    LogEvent event;
    int events = 0;
    while (reader->Next(event)) ++events;
    ::_exit(events == 1 && event.channel == "A" ? 0 : 5);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  std::filesystem::remove(path);
  ASSERT_TRUE(WIFEXITED(status)) << "the reader died of signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

}  // namespace
}  // namespace selfcal
