// A recording made from the fuzz input (joint states of any count, names and values, scan
// markers in any order, sensor messages of any shape, raw events on any channel, at any times;
// the log optionally cut short) and loaded into datasets exactly as `selfcal calibrate` and the
// daemon load one: an error, or datasets whose arrays agree with their shape and whose joints
// are finite; never a crash or a hang.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "protocols/lcm_log/lcm_log.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/line_profile_t.hpp"
#include "selfcal/organized_cloud_t.hpp"
#include "selfcal/range_scan_t.hpp"
#include "selfcal/scan_marker_t.hpp"
#include "tests/fuzz/fuzz_input_file.h"

namespace {

using namespace selfcal;

struct Setup {
  RobotModel robot;
  SensorConfig sensors[3];  // rotating LiDAR, line scanner, depth camera (shrunk to 8 x 6)
};

SensorConfig Sensor(const char* file) {
  auto sensor = ReadSensorConfig(std::string(SELFCAL_SOURCE_DIR "/config/sensors/") + file);
  if (!sensor.ok()) __builtin_trap();
  return *sensor;
}

const Setup& Fixture() {
  static const Setup setup = [] {
    Setup s;
    auto model = ReadModelFile(SELFCAL_SOURCE_DIR "/config/robots/kuka_lbr_iiwa_r840.yaml");
    if (!model.ok()) __builtin_trap();
    s.robot = model->model;
    s.sensors[0] = Sensor("hokuyo_utm30lx.yaml");
    s.sensors[1] = Sensor("wenglor_mlsl236.yaml");
    s.sensors[2] = Sensor("kinect_azure_nfov_binned.yaml");
    // Small frames keep an input fast; the loader reads the shape from the messages.
    SensorConfig& camera = s.sensors[2];
    camera.resolution_x = 8;
    camera.resolution_y = 6;
    camera.camera.intrinsics.cx = 3.5;
    camera.camera.intrinsics.cy = 2.5;
    return s;
  }();
  return setup;
}

// Reads the input front to back; zeros once it is used up.
class Input {
 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool empty() const { return at_ >= size_; }
  std::uint8_t Byte() { return at_ < size_ ? data_[at_++] : 0; }
  // A length-scaled value: mostly small, sometimes the size the sensor file names.
  int Count(int nominal) {
    const std::uint8_t b = Byte();
    return b == 255 ? nominal : b % 24;
  }
  float Value(double scale) {
    const std::uint8_t b = Byte();
    if (b == 255) return std::nanf("");
    return static_cast<float>((b - 128) * scale);
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

joint_state_t JointState(Input& in, const RobotModel& robot, std::int64_t utime) {
  joint_state_t m;
  m.utime = utime;
  m.device_utime = utime;
  const std::uint8_t shape = in.Byte();
  const int n = shape < 240 ? static_cast<int>(robot.JointCount()) : shape % 9;
  m.num_joints = n;
  for (int i = 0; i < n; ++i) {
    const std::size_t j = static_cast<std::size_t>(i) % robot.JointCount();
    // Names in the model's order, reversed, or one renamed.
    const std::size_t k = shape % 7 == 1 ? robot.JointCount() - 1 - j : j;
    m.names.push_back(shape % 11 == 2 && i == 0 ? "X" : robot.joints[k].name);
    m.positions.push_back(in.Value(0.02));
    m.velocities.push_back(0);
    m.efforts.push_back(0);
  }
  return m;
}

scan_marker_t Marker(Input& in, std::int64_t utime) {
  scan_marker_t m;
  m.utime = utime;
  const std::uint8_t b = in.Byte();
  m.event = static_cast<std::int8_t>(b % 3);  // 0 is no event
  m.purpose = static_cast<std::int8_t>((b / 3) % 3);
  m.scan_index = (b / 9) % 4 - 1;
  m.plan_name = "fuzz";
  m.session_id = "s";
  return m;
}

range_scan_t RangeScan(Input& in, const SensorConfig& sensor, std::int64_t utime) {
  range_scan_t m;
  m.utime = utime;
  m.device_utime = utime;
  m.scan_counter = in.Byte();
  m.time_per_ray = sensor.lidar.rotation_rate_hz > 0
                       ? 1.0 / (sensor.lidar.rotation_rate_hz * sensor.lidar.steps_per_rotation)
                       : 0;
  m.angle_first = sensor.lidar.angle_first;
  m.angle_increment = sensor.lidar.angle_increment;
  m.num_ranges = in.Count(sensor.lidar.steps);
  for (int i = 0; i < m.num_ranges; ++i) m.ranges.push_back(std::abs(in.Value(0.05)));
  m.num_intensities = 0;
  return m;
}

line_profile_t LineProfile(Input& in, const SensorConfig& sensor, std::int64_t utime) {
  line_profile_t m;
  m.utime = utime;
  m.device_utime = utime;
  m.device_counter = in.Byte();
  m.num_points = in.Count(sensor.line.points);
  for (int i = 0; i < m.num_points; ++i) {
    m.x.push_back(in.Value(0.002));
    m.z.push_back(std::abs(in.Value(0.004)));
    m.intensity.push_back(100);
  }
  return m;
}

depth_image_t DepthImage(Input& in, const SensorConfig& sensor, std::int64_t utime) {
  depth_image_t m;
  m.utime = utime;
  m.device_utime = utime;
  m.frame_counter = in.Byte();
  const std::uint8_t shape = in.Byte();
  m.width = shape < 200 ? sensor.resolution_x : shape % 10;
  m.height = shape < 200 ? sensor.resolution_y : (shape / 10) % 10;
  m.depth_unit_m = shape % 13 == 0 ? 0 : 0.001;
  const auto& k = sensor.camera.intrinsics;
  m.fx = k.fx;
  m.fy = k.fy;
  m.cx = k.cx;
  m.cy = k.cy;
  m.num_pixels = m.width * m.height + (shape % 17 == 0 ? 1 : 0);
  for (int i = 0; i < m.num_pixels; ++i) {
    m.depth.push_back(static_cast<std::int16_t>(in.Byte() * 16));
  }
  return m;
}

organized_cloud_t OrganizedCloud(Input& in, const SensorConfig& sensor, std::int64_t utime) {
  organized_cloud_t m;
  m.utime = utime;
  m.device_utime = utime;
  m.frame_counter = in.Byte();
  const std::uint8_t shape = in.Byte();
  m.width = shape < 200 ? sensor.resolution_x : shape % 10;
  m.height = shape < 200 ? sensor.resolution_y : (shape / 10) % 10;
  m.num_points = m.width * m.height + (shape % 17 == 0 ? 1 : 0);
  for (int i = 0; i < m.num_points; ++i) {
    m.x.push_back(in.Value(0.01));
    m.y.push_back(in.Value(0.01));
    m.z.push_back(std::abs(in.Value(0.02)));
  }
  m.num_intensities = 0;
  return m;
}

void CheckDatasets(const std::vector<calib::Dataset>& datasets, const RobotModel& robot) {
  for (const calib::Dataset& d : datasets) {
    const std::size_t n = d.PointCount();
    if (d.x.size() != n || d.y.size() != n || d.z.size() != n) __builtin_trap();
    if (d.joint_count != robot.JointCount()) __builtin_trap();
    if (!d.HasJointsOfEveryPose()) __builtin_trap();
    for (const double q : d.pose_joints.empty() ? d.joint_states->positions : d.pose_joints) {
      if (!std::isfinite(q)) __builtin_trap();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const Setup& setup = Fixture();
  static const std::string path = fuzz::InputPath(".lcmlog");
  Input in(data, size);
  const std::uint8_t head = in.Byte();
  const SensorConfig& sensor = setup.sensors[head % 3];
  const bool cloud = (head / 3) % 2 == 1;  // a depth camera sends organized clouds
  recording::RecordingOptions options;
  options.max_fit_scans = (head / 6) % 3;
  const auto channel = [&](std::uint8_t which) -> const std::string& {
    static const std::string other = "OTHER";
    switch (which % 7) {
      case 0:
        return options.channels.joint_state;
      case 1:
        return options.channels.scan_marker;
      case 2:
        return options.channels.range_scan;
      case 3:
        return options.channels.line_profile;
      case 4:
        return options.channels.depth_image;
      case 5:
        return options.channels.organized_cloud;
      default:
        return other;
    }
  };
  {
    auto writer = LcmLogWriter::Open(path);
    if (!writer.ok()) __builtin_trap();
    std::int64_t utime = 1'700'000'000'000'000;
    int events = 0;
    while (!in.empty() && events++ < 4096) {
      const std::uint8_t op = in.Byte();
      utime += std::int64_t{in.Byte()} * 1000 - (op >= 0xF0 ? 200'000 : 0);  // sometimes back
      Status written = OkStatus();
      switch (op % 6) {
        case 0:
        case 1:
          written = writer->Write(options.channels.joint_state, utime,
                                  JointState(in, setup.robot, utime));
          break;
        case 2:
          written = writer->Write(options.channels.scan_marker, utime, Marker(in, utime));
          break;
        case 3:
        case 4:
          if (sensor.layout == SensorLayout::kRotatingLidar) {
            written =
                writer->Write(options.channels.range_scan, utime, RangeScan(in, sensor, utime));
          } else if (sensor.layout == SensorLayout::kLineScanner) {
            written =
                writer->Write(options.channels.line_profile, utime, LineProfile(in, sensor, utime));
          } else if (cloud) {
            written = writer->Write(options.channels.organized_cloud, utime,
                                    OrganizedCloud(in, sensor, utime));
          } else {
            written =
                writer->Write(options.channels.depth_image, utime, DepthImage(in, sensor, utime));
          }
          break;
        default: {
          // Raw bytes on any channel: messages that do not decode, or of the wrong type.
          const std::string& name = channel(in.Byte());
          std::vector<std::uint8_t> raw(in.Byte() % 48);
          for (auto& b : raw) b = in.Byte();
          written = writer->Write(name, utime, raw);
        }
      }
      if (!written.ok()) __builtin_trap();
    }
    if (!writer->Commit().ok()) __builtin_trap();
  }
  if (head >= 240) {
    // A log cut off mid-event (copied while being written, or `head -c`).
    const long cut = 1 + head % 16;
    std::FILE* file = std::fopen(path.c_str(), "rb");
    std::fseek(file, 0, SEEK_END);
    const long length = std::ftell(file);
    std::fclose(file);
    if (length > cut && truncate(path.c_str(), length - cut) != 0) __builtin_trap();
  }
  auto datasets = recording::LoadRecording(path, setup.robot, sensor, options);
  if (datasets.ok()) CheckDatasets(*datasets, setup.robot);
  return 0;
}
