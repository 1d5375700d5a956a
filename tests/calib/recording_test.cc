// Recordings -> datasets (protocols/recording): segmentation by markers, grids, interpolation to
// each measurement time (+ latency), and errors that name the scan.
#include "protocols/recording/recording.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/calib/joint_interpolation.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/line_profile_t.hpp"
#include "selfcal/range_scan_t.hpp"
#include "selfcal/scan_marker_t.hpp"
#include "tests/calib/synthetic.h"

namespace selfcal::recording {
namespace {

constexpr std::int64_t kStart = 1700000000000000;

class RecordingTest : public ::testing::Test {
 public:  // the error cases call these from lambdas
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("selfcal_recording_test_" + std::to_string(getpid()) + "_" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(directory_);
    robot_ = calib::testing::LoadIiwa();
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }
  std::string Path() const { return (directory_ / "recording.lcmlog").string(); }

  // Joint i at time t [s after kStart]: a ramp, so linear interpolation is exact.
  static double Joint(std::size_t i, double t) { return 0.1 * static_cast<double>(i) + 0.5 * t; }

  void WriteJointStates(LcmLogWriter& writer, double from_s, double to_s, double rate_hz,
                        int joints = 7, double poison_at_s = -1) {
    for (double t = from_s; t <= to_s + 1e-9; t += 1.0 / rate_hz) {
      selfcal::joint_state_t state{};
      state.utime = kStart + static_cast<std::int64_t>(std::llround(t * 1e6));
      state.device_utime = -1;
      state.num_joints = joints;
      for (int i = 0; i < joints; ++i) {
        const auto joint = static_cast<std::size_t>(i);
        state.names.push_back(joint < joint_names_.size() ? joint_names_[joint]
                              : i < 7                     ? robot_.joints[joint].name
                                                          : "X");
        state.positions.push_back(std::abs(t - poison_at_s) < 1e-9
                                      ? std::nan("")
                                      : Joint(static_cast<std::size_t>(i), t));
        state.velocities.push_back(0.5);
        state.efforts.push_back(std::nan(""));
      }
      ASSERT_TRUE(writer.Write("SELFCAL_JOINT_STATE", state.utime, state).ok());
    }
  }
  void WriteMarker(LcmLogWriter& writer, double t, int8_t event, int scan, int8_t purpose = 1) {
    selfcal::scan_marker_t marker{};
    marker.utime = kStart + static_cast<std::int64_t>(std::llround(t * 1e6));
    marker.event = event;
    marker.purpose = purpose;
    marker.scan_index = scan;
    marker.plan_name = "test";
    marker.session_id = "s";
    ASSERT_TRUE(writer.Write("SELFCAL_SCAN_MARKER", marker.utime, marker).ok());
  }
  // A log of one LiDAR scan (0.5-0.9 s): three rotations of five rays each from 0.6 s, the third
  // ray without a return, and the joints' ramp at 1 kHz.
  void WriteLidarLog() {
    auto writer = LcmLogWriter::Open(Path());
    ASSERT_TRUE(writer.ok());
    WriteJointStates(*writer, 0.0, 2.0, 1000);
    WriteMarker(*writer, 0.5, 1, 0);
    for (int rotation = 0; rotation < 3; ++rotation)
      WriteRangeScan(*writer, 0.6 + 0.025 * rotation);
    WriteMarker(*writer, 0.9, 2, 0);
    ASSERT_TRUE(writer->Commit().ok());
  }
  // A two-point line profile (z 0.5 and 0.6 m) measured at t [s after kStart].
  void WriteLineProfile(LcmLogWriter& writer, double t) {
    selfcal::line_profile_t profile{};
    profile.utime = kStart + static_cast<std::int64_t>(std::llround(t * 1e6));
    profile.device_utime = -1;
    profile.num_points = 2;
    profile.x = {-0.1f, 0.1f};
    profile.z = {0.5f, 0.6f};
    profile.intensity = {1, 1};
    ASSERT_TRUE(writer.Write("SELFCAL_LINE_PROFILE", profile.utime + 500, profile).ok());
  }
  void WriteDepth(LcmLogWriter& writer, double t, std::uint16_t depth_mm,
                  bool all_invalid = false) {
    selfcal::depth_image_t image{};
    image.utime = kStart + static_cast<std::int64_t>(std::llround(t * 1e6));
    image.device_utime = -1;
    image.width = 4;
    image.height = 3;
    image.depth_unit_m = 0.001;
    image.fx = 2;
    image.fy = 2;
    image.cx = 1.5;
    image.cy = 1;
    image.num_pixels = 12;
    for (int i = 0; i < 12; ++i)
      image.depth.push_back(all_invalid || i == 5 ? 0 : static_cast<int16_t>(depth_mm));
    ASSERT_TRUE(
        writer.Write("SELFCAL_DEPTH_IMAGE", image.utime + 30000, image).ok());  // logged later
  }

  void WriteRangeScan(LcmLogWriter& writer, double t) {
    selfcal::range_scan_t scan{};
    scan.utime = kStart + static_cast<std::int64_t>(std::llround(t * 1e6));
    scan.device_utime = -1;
    scan.time_per_ray = 1.0 / 57600;
    scan.angle_first = -0.5;
    scan.angle_increment = 0.25;
    scan.num_ranges = 5;
    scan.ranges = {1.0f, 2.0f, std::nanf(""), 4.0f, 5.0f};
    scan.num_intensities = 0;
    ASSERT_TRUE(writer.Write("SELFCAL_RANGE_SCAN", scan.utime + 1000, scan).ok());
  }
  // Fit scans 0 and 1 (one depth frame each), complete; the log is committed.
  void WriteTwoCompleteScans(LcmLogWriter& writer) {
    WriteJointStates(writer, 0.0, 1.0, 200);
    WriteMarker(writer, 0.1, 1, 0);
    WriteDepth(writer, 0.15, 1500);
    WriteMarker(writer, 0.2, 2, 0);
    WriteMarker(writer, 0.3, 1, 1);
    WriteDepth(writer, 0.35, 1500);
    WriteMarker(writer, 0.4, 2, 1);
  }
  // Cuts the last `bytes` bytes off the log, as `head -c` or a crash while writing does.
  void CutOff(std::uintmax_t bytes) {
    std::filesystem::resize_file(Path(), std::filesystem::file_size(Path()) - bytes);
  }

  std::filesystem::path directory_;
  RobotModel robot_;
  std::vector<std::string> joint_names_;  // names the joint states give; empty = the model's
};

SensorConfig Camera() {
  SensorConfig sensor;
  sensor.layout = SensorLayout::kDepthCamera;
  return sensor;
}

TEST_F(RecordingTest, DepthImagesBecomeOnePoseDatasetsWithInterpolatedJoints) {
  auto writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteJointStates(*writer, 0.0, 3.0, 200);
  WriteMarker(*writer, 0.5, 1, 1, 2);  // scan 1 is a validation scan, recorded first
  WriteDepth(*writer, 0.6012, 1500);
  WriteMarker(*writer, 0.7, 2, 1, 2);
  WriteMarker(*writer, 1.5, 1, 0);
  WriteDepth(*writer, 1.6033, 2000);
  WriteMarker(*writer, 1.7, 2, 0);
  ASSERT_TRUE(writer->Commit().ok());

  RecordingOptions options;
  options.latency_s = 0.004;
  const auto datasets = LoadRecording(Path(), robot_, Camera(), options);
  ASSERT_TRUE(datasets.ok()) << datasets.error().message;
  ASSERT_EQ(datasets->size(), 2u);
  const calib::Dataset& first = (*datasets)[0];  // scan_index order
  EXPECT_EQ(first.scan_index, 0);
  EXPECT_FALSE(first.validation);
  EXPECT_TRUE((*datasets)[1].validation);
  EXPECT_EQ(first.layout, calib::PoseLayout::kOnePerScan);
  EXPECT_EQ(first.rows, 3u);
  EXPECT_EQ(first.cols, 4u);
  EXPECT_EQ(first.ValidPointCount(), 11u);  // depth 0 = no measurement
  EXPECT_TRUE(std::isnan(first.z[5]));
  // Pixel (row 2, col 0): x = (0 - 1.5) * z / 2, y = (2 - 1) * z / 2.
  EXPECT_FLOAT_EQ(first.z[8], 2.0f);
  EXPECT_FLOAT_EQ(first.x[8], -1.5f);
  EXPECT_FLOAT_EQ(first.y[8], 1.0f);
  ASSERT_EQ(first.pose_joints.size(), 7u);
  for (std::size_t i = 0; i < 7; ++i)
    EXPECT_NEAR(first.pose_joints[i], Joint(i, 1.6033 + 0.004), 1e-9);
  EXPECT_DOUBLE_EQ(first.joint_latency_s, 0.004);

  // Unset in the options, the latency is the sensor file's; set, the options' wins.
  SensorConfig camera = Camera();
  camera.latency_s = 0.010;
  const auto from_file = LoadRecording(Path(), robot_, camera);
  ASSERT_TRUE(from_file.ok()) << from_file.error().message;
  EXPECT_DOUBLE_EQ((*from_file)[0].joint_latency_s, 0.010);
  for (std::size_t i = 0; i < 7; ++i)
    EXPECT_NEAR((*from_file)[0].pose_joints[i], Joint(i, 1.6033 + 0.010), 1e-9);
  const auto overridden = LoadRecording(Path(), robot_, camera, options);
  ASSERT_TRUE(overridden.ok()) << overridden.error().message;
  for (std::size_t i = 0; i < 7; ++i)
    EXPECT_NEAR((*overridden)[0].pose_joints[i], Joint(i, 1.6033 + 0.004), 1e-9);
}

TEST_F(RecordingTest, RangeScansGetOnePosePerRay) {
  WriteLidarLog();
  SensorConfig lidar;
  lidar.layout = SensorLayout::kRotatingLidar;
  const auto datasets = LoadRecording(Path(), robot_, lidar);
  ASSERT_TRUE(datasets.ok()) << datasets.error().message;
  const calib::Dataset& d = datasets->front();
  EXPECT_EQ(d.layout, calib::PoseLayout::kOnePerPoint);
  EXPECT_EQ(d.rows, 5u);  // rays
  EXPECT_EQ(d.cols, 3u);  // rotations
  // Ray 3 of rotation 1: angle -0.5 + 0.75, range 4, time 0.625 s + 3 / 57600 s.
  const std::size_t point = 3 * 3 + 1;
  EXPECT_FLOAT_EQ(d.x[point], static_cast<float>(4 * std::cos(0.25)));
  EXPECT_FLOAT_EQ(d.y[point], static_cast<float>(4 * std::sin(0.25)));
  EXPECT_TRUE(std::isnan(d.x[2 * 3 + 0]));
}

// With the joint timing kept, a LiDAR point's joints are not stored but interpolated when read,
// to the same bits as the stored ones.
TEST_F(RecordingTest, ALidarScanWithJointTimingInterpolatesItsJointsWhenRead) {
  WriteLidarLog();
  SensorConfig lidar;
  lidar.layout = SensorLayout::kRotatingLidar;
  RecordingOptions options;
  options.latency_s = 0.0123;  // between joint samples, so the joints are interpolated
  const auto stored = LoadRecording(Path(), robot_, lidar, options);
  ASSERT_TRUE(stored.ok()) << stored.error().message;
  options.joint_timing = true;
  const auto timed = LoadRecording(Path(), robot_, lidar, options);
  ASSERT_TRUE(timed.ok()) << timed.error().message;
  const calib::Dataset& a = stored->front();
  const calib::Dataset& b = timed->front();
  EXPECT_FALSE(a.HasJointTiming());
  ASSERT_TRUE(b.HasJointTiming());
  EXPECT_TRUE(b.pose_joints.empty());
  EXPECT_TRUE(b.HasJointsOfEveryPose());
  // Nor its times: a rotation's first ray and the time between rays.
  EXPECT_EQ(b.pose_utime.size(), b.cols);
  EXPECT_DOUBLE_EQ(b.PoseUtime(3 * 3 + 1), static_cast<double>(kStart) + 625000 + 3e6 / 57600);
  ASSERT_EQ(a.PoseCount(), 15u);
  for (std::size_t pose = 0; pose < a.PoseCount(); ++pose) {
    double buffer[calib::kMaxJoints];
    const double* from_timing = b.JointsOfPose(pose, buffer);
    EXPECT_EQ(from_timing, buffer);
    for (std::size_t j = 0; j < a.joint_count; ++j)
      EXPECT_EQ(from_timing[j], a.pose_joints[pose * a.joint_count + j]) << pose << " " << j;
  }
  EXPECT_NE(a.pose_joints[0], a.pose_joints[a.joint_count]) << "the joints move along the scan";
}

TEST_F(RecordingTest, LineProfilesGetOnePosePerColumn) {
  auto writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteJointStates(*writer, 0.0, 2.0, 1000);
  WriteMarker(*writer, 0.5, 1, 0);
  for (int k = 0; k < 4; ++k) WriteLineProfile(*writer, 0.6 + k * 0.002);
  WriteMarker(*writer, 0.9, 2, 0);
  ASSERT_TRUE(writer->Commit().ok());
  SensorConfig line;
  line.layout = SensorLayout::kLineScanner;
  const auto datasets = LoadRecording(Path(), robot_, line);
  ASSERT_TRUE(datasets.ok()) << datasets.error().message;
  const calib::Dataset& d = datasets->front();
  EXPECT_EQ(d.layout, calib::PoseLayout::kOnePerColumn);
  EXPECT_EQ(d.rows, 2u);
  EXPECT_EQ(d.cols, 4u);
  EXPECT_FLOAT_EQ(d.z[1 * 4 + 2], 0.6f);
  EXPECT_NEAR(d.pose_joints[2 * d.joint_count], Joint(0, 0.604), 1e-9);
}

TEST_F(RecordingTest, MeasurementsInAJointStateGapAreDroppedWithAWarning) {
  auto writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  // The arm's driver stalls for 100 ms in the middle of the scan.
  WriteJointStates(*writer, 0.0, 0.60, 1000);
  WriteJointStates(*writer, 0.70, 2.0, 1000);
  WriteMarker(*writer, 0.5, 1, 0);
  for (const double t : {0.55, 0.58, 0.66, 0.72}) WriteLineProfile(*writer, t);
  WriteMarker(*writer, 0.9, 2, 0);
  ASSERT_TRUE(writer->Commit().ok());
  SensorConfig line;
  line.layout = SensorLayout::kLineScanner;
  const auto recording = ReadRecording(Path(), robot_, line);
  ASSERT_TRUE(recording.ok()) << recording.error().message;
  const calib::Dataset& d = recording->datasets.front();
  ASSERT_EQ(d.cols, 4u);
  EXPECT_EQ(d.ValidPointCount(), 6u) << "the profile at 0.66 s is 60 ms after its last joint state";
  EXPECT_TRUE(std::isnan(d.z[0 * 4 + 2]) && std::isnan(d.z[1 * 4 + 2]));
  EXPECT_FLOAT_EQ(d.z[1 * 4 + 3], 0.6f);
  EXPECT_NEAR(d.pose_joints[3 * d.joint_count], Joint(0, 0.72), 1e-9);
  ASSERT_EQ(recording->warnings.size(), 1u);
  EXPECT_NE(recording->warnings[0].find("scan 0: 1 of 4 measurements dropped"), std::string::npos)
      << recording->warnings[0];
  EXPECT_NE(recording->warnings[0].find("are 100.000 ms apart"), std::string::npos)
      << recording->warnings[0];
}

TEST_F(RecordingTest, ErrorsNameTheScan) {
  struct Case {
    const char* name;
    std::function<void(RecordingTest&, LcmLogWriter&)> write;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"joint states stop before the scan",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 0.55, 200);
         t.WriteMarker(w, 0.5, 1, 3);
         t.WriteDepth(w, 0.6, 1000);
         t.WriteMarker(w, 0.7, 2, 3);
       },
       "scan 3: no joint state after utime"},
      {"a gap in the joint states",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 0.55, 200);
         t.WriteJointStates(w, 0.66, 1.0, 200);  // 60 ms after the frame: beyond 50 ms
         t.WriteMarker(w, 0.5, 1, 4);
         t.WriteDepth(w, 0.6, 1000);
         t.WriteMarker(w, 0.7, 2, 4);
       },
       "scan 4: joint states around utime"},
      {"wrong joint count",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 1.0, 200, 6);
         t.WriteMarker(w, 0.5, 1, 5);
         t.WriteDepth(w, 0.6, 1000);
         t.WriteMarker(w, 0.7, 2, 5);
       },
       "scan 5: joint state (event"},
      {"NaN joint values",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 1.0, 200, 7, 0.6);
         t.WriteMarker(w, 0.5, 1, 6);
         t.WriteDepth(w, 0.6, 1000);
         t.WriteMarker(w, 0.7, 2, 6);
       },
       "NaN or infinite joint positions"},
      {"no valid points",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 1.0, 200);
         t.WriteMarker(w, 0.5, 1, 7);
         t.WriteDepth(w, 0.6, 1000, true);
         t.WriteMarker(w, 0.7, 2, 7);
       },
       "scan 7: no valid points"},
      {"no frame",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 1.0, 200);
         t.WriteMarker(w, 0.5, 1, 8);
         t.WriteMarker(w, 0.7, 2, 8);
       },
       "scan 8: no depth frame"},
      {"a frame stamped after END says it came late",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 1.0, 200);
         t.WriteMarker(w, 0.5, 1, 10);
         t.WriteMarker(w, 0.7, 2, 10);
         t.WriteDepth(w, 0.7123, 1000);
       },
       "scan 10: no depth frame between its BEGIN and END markers: the nearest on "
       "SELFCAL_DEPTH_IMAGE is stamped 12.300 ms after its END (late)"},
      {"sensor messages of another layout are named",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 1.0, 200);
         t.WriteMarker(w, 0.5, 1, 11);
         t.WriteRangeScan(w, 0.6);
         t.WriteMarker(w, 0.7, 2, 11);
       },
       "scan 11: no depth frame between its BEGIN and END markers: a depth_camera sensor file "
       "reads selfcal.depth_image_t on SELFCAL_DEPTH_IMAGE or selfcal.organized_cloud_t on "
       "SELFCAL_ORGANIZED_CLOUD; the log has SELFCAL_RANGE_SCAN (selfcal.range_scan_t, 1 "
       "message)"},
      {"joint states only long before the scan",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 0.1, 200);
         t.WriteMarker(w, 0.5, 1, 12);
         t.WriteDepth(w, 0.6, 1000);
         t.WriteMarker(w, 0.7, 2, 12);
       },
       "scan 12: no joint state within 50.000 ms of any scan"},
      {"BEGIN without END",
       [](RecordingTest& t, LcmLogWriter& w) {
         t.WriteJointStates(w, 0.0, 1.0, 200);
         t.WriteMarker(w, 0.5, 1, 9);
         t.WriteDepth(w, 0.6, 1000);
       },
       "scan 9: BEGIN marker without END"},
  };
  for (const Case& c : cases) {
    std::filesystem::remove(Path());
    auto writer = LcmLogWriter::Open(Path());
    ASSERT_TRUE(writer.ok());
    c.write(*this, *writer);
    ASSERT_TRUE(writer->Commit().ok());
    const auto datasets = LoadRecording(Path(), robot_, Camera());
    ASSERT_FALSE(datasets.ok()) << c.name;
    EXPECT_NE(datasets.error().message.find(c.expected), std::string::npos)
        << c.name << ": " << datasets.error().message;
  }
  const auto missing = LoadRecording((directory_ / "absent.lcmlog").string(), robot_, Camera());
  EXPECT_FALSE(missing.ok());
}

TEST_F(RecordingTest, JointStatesMustNameTheModelsJointsInItsOrder) {
  // The model's joints reversed (A7 .. A1): the positions cannot be trusted to be in either order.
  for (auto joint = robot_.joints.rbegin(); joint != robot_.joints.rend(); ++joint)
    joint_names_.push_back(joint->name);
  auto writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteTwoCompleteScans(*writer);
  ASSERT_TRUE(writer->Commit().ok());
  const auto reversed = LoadRecording(Path(), robot_, Camera());
  ASSERT_FALSE(reversed.ok());
  EXPECT_NE(reversed.error().message.find(
                "scan 0: joint state (event 10, utime 1700000000050000) names its joints A7, A6, "
                "A5, A4, A3, A2, A1; the robot model kuka_lbr_iiwa_r840 has A1, A2, A3, A4, A5, "
                "A6, A7 (the same joints in another order)"),
            std::string::npos)
      << reversed.error().message;

  joint_names_ = {"A1", "A2", "A3", "J4", "A5", "A6", "A7"};
  std::filesystem::remove(Path());
  writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteTwoCompleteScans(*writer);
  ASSERT_TRUE(writer->Commit().ok());
  const auto foreign = LoadRecording(Path(), robot_, Camera());
  ASSERT_FALSE(foreign.ok());
  EXPECT_NE(foreign.error().message.find("names its joints A1, A2, A3, J4, A5, A6, A7; the robot "
                                         "model kuka_lbr_iiwa_r840 has A1, A2, A3, A4"),
            std::string::npos)
      << foreign.error().message;
}

TEST_F(RecordingTest, ALogCutInsideAScanIsNamedAndItsCompleteScansAreKept) {
  auto writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteTwoCompleteScans(*writer);
  WriteMarker(*writer, 0.5, 1, 2);
  WriteDepth(*writer, 0.55, 1500);
  ASSERT_TRUE(writer->Commit().ok());
  CutOff(10);  // inside the last depth frame

  const auto strict = LoadRecording(Path(), robot_, Camera());
  ASSERT_FALSE(strict.ok());
  EXPECT_NE(strict.error().message.find(
                Path() + ": the log ends early (cut off, or still being written): its last "),
            std::string::npos)
      << strict.error().message;
  EXPECT_NE(strict.error().message.find("bytes are a torn event; scan 2: BEGIN marker without END; "
                                        "2 complete scans before it"),
            std::string::npos)
      << strict.error().message;

  RecordingOptions options;
  options.allow_incomplete = true;
  const auto kept = ReadRecording(Path(), robot_, Camera(), options);
  ASSERT_TRUE(kept.ok()) << kept.error().message;
  ASSERT_EQ(kept->datasets.size(), 2u);
  EXPECT_EQ(kept->datasets[1].scan_index, 1);
  EXPECT_NE(kept->incomplete.find("scan 2: BEGIN marker without END"), std::string::npos)
      << kept->incomplete;
}

TEST_F(RecordingTest, ALogCutBetweenScansIsNamedIncomplete) {
  auto writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteTwoCompleteScans(*writer);
  WriteJointStates(*writer, 1.005, 1.005, 200);
  ASSERT_TRUE(writer->Commit().ok());
  CutOff(3);  // inside the last joint state, after the END of scan 1

  const auto strict = LoadRecording(Path(), robot_, Camera());
  ASSERT_FALSE(strict.ok());
  EXPECT_NE(strict.error().message.find("the log ends early (cut off, or still being written)"),
            std::string::npos)
      << strict.error().message;
  RecordingOptions options;
  options.allow_incomplete = true;
  const auto kept = ReadRecording(Path(), robot_, Camera(), options);
  ASSERT_TRUE(kept.ok()) << kept.error().message;
  EXPECT_EQ(kept->datasets.size(), 2u);
  EXPECT_NE(kept->incomplete.find("torn event"), std::string::npos) << kept->incomplete;

  // A complete log reads as complete.
  std::filesystem::remove(Path());
  writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteTwoCompleteScans(*writer);
  ASSERT_TRUE(writer->Commit().ok());
  const auto complete = ReadRecording(Path(), robot_, Camera());
  ASSERT_TRUE(complete.ok()) << complete.error().message;
  EXPECT_EQ(complete->incomplete, "");
  EXPECT_TRUE(complete->warnings.empty());
}

TEST_F(RecordingTest, AFileThatIsNoLcmLogIsNamedSo) {
  {
    std::ofstream text(Path());
    text << "name: kuka_lbr_iiwa_r840\njoints: []\n";
  }
  const auto datasets = LoadRecording(Path(), robot_, Camera());
  ASSERT_FALSE(datasets.ok());
  EXPECT_NE(datasets.error().message.find(Path() + ": not an LCM log"), std::string::npos)
      << datasets.error().message;
}

// The frames of the recording against the sensor file's Table I geometry (docs/formats.md).
TEST_F(RecordingTest, TheSensorFileIsCheckedAgainstTheFrames) {
  auto writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteTwoCompleteScans(*writer);  // 4 x 3 frames, fx = fy = 2, cx = 1.5, cy = 1, depth 1.5 m
  ASSERT_TRUE(writer->Commit().ok());
  SensorConfig sensor = Camera();
  sensor.name = "camera";
  sensor.resolution_x = 4;
  sensor.resolution_y = 3;
  sensor.camera.intrinsics = {2, 2, 1.5, 1};
  sensor.range_closest = 0.5;
  sensor.range_farthest = 2.0;
  const auto fitting = ReadRecording(Path(), robot_, sensor);
  ASSERT_TRUE(fitting.ok()) << fitting.error().message;
  EXPECT_TRUE(fitting->warnings.empty()) << fitting->warnings.front();

  // Twice the resolution and the same field of view: frames binned 2 x 2, said once.
  SensorConfig unbinned = sensor;
  unbinned.resolution_x = 8;
  unbinned.resolution_y = 6;
  unbinned.camera.intrinsics = {4, 4, 3.5, 2.5};
  const auto binned = ReadRecording(Path(), robot_, unbinned);
  ASSERT_TRUE(binned.ok()) << binned.error().message;
  ASSERT_EQ(binned->warnings.size(), 1u);
  EXPECT_EQ(binned->warnings[0],
            "sensor file camera is for 8 x 6 frames; the recording's are 4 x 3 (binned 2 x 2): "
            "its thresholds are used as they are");

  // Another sensor's file: not a binning of its resolution.
  SensorConfig photoneo = sensor;
  photoneo.name = "photoneo_motioncam3d";
  photoneo.resolution_x = 1120;
  photoneo.resolution_y = 800;
  const auto other = ReadRecording(Path(), robot_, photoneo);
  ASSERT_FALSE(other.ok());
  EXPECT_NE(other.error().message.find(
                "scan 0: a 4 x 3 frame, but sensor file photoneo_motioncam3d is for 1120 x 800 "
                "frames (nor a binning of them): the sensor file of another sensor?"),
            std::string::npos)
      << other.error().message;

  // Intrinsics and view range that do not fit warn.
  SensorConfig off = sensor;
  off.camera.intrinsics = {3, 2, 1.5, 1};
  off.range_farthest = 1.2;
  const auto warned = ReadRecording(Path(), robot_, off);
  ASSERT_TRUE(warned.ok()) << warned.error().message;
  ASSERT_EQ(warned->warnings.size(), 2u);
  EXPECT_EQ(warned->warnings[0],
            "scan 0: the frame's intrinsics fx 2, fy 2, cx 1.5, cy 1 differ from sensor file "
            "camera's fx 3, fy 2, cx 1.5, cy 1 by more than 10 %: the sensor file of another "
            "sensor?");
  EXPECT_EQ(warned->warnings[1],
            "100.0 % of the recording's 22 valid points lie outside sensor file camera's view "
            "range 0.5 .. 1.2 m: the sensor file of another sensor?");
}

TEST_F(RecordingTest, TheSensorFileIsCheckedAgainstTheRays) {
  auto writer = LcmLogWriter::Open(Path());
  ASSERT_TRUE(writer.ok());
  WriteJointStates(*writer, 0.0, 1.0, 1000);
  WriteMarker(*writer, 0.5, 1, 0);
  WriteRangeScan(*writer, 0.6);
  WriteRangeScan(*writer, 0.625);
  WriteMarker(*writer, 0.7, 2, 0);
  ASSERT_TRUE(writer->Commit().ok());
  SensorConfig lidar;
  lidar.name = "lidar";
  lidar.layout = SensorLayout::kRotatingLidar;
  lidar.resolution_x = 5;
  lidar.resolution_y = 1;
  lidar.range_closest = 0.1;
  lidar.range_farthest = 30;
  lidar.lidar.steps = 5;
  lidar.lidar.angle_first = -0.5;
  lidar.lidar.angle_increment = 0.25;
  const auto fitting = ReadRecording(Path(), robot_, lidar);
  ASSERT_TRUE(fitting.ok()) << fitting.error().message;
  EXPECT_TRUE(fitting->warnings.empty()) << fitting->warnings.front();

  SensorConfig other = lidar;
  other.lidar.steps = 1081;
  other.lidar.angle_first = -2.356194490192345;
  other.lidar.angle_increment = 0.004363323129985824;
  const auto warned = ReadRecording(Path(), robot_, other);
  ASSERT_TRUE(warned.ok()) << warned.error().message;
  ASSERT_EQ(warned->warnings.size(), 1u);
  EXPECT_EQ(warned->warnings[0],
            "scan 0: range scans of 5 rays from -0.5 rad in steps of 0.25 rad, but sensor file "
            "lidar has 1081 rays from -2.35619 rad in steps of 0.00436332 rad: the sensor file of "
            "another sensor?");
}

// Deviation 9 (docs/engine.md): matches to the border of a scan's coverage are rejected for line
// scanners only, where it was measured (docs/accuracy.md, wenglor-bunny).
TEST(CalibrationOptions, RejectCoverageBorderForLineScannersOnly) {
  SensorConfig sensor;
  sensor.layout = SensorLayout::kLineScanner;
  EXPECT_TRUE(CalibrationOptionsFromSensor(sensor).reject_coverage_border);
  for (SensorLayout layout : {SensorLayout::kDepthCamera, SensorLayout::kRotatingLidar}) {
    sensor.layout = layout;
    EXPECT_FALSE(CalibrationOptionsFromSensor(sensor).reject_coverage_border)
        << kSensorLayoutNames.Name(layout);
  }
}

// Deviation 24: the sensor file's strides are the engine's.
TEST(CalibrationOptions, StridesFromTheSensorFile) {
  SensorConfig sensor;
  sensor.query_stride = 2;
  sensor.coarse_stride = 8;
  const calib::CalibrationOptions options = CalibrationOptionsFromSensor(sensor);
  EXPECT_EQ(options.query_stride, 2);
  EXPECT_EQ(options.coarse_stride, 8);
}

// Deviation 16: sweeping sensors estimate their latency unless their file says otherwise; a
// depth camera does only when its file asks (a camera that scans while the arm moves).
TEST(CalibrationOptions, LatencyEstimatedByLayoutUnlessTheSensorFileSays) {
  SensorConfig sensor;
  for (SensorLayout layout : {SensorLayout::kLineScanner, SensorLayout::kRotatingLidar}) {
    sensor.layout = layout;
    sensor.estimate_latency.reset();
    EXPECT_TRUE(CalibrationOptionsFromSensor(sensor).estimate_latency)
        << kSensorLayoutNames.Name(layout);
    sensor.estimate_latency = false;
    EXPECT_FALSE(CalibrationOptionsFromSensor(sensor).estimate_latency)
        << kSensorLayoutNames.Name(layout);
  }
  sensor.layout = SensorLayout::kDepthCamera;
  sensor.estimate_latency.reset();
  EXPECT_FALSE(CalibrationOptionsFromSensor(sensor).estimate_latency);
  sensor.estimate_latency = true;
  EXPECT_TRUE(CalibrationOptionsFromSensor(sensor).estimate_latency);
}

// Deviation 17: a LiDAR calibrates its range offset unless its file says otherwise; the other
// sensors calibrate intrinsics only when their file asks.
TEST(CalibrationOptions, IntrinsicsCalibratedForLidarsUnlessTheSensorFileSays) {
  SensorConfig sensor;
  sensor.layout = SensorLayout::kRotatingLidar;
  EXPECT_EQ(CalibrationOptionsFromSensor(sensor).IntrinsicsName(), "offset");
  sensor.calibrate_intrinsics = "none";
  EXPECT_FALSE(CalibrationOptionsFromSensor(sensor).AnyIntrinsic());
  for (SensorLayout layout : {SensorLayout::kDepthCamera, SensorLayout::kLineScanner}) {
    sensor.layout = layout;
    sensor.calibrate_intrinsics.clear();
    EXPECT_FALSE(CalibrationOptionsFromSensor(sensor).AnyIntrinsic())
        << kSensorLayoutNames.Name(layout);
    sensor.calibrate_intrinsics = "offset+focal";
    const calib::CalibrationOptions asked = CalibrationOptionsFromSensor(sensor);
    EXPECT_TRUE(asked.intrinsics.offset && asked.intrinsics.focal && !asked.intrinsics.scale &&
                !asked.intrinsics.automatic)
        << kSensorLayoutNames.Name(layout);
    EXPECT_EQ(asked.IntrinsicsName(), "offset+focal");
  }
}

TEST(JointInterpolation, IsLinearAndNeedsBothNeighboursWithinTheGap) {
  calib::JointStateSeries series;
  series.joint_count = 2;
  series.utime = {1000, 2000, 100000};
  series.positions = {0.0, 1.0, 1.0, 3.0, 5.0, 5.0};
  double out[2];
  ASSERT_TRUE(calib::InterpolateJoints(series, 1250.0, 50000, out).ok());
  EXPECT_DOUBLE_EQ(out[0], 0.25);
  EXPECT_DOUBLE_EQ(out[1], 1.5);
  ASSERT_TRUE(calib::InterpolateJoints(series, 2000.0, 50000, out).ok());  // exact sample
  EXPECT_DOUBLE_EQ(out[1], 3.0);
  EXPECT_FALSE(calib::InterpolateJoints(series, 500.0, 50000, out).ok());     // nothing before
  EXPECT_FALSE(calib::InterpolateJoints(series, 100500.0, 50000, out).ok());  // nothing after
  EXPECT_FALSE(calib::InterpolateJoints(series, 60000.0, 50000, out).ok());   // 98 ms gap
}

TEST(JointInterpolation, AGapJustOverTheLimitIsPrintedWithItsDigits) {
  calib::JointStateSeries series;
  series.joint_count = 1;
  series.utime = {1000000, 1100600};
  series.positions = {0.0, 1.0};
  double out[1];
  const Status gap = calib::InterpolateJoints(series, 1050300.0, 50000, out);
  ASSERT_FALSE(gap.ok());
  EXPECT_EQ(gap.error().message,
            "joint states around utime 1050300 are 100.600 ms apart: the one before is 50.300 ms "
            "and the one after 50.300 ms from it (each must lie within 50.000 ms)");
}

}  // namespace
}  // namespace selfcal::recording
