#include "protocols/recording/recording.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/calib/joint_interpolation.h"
#include "core/camera/pinhole_intrinsics.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/line_profile_t.hpp"
#include "selfcal/organized_cloud_t.hpp"
#include "selfcal/range_scan_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal::recording {

namespace {

using calib::Dataset;
using calib::PoseLayout;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

struct ScanWindow {
  int scan_index = 0;
  bool validation = false;
  std::int64_t begin_utime = -1;
  std::int64_t end_utime = -1;
  std::string Name() const { return "scan " + std::to_string(scan_index); }
};

struct RawJointState {
  std::int64_t utime;
  std::int64_t event_number;
  std::vector<double> positions;
  bool wrong_count;
  bool non_finite;
  int32_t count;
};

// One column of a line scanner or rotating LiDAR scan, in sensor coordinates.
struct Column {
  std::int64_t utime = 0;
  double time_per_point_s = 0;  // LiDAR: time between rays; line scanner: 0
  std::vector<float> x, y, z;
};

// The sensor messages of one scan.
struct ScanData {
  std::vector<Column> columns;
  int frames = 0;
  Dataset image;  // depth camera: the one frame
  std::int64_t image_utime = 0;
};

std::string Where(const LcmLogReader& reader, const LogEvent& event) {
  return reader.path() + ": event " + std::to_string(event.event_number) + " on " + event.channel;
}

const ScanWindow* FindScan(const std::vector<ScanWindow>& scans, std::int64_t utime,
                           std::int64_t margin) {
  for (const ScanWindow& scan : scans) {
    if (utime >= scan.begin_utime - margin && utime <= scan.end_utime + margin) return &scan;
  }
  return nullptr;
}

// The scan whose window holds `utime`, or -1.
long ScanOf(const std::vector<ScanWindow>& scans, std::int64_t utime) {
  const ScanWindow* scan = FindScan(scans, utime, 0);
  return scan == nullptr ? -1 : static_cast<long>(scan - scans.data());
}

// --- Per-message converters: one LCM message -> sensor-frame points ----------------------------

Status AddMarker(const selfcal::scan_marker_t& marker, const std::string& where,
                 std::map<int, ScanWindow>& windows) {
  ScanWindow& window = windows[marker.scan_index];
  window.scan_index = marker.scan_index;
  const std::string name = where + ": scan " + std::to_string(marker.scan_index);
  if (marker.event == selfcal::scan_marker_t::BEGIN) {
    if (window.begin_utime >= 0) return Error{name + ": a second BEGIN marker"};
    window.begin_utime = marker.utime;
    window.validation = marker.purpose == selfcal::scan_marker_t::VALIDATION;
    if (marker.purpose != selfcal::scan_marker_t::FIT &&
        marker.purpose != selfcal::scan_marker_t::VALIDATION) {
      return Error{name + ": purpose " + std::to_string(marker.purpose) +
                   " is neither FIT nor VALIDATION"};
    }
  } else if (marker.event == selfcal::scan_marker_t::END) {
    if (window.begin_utime < 0) return Error{name + ": END marker before its BEGIN"};
    if (window.end_utime >= 0) return Error{name + ": a second END marker"};
    if (marker.utime < window.begin_utime) return Error{name + ": END marker before BEGIN in time"};
    window.end_utime = marker.utime;
  } else {
    return Error{name + ": marker event " + std::to_string(marker.event) +
                 " is neither BEGIN nor END"};
  }
  return OkStatus();
}

RawJointState ToRawJointState(const selfcal::joint_state_t& state, std::int64_t event_number,
                              std::size_t joint_count) {
  RawJointState raw{state.utime, event_number, state.positions, false, false, state.num_joints};
  raw.wrong_count = static_cast<std::size_t>(state.num_joints) != joint_count;
  for (double value : state.positions) raw.non_finite |= !std::isfinite(value);
  return raw;
}

// A depth image unprojected through its pinhole intrinsics; pixels without a return are NaN.
Expected<Dataset> DepthImageFrame(const selfcal::depth_image_t& message, const std::string& where) {
  if (message.width <= 0 || message.height <= 0 ||
      static_cast<long>(message.width) * message.height != message.num_pixels) {
    return Error{where + ": depth image of " + std::to_string(message.width) + " x " +
                 std::to_string(message.height) + " with " + std::to_string(message.num_pixels) +
                 " pixels"};
  }
  if (!(message.fx > 0) || !(message.fy > 0) || !(message.depth_unit_m > 0)) {
    return Error{where + ": depth image with non-positive fx, fy or depth_unit_m"};
  }
  Dataset image;
  image.rows = static_cast<std::size_t>(message.height);
  image.cols = static_cast<std::size_t>(message.width);
  const std::size_t n = image.rows * image.cols;
  image.x.assign(n, kNan);
  image.y.assign(n, kNan);
  image.z.assign(n, kNan);
  const PinholeIntrinsics k{message.fx, message.fy, message.cx, message.cy};
  for (std::size_t r = 0; r < image.rows; ++r) {
    for (std::size_t c = 0; c < image.cols; ++c) {
      const std::size_t i = r * image.cols + c;
      const auto counts = static_cast<std::uint16_t>(message.depth[i]);
      if (counts == 0) continue;
      const Eigen::Vector3d p = k.Unproject(static_cast<double>(c), static_cast<double>(r),
                                            counts * message.depth_unit_m);
      image.x[i] = static_cast<float>(p.x());
      image.y[i] = static_cast<float>(p.y());
      image.z[i] = static_cast<float>(p.z());
    }
  }
  return image;
}

// An organized cloud as it is; points with a non-finite coordinate are NaN.
Expected<Dataset> OrganizedCloudFrame(selfcal::organized_cloud_t&& message,
                                      const std::string& where) {
  if (message.width <= 0 || message.height <= 0 ||
      static_cast<long>(message.width) * message.height != message.num_points) {
    return Error{where + ": organized cloud of " + std::to_string(message.width) + " x " +
                 std::to_string(message.height) + " with " + std::to_string(message.num_points) +
                 " points"};
  }
  Dataset image;
  image.rows = static_cast<std::size_t>(message.height);
  image.cols = static_cast<std::size_t>(message.width);
  image.x = std::move(message.x);
  image.y = std::move(message.y);
  image.z = std::move(message.z);
  for (std::size_t i = 0; i < image.x.size(); ++i) {
    if (!std::isfinite(image.x[i]) || !std::isfinite(image.y[i]) || !std::isfinite(image.z[i])) {
      image.x[i] = image.y[i] = image.z[i] = kNan;
    }
  }
  return image;
}

// A line profile in the sensor's x-z plane; points with a non-finite coordinate are NaN.
Column LineProfileColumn(selfcal::line_profile_t&& message) {
  Column column;
  column.utime = message.utime;
  column.x = std::move(message.x);
  column.z = std::move(message.z);
  column.y.assign(column.x.size(), 0.0f);
  for (std::size_t i = 0; i < column.x.size(); ++i) {
    if (!std::isfinite(column.x[i]) || !std::isfinite(column.z[i]))
      column.x[i] = column.y[i] = column.z[i] = kNan;
  }
  return column;
}

// A range scan in the sensor's x-y plane, one ray per point; rays without a return are NaN.
Expected<Column> RangeScanColumn(const selfcal::range_scan_t& message, const std::string& where) {
  if (!std::isfinite(message.time_per_ray) || message.time_per_ray < 0 ||
      !std::isfinite(message.angle_first) || !std::isfinite(message.angle_increment)) {
    return Error{where + ": range scan with a non-finite or negative time_per_ray or angle"};
  }
  Column column;
  column.utime = message.utime;
  column.time_per_point_s = message.time_per_ray;
  const std::size_t n = message.ranges.size();
  column.x.assign(n, kNan);
  column.y.assign(n, kNan);
  column.z.assign(n, kNan);
  for (std::size_t i = 0; i < n; ++i) {
    const float range = message.ranges[i];
    if (!std::isfinite(range) || range <= 0.0f) continue;
    const double angle = message.angle_first + static_cast<double>(i) * message.angle_increment;
    column.x[i] = static_cast<float>(range * std::cos(angle));
    column.y[i] = static_cast<float>(range * std::sin(angle));
    column.z[i] = 0.0f;
  }
  return column;
}

// --- Pass 1: markers and joint states -----------------------------------------------------------

struct MarkersAndJoints {
  std::map<int, ScanWindow> windows;
  std::vector<RawJointState> joint_states;
};

Expected<MarkersAndJoints> ReadMarkersAndJoints(const std::string& path, std::size_t joint_count,
                                                const RecordingOptions& options) {
  MarkersAndJoints out;
  auto reader = LcmLogReader::Open(path);
  if (!reader) return reader.error();
  LogEvent event;
  while (reader->Next(event)) {
    if (event.channel == options.scan_marker_channel) {
      auto marker = DecodeLcm<selfcal::scan_marker_t>(event.data, Where(*reader, event));
      if (!marker) return marker.error();
      const Status added = AddMarker(*marker, Where(*reader, event), out.windows);
      if (!added) return added.error();
    } else if (event.channel == options.joint_state_channel) {
      auto state = DecodeLcm<selfcal::joint_state_t>(event.data, Where(*reader, event));
      if (!state) return state.error();
      out.joint_states.push_back(ToRawJointState(*state, event.event_number, joint_count));
    }
  }
  return out;
}

// The complete scan windows in scan_index order, at most max_fit_scans fit scans.
Expected<std::vector<ScanWindow>> ScanWindows(const std::string& path,
                                              const std::map<int, ScanWindow>& windows,
                                              const RecordingOptions& options) {
  std::vector<ScanWindow> scans;
  for (const auto& [index, window] : windows) {
    if (window.end_utime < 0)
      return Error{path + ": scan " + std::to_string(index) + ": BEGIN marker without END"};
    scans.push_back(window);
  }
  if (scans.empty()) return Error{path + ": no scan markers on " + options.scan_marker_channel};
  if (options.max_fit_scans > 0) {
    int fit = 0;
    std::vector<ScanWindow> kept;
    for (const ScanWindow& scan : scans) {
      if (scan.validation || fit++ < options.max_fit_scans) kept.push_back(scan);
    }
    scans = std::move(kept);
  }
  return scans;
}

// The joint states near a scan, in time order; they must be well formed (the rest is ignored).
Expected<calib::JointStateSeries> JointSeries(const std::string& path,
                                              std::vector<RawJointState>& raw_states,
                                              const std::vector<ScanWindow>& scans,
                                              const RobotModel& robot, std::int64_t max_gap_us) {
  const std::size_t joint_count = robot.JointCount();
  calib::JointStateSeries series;
  series.joint_count = joint_count;
  std::stable_sort(
      raw_states.begin(), raw_states.end(),
      [](const RawJointState& a, const RawJointState& b) { return a.utime < b.utime; });
  for (const RawJointState& state : raw_states) {
    const ScanWindow* scan = FindScan(scans, state.utime, max_gap_us);
    if (scan == nullptr) continue;
    const std::string where = path + ": " + scan->Name() + ": joint state (event " +
                              std::to_string(state.event_number) + ", utime " +
                              std::to_string(state.utime) + ")";
    if (state.wrong_count) {
      return Error{where + " has " + std::to_string(state.count) + " joints, the robot model " +
                   robot.name + " has " + std::to_string(joint_count)};
    }
    if (state.positions.size() != joint_count) {
      return Error{where + " has " + std::to_string(state.positions.size()) + " positions for " +
                   std::to_string(joint_count) + " joints"};
    }
    if (state.non_finite) return Error{where + " has NaN or infinite joint positions"};
    if (!series.utime.empty() && series.utime.back() == state.utime) continue;  // duplicate sample
    series.utime.push_back(state.utime);
    series.positions.insert(series.positions.end(), state.positions.begin(), state.positions.end());
  }
  return series;
}

// --- Pass 2: sensor messages into scans ---------------------------------------------------------

// A depth frame (image or organized cloud) at `utime` into its scan; a scan holds one frame.
Status AddFrame(Expected<Dataset> frame, std::int64_t utime, const std::string& where,
                const std::vector<ScanWindow>& scans, std::vector<ScanData>& data) {
  if (!frame) return frame.error();
  const long s = ScanOf(scans, utime);
  if (s < 0) return OkStatus();
  ScanData& scan = data[static_cast<std::size_t>(s)];
  if (++scan.frames > 1) {
    return Error{
        where + ": " + scans[static_cast<std::size_t>(s)].Name() +
        ": more than one depth frame (a depth-camera scan is one frame, docs/recording.md)"};
  }
  scan.image = std::move(*frame);
  scan.image_utime = utime;
  return OkStatus();
}

// Converts one sensor message of `sensor`'s layout into the scan whose window holds it.
Status AddSensorMessage(const LogEvent& event, const std::string& where, const SensorConfig& sensor,
                        const RecordingOptions& options, const std::vector<ScanWindow>& scans,
                        std::vector<ScanData>& data) {
  if (sensor.layout == SensorLayout::kDepthCamera && event.channel == options.depth_image_channel) {
    auto message = DecodeLcm<selfcal::depth_image_t>(event.data, where);
    if (!message) return message.error();
    return AddFrame(DepthImageFrame(*message, where), message->utime, where, scans, data);
  }
  if (sensor.layout == SensorLayout::kDepthCamera &&
      event.channel == options.organized_cloud_channel) {
    auto message = DecodeLcm<selfcal::organized_cloud_t>(event.data, where);
    if (!message) return message.error();
    const std::int64_t utime = message->utime;
    return AddFrame(OrganizedCloudFrame(std::move(*message), where), utime, where, scans, data);
  }
  if (sensor.layout == SensorLayout::kLineScanner &&
      event.channel == options.line_profile_channel) {
    auto message = DecodeLcm<selfcal::line_profile_t>(event.data, where);
    if (!message) return message.error();
    const long s = ScanOf(scans, message->utime);
    if (s >= 0)
      data[static_cast<std::size_t>(s)].columns.push_back(LineProfileColumn(std::move(*message)));
    return OkStatus();
  }
  if (sensor.layout == SensorLayout::kRotatingLidar &&
      event.channel == options.range_scan_channel) {
    auto message = DecodeLcm<selfcal::range_scan_t>(event.data, where);
    if (!message) return message.error();
    const long s = ScanOf(scans, message->utime);
    if (s < 0) return OkStatus();
    auto column =
        RangeScanColumn(*message, where + ": " + scans[static_cast<std::size_t>(s)].Name());
    if (!column) return column.error();
    data[static_cast<std::size_t>(s)].columns.push_back(std::move(*column));
  }
  return OkStatus();
}

Expected<std::vector<ScanData>> ReadSensorMessages(const std::string& path,
                                                   const SensorConfig& sensor,
                                                   const RecordingOptions& options,
                                                   const std::vector<ScanWindow>& scans) {
  std::vector<ScanData> data(scans.size());
  auto reader = LcmLogReader::Open(path);
  if (!reader) return reader.error();
  LogEvent event;
  while (reader->Next(event)) {
    const Status added =
        AddSensorMessage(event, Where(*reader, event), sensor, options, scans, data);
    if (!added) return added.error();
  }
  return data;
}

// --- Assembly: a scan's messages -> one grid, and a host time per pose --------------------------

// The columns of a line scanner or LiDAR scan side by side in time order; `pose_times` gets the
// host time [us] of every pose (per column, or per point for a LiDAR).
Status AssembleColumns(std::vector<Column>& columns, SensorLayout layout, const std::string& name,
                       Dataset& dataset, std::vector<double>& pose_times) {
  if (columns.empty())
    return Error{name + ": no sensor messages between its BEGIN and END markers"};
  std::stable_sort(columns.begin(), columns.end(),
                   [](const Column& a, const Column& b) { return a.utime < b.utime; });
  const std::size_t rows = columns.front().x.size();
  for (const Column& column : columns) {
    if (column.x.size() != rows) {
      return Error{name + ": sensor messages of " + std::to_string(rows) + " and " +
                   std::to_string(column.x.size()) + " points in one scan"};
    }
  }
  dataset.rows = rows;
  dataset.cols = columns.size();
  const std::size_t n = rows * columns.size();
  dataset.x.resize(n);
  dataset.y.resize(n);
  dataset.z.resize(n);
  for (std::size_t c = 0; c < columns.size(); ++c) {
    for (std::size_t r = 0; r < rows; ++r) {
      dataset.x[r * dataset.cols + c] = columns[c].x[r];
      dataset.y[r * dataset.cols + c] = columns[c].y[r];
      dataset.z[r * dataset.cols + c] = columns[c].z[r];
    }
  }
  if (layout == SensorLayout::kLineScanner) {
    dataset.layout = PoseLayout::kOnePerColumn;
    for (const Column& column : columns) pose_times.push_back(static_cast<double>(column.utime));
  } else {
    dataset.layout = PoseLayout::kOnePerPoint;
    pose_times.resize(n);
    for (std::size_t r = 0; r < rows; ++r) {
      for (std::size_t c = 0; c < columns.size(); ++c) {
        pose_times[r * dataset.cols + c] =
            static_cast<double>(columns[c].utime) +
            1e6 * static_cast<double>(r) * columns[c].time_per_point_s;
      }
    }
  }
  columns.clear();
  columns.shrink_to_fit();
  return OkStatus();
}

// One scan's dataset: its grid, and the joints of every pose interpolated to its time + latency.
Expected<Dataset> AssembleDataset(const ScanWindow& scan, ScanData& scan_data,
                                  const SensorConfig& sensor, const calib::JointStateSeries& series,
                                  const std::string& path, const RecordingOptions& options,
                                  std::int64_t max_gap_us) {
  const std::string name = path + ": " + scan.Name();
  Dataset dataset;
  std::vector<double> pose_times;  // host time [us] of every pose
  if (sensor.layout == SensorLayout::kDepthCamera) {
    if (scan_data.frames == 0)
      return Error{name + ": no depth frame between its BEGIN and END markers"};
    dataset = std::move(scan_data.image);
    dataset.layout = PoseLayout::kOnePerScan;
    pose_times.push_back(static_cast<double>(scan_data.image_utime));
  } else {
    const Status assembled =
        AssembleColumns(scan_data.columns, sensor.layout, name, dataset, pose_times);
    if (!assembled) return assembled.error();
  }
  dataset.scan_index = scan.scan_index;
  dataset.validation = scan.validation;
  dataset.joint_count = series.joint_count;
  if (dataset.ValidPointCount() == 0) return Error{name + ": no valid points"};
  const std::size_t joint_count = series.joint_count;
  dataset.pose_joints.resize(pose_times.size() * joint_count);
  for (std::size_t pose = 0; pose < pose_times.size(); ++pose) {
    // Poses of invalid points (LiDAR) need no joints, but interpolating them too keeps the
    // arrays dense; a gap there still means the recording lost joint states mid-scan.
    const Status status = calib::InterpolateJoints(
        series, pose_times[pose] + options.latency_s * 1e6, static_cast<double>(max_gap_us),
        std::span<double>(dataset.pose_joints.data() + pose * joint_count, joint_count));
    if (!status) return Error{name + ": " + status.error().message};
  }
  return dataset;
}

}  // namespace

Expected<std::vector<Dataset>> LoadRecording(const std::string& path, const RobotModel& robot,
                                             const SensorConfig& sensor,
                                             const RecordingOptions& options) {
  const std::int64_t max_gap_us =
      static_cast<std::int64_t>(std::llround(options.max_joint_gap_s * 1e6));
  auto markers = ReadMarkersAndJoints(path, robot.JointCount(), options);
  if (!markers) return markers.error();
  const auto scans = ScanWindows(path, markers->windows, options);
  if (!scans) return scans.error();
  const auto series = JointSeries(path, markers->joint_states, *scans, robot, max_gap_us);
  if (!series) return series.error();
  auto data = ReadSensorMessages(path, sensor, options, *scans);
  if (!data) return data.error();
  std::vector<Dataset> datasets;
  datasets.reserve(scans->size());
  for (std::size_t s = 0; s < scans->size(); ++s) {
    auto dataset =
        AssembleDataset((*scans)[s], (*data)[s], sensor, *series, path, options, max_gap_us);
    if (!dataset) return dataset.error();
    datasets.push_back(std::move(*dataset));
  }
  return datasets;
}

calib::CalibrationOptions CalibrationOptionsFromSensor(const SensorConfig& sensor) {
  calib::CalibrationOptions options;
  options.filter_n = sensor.filter_n;
  options.filter_m = sensor.filter_m;
  options.g_min = sensor.g_min;
  options.d_max = sensor.d_max;
  options.f_min = sensor.f_min;
  options.query_stride = sensor.query_stride;
  options.epsilon = sensor.epsilon;
  options.i_max = sensor.i_max;
  options.reject_coverage_border = sensor.layout == SensorLayout::kLineScanner;  // deviation 10
  return options;
}

}  // namespace selfcal::recording
