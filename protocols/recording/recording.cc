#include "protocols/recording/recording.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>

#include "core/calib/joint_interpolation.h"
#include "core/camera/pinhole_intrinsics.h"
#include "protocols/lcm_log/lcm_log.h"
#include "protocols/recording/sensor_fit.h"
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
  std::size_t begin_marker = 0;  // how many markers came before its BEGIN in the log
  std::string Name() const { return "scan " + std::to_string(scan_index); }
};

struct RawJointState {
  std::int64_t utime;
  std::int64_t event_number;
  std::vector<double> positions;
  bool wrong_names;
  std::vector<std::string> names;  // the state's joint names when they are not the model's
  bool wrong_count;
  bool non_finite;
  int32_t count;
};

// What a channel of the log carries, for the error of a scan without sensor messages.
struct ChannelSummary {
  std::size_t messages = 0;
  std::string type;  // of its first message
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
  // The sensor message nearest to the window among those outside every window: how far before
  // BEGIN (negative) or after END (positive) it is stamped [us], and its channel.
  bool has_outside = false;
  std::int64_t outside_us = 0;
  std::string outside_channel;
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

std::string Milliseconds(double us) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f ms", us / 1000.0);
  return text;
}

// The LCM type of a message by its fingerprint, among the types a recording holds.
std::string TypeOf(const std::vector<std::uint8_t>& data) {
  if (data.size() < 8) return "shorter than a fingerprint";
  std::uint64_t fingerprint = 0;
  for (std::size_t i = 0; i < 8; ++i) fingerprint = (fingerprint << 8) | data[i];
  const auto hash = static_cast<std::int64_t>(fingerprint);
  if (hash == selfcal::range_scan_t::getHash()) return "selfcal.range_scan_t";
  if (hash == selfcal::line_profile_t::getHash()) return "selfcal.line_profile_t";
  if (hash == selfcal::depth_image_t::getHash()) return "selfcal.depth_image_t";
  if (hash == selfcal::organized_cloud_t::getHash()) return "selfcal.organized_cloud_t";
  if (hash == selfcal::joint_state_t::getHash()) return "selfcal.joint_state_t";
  if (hash == selfcal::scan_marker_t::getHash()) return "selfcal.scan_marker_t";
  return "a type unknown to selfcal";
}

// The messages a sensor file of `layout` reads, and on which channels.
std::string ExpectedMessages(SensorLayout layout, const RecordingOptions& options) {
  switch (layout) {
    case SensorLayout::kDepthCamera:
      return "selfcal.depth_image_t on " + options.channels.depth_image +
             " or selfcal.organized_cloud_t on " + options.channels.organized_cloud;
    case SensorLayout::kLineScanner:
      return "selfcal.line_profile_t on " + options.channels.line_profile;
    case SensorLayout::kRotatingLidar:
      return "selfcal.range_scan_t on " + options.channels.range_scan;
  }
  return "";
}

// --- Per-message converters: one LCM message -> sensor-frame points ----------------------------

Status AddMarker(const selfcal::scan_marker_t& marker, const std::string& where,
                 std::size_t markers_before, std::map<int, ScanWindow>& windows) {
  ScanWindow& window = windows[marker.scan_index];
  window.scan_index = marker.scan_index;
  const std::string name = where + ": scan " + std::to_string(marker.scan_index);
  if (marker.event == selfcal::scan_marker_t::BEGIN) {
    if (window.begin_utime >= 0) return Error{name + ": a second BEGIN marker"};
    window.begin_utime = marker.utime;
    window.begin_marker = markers_before;
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

// `names`: the model's joint names, base to tip, which a state must give in that order (as the
// daemon requires of live states): a state that names them otherwise cannot be trusted to hold
// its positions in either order.
RawJointState ToRawJointState(selfcal::joint_state_t&& state, std::int64_t event_number,
                              const std::vector<std::string>& names) {
  RawJointState raw{state.utime, event_number,    std::move(state.positions), false, {}, false,
                    false,       state.num_joints};
  raw.wrong_count = static_cast<std::size_t>(state.num_joints) != names.size();
  raw.wrong_names = state.names != names;
  if (raw.wrong_names) raw.names = std::move(state.names);
  for (double value : raw.positions) raw.non_finite |= !std::isfinite(value);
  return raw;
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& name : names) joined += (joined.empty() ? "" : ", ") + name;
  return joined;
}

// Why a state's joint names are not the model's.
std::string WrongNames(const std::vector<std::string>& state, const RobotModel& robot) {
  std::vector<std::string> model;
  for (const JointSpec& joint : robot.joints) model.push_back(joint.name);
  std::vector<std::string> sorted_state = state, sorted_model = model;
  std::sort(sorted_state.begin(), sorted_state.end());
  std::sort(sorted_model.begin(), sorted_model.end());
  return " names its joints " + (state.empty() ? std::string("not at all") : JoinNames(state)) +
         "; the robot model " + robot.name + " has " + JoinNames(model) +
         (sorted_state == sorted_model ? " (the same joints in another order)" : "") +
         ": joint states must name the model's joints, base to tip (docs/recording.md)";
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
  std::size_t markers = 0;
  std::vector<RawJointState> joint_states;
  std::map<std::string, ChannelSummary> channels;  // every channel of the log
  std::int64_t torn_bytes = 0;                     // the log's torn last event
};

Expected<MarkersAndJoints> ReadMarkersAndJoints(const std::string& path, const RobotModel& robot,
                                                const RecordingOptions& options) {
  MarkersAndJoints out;
  std::vector<std::string> names;
  for (const JointSpec& joint : robot.joints) names.push_back(joint.name);
  auto reader = LcmLogReader::Open(path);
  if (!reader) return reader.error();
  LogEvent event;
  while (reader->Next(event)) {
    ChannelSummary& channel = out.channels[event.channel];
    if (channel.messages++ == 0) channel.type = TypeOf(event.data);
    if (event.channel == options.channels.scan_marker) {
      auto marker = DecodeLcm<selfcal::scan_marker_t>(event.data, Where(*reader, event));
      if (!marker) return marker.error();
      const Status added = AddMarker(*marker, Where(*reader, event), out.markers++, out.windows);
      if (!added) return added.error();
    } else if (event.channel == options.channels.joint_state) {
      auto state = DecodeLcm<selfcal::joint_state_t>(event.data, Where(*reader, event));
      if (!state) return state.error();
      out.joint_states.push_back(ToRawJointState(std::move(*state), event.event_number, names));
    }
  }
  out.torn_bytes = reader->torn_bytes();
  return out;
}

// The open scan a log ends in: the one whose BEGIN is the log's last marker, without END.
const ScanWindow* OpenLastScan(const MarkersAndJoints& markers) {
  for (const auto& [index, window] : markers.windows) {
    if (window.end_utime < 0 && window.begin_marker + 1 == markers.markers) return &window;
  }
  return nullptr;
}

// How the log ends early, or empty: a torn last event, a last scan without END.
std::string IncompleteEnd(const std::string& path, const MarkersAndJoints& markers) {
  std::string how;
  if (markers.torn_bytes > 0) {
    how = "its last " + std::to_string(markers.torn_bytes) + " bytes are a torn event";
  }
  if (const ScanWindow* open = OpenLastScan(markers)) {
    how += (how.empty() ? "" : "; ") + open->Name() + ": BEGIN marker without END";
  }
  if (how.empty()) return how;
  std::size_t complete = 0;
  for (const auto& [index, window] : markers.windows) complete += window.end_utime >= 0;
  return path + ": the log ends early (cut off, or still being written): " + how + "; " +
         std::to_string(complete) + " complete scans before it";
}

// The complete scan windows in scan_index order, at most max_fit_scans fit scans; the open scan
// the log ends in is left out (IncompleteEnd() names it).
Expected<std::vector<ScanWindow>> ScanWindows(const std::string& path,
                                              const MarkersAndJoints& markers,
                                              const RecordingOptions& options) {
  std::vector<ScanWindow> scans;
  const ScanWindow* open_last = OpenLastScan(markers);
  for (const auto& [index, window] : markers.windows) {
    if (&window == open_last) continue;
    if (window.end_utime < 0) {
      return Error{path + ": scan " + std::to_string(index) +
                   ": BEGIN marker without END (later scans follow: not a cut-off log)"};
    }
    scans.push_back(window);
  }
  if (markers.windows.empty()) {
    return Error{path + ": no scan markers on " + options.channels.scan_marker};
  }
  if (scans.empty()) return Error{path + ": no complete scan on " + options.channels.scan_marker};
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
    if (state.wrong_names) return Error{where + WrongNames(state.names, robot)};
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

// What pass 2 fills: the messages of every scan, and the checks of them against the sensor file.
struct SensorPass {
  const SensorConfig& sensor;
  const RecordingOptions& options;
  const std::vector<ScanWindow>& scans;
  std::vector<ScanData> data;
  SensorFit fit;
};

// A sensor message stamped outside every scan: the nearest yet of each scan, for the error of a
// scan left without messages (a frame stamped after END came late).
void NoteOutside(std::int64_t utime, const std::string& channel, SensorPass& pass) {
  for (std::size_t s = 0; s < pass.scans.size(); ++s) {
    const ScanWindow& window = pass.scans[s];
    const std::int64_t offset =
        utime < window.begin_utime ? utime - window.begin_utime : utime - window.end_utime;
    ScanData& scan = pass.data[s];
    if (!scan.has_outside || std::llabs(offset) < std::llabs(scan.outside_us)) {
      scan.has_outside = true;
      scan.outside_us = offset;
      scan.outside_channel = channel;
    }
  }
}

// The scan whose window holds `utime`, or -1 after noting the message as outside.
long ScanOfMessage(std::int64_t utime, const std::string& channel, SensorPass& pass) {
  const long s = ScanOf(pass.scans, utime);
  if (s < 0) NoteOutside(utime, channel, pass);
  return s;
}

// A depth frame (image or organized cloud) at `utime` into its scan; a scan holds one frame.
// `intrinsics`: the frame's own (null for an organized cloud).
Status AddFrame(Expected<Dataset> frame, std::int64_t utime, const PinholeIntrinsics* intrinsics,
                const std::string& where, const std::string& channel, SensorPass& pass) {
  if (!frame) return frame.error();
  const long s = ScanOfMessage(utime, channel, pass);
  if (s < 0) return OkStatus();
  const std::string name = pass.scans[static_cast<std::size_t>(s)].Name();
  const Status fits = pass.fit.CheckFrame(static_cast<int>(frame->cols),
                                          static_cast<int>(frame->rows), intrinsics, name);
  if (!fits) return Error{where + ": " + fits.error().message};
  ScanData& scan = pass.data[static_cast<std::size_t>(s)];
  if (++scan.frames > 1) {
    return Error{
        where + ": " + name +
        ": more than one depth frame (a depth-camera scan is one frame, docs/recording.md)"};
  }
  scan.image = std::move(*frame);
  scan.image_utime = utime;
  return OkStatus();
}

Status AddDepthMessage(const LogEvent& event, const std::string& where, SensorPass& pass) {
  const RecordingOptions& options = pass.options;
  // One channel may carry both (the daemon records one sensor channel): the fingerprint decides.
  const bool image = event.channel == options.channels.depth_image &&
                     (event.channel != options.channels.organized_cloud ||
                      TypeOf(event.data) == "selfcal.depth_image_t");
  if (image) {
    auto message = DecodeLcm<selfcal::depth_image_t>(event.data, where);
    if (!message) return message.error();
    const PinholeIntrinsics intrinsics{message->fx, message->fy, message->cx, message->cy};
    return AddFrame(DepthImageFrame(*message, where), message->utime, &intrinsics, where,
                    event.channel, pass);
  }
  if (event.channel != options.channels.organized_cloud) return OkStatus();
  auto message = DecodeLcm<selfcal::organized_cloud_t>(event.data, where);
  if (!message) return message.error();
  const std::int64_t utime = message->utime;
  return AddFrame(OrganizedCloudFrame(std::move(*message), where), utime, nullptr, where,
                  event.channel, pass);
}

// Converts one sensor message of `sensor`'s layout into the scan whose window holds it.
Status AddSensorMessage(const LogEvent& event, const std::string& where, SensorPass& pass) {
  const RecordingOptions& options = pass.options;
  const SensorLayout layout = pass.sensor.layout;
  if (layout == SensorLayout::kDepthCamera) return AddDepthMessage(event, where, pass);
  if (layout == SensorLayout::kLineScanner && event.channel == options.channels.line_profile) {
    auto message = DecodeLcm<selfcal::line_profile_t>(event.data, where);
    if (!message) return message.error();
    const long s = ScanOfMessage(message->utime, event.channel, pass);
    if (s < 0) return OkStatus();
    pass.fit.CheckLine(message->x.size(), pass.scans[static_cast<std::size_t>(s)].Name());
    pass.data[static_cast<std::size_t>(s)].columns.push_back(
        LineProfileColumn(std::move(*message)));
    return OkStatus();
  }
  if (layout == SensorLayout::kRotatingLidar && event.channel == options.channels.range_scan) {
    auto message = DecodeLcm<selfcal::range_scan_t>(event.data, where);
    if (!message) return message.error();
    const long s = ScanOfMessage(message->utime, event.channel, pass);
    if (s < 0) return OkStatus();
    const std::string name = pass.scans[static_cast<std::size_t>(s)].Name();
    auto column = RangeScanColumn(*message, where + ": " + name);
    if (!column) return column.error();
    pass.fit.CheckRays(message->ranges.size(), message->angle_first, message->angle_increment,
                       name);
    pass.data[static_cast<std::size_t>(s)].columns.push_back(std::move(*column));
  }
  return OkStatus();
}

Status ReadSensorMessages(const std::string& path, SensorPass& pass) {
  pass.data.resize(pass.scans.size());
  auto reader = LcmLogReader::Open(path);
  if (!reader) return reader.error();
  LogEvent event;
  while (reader->Next(event)) {
    const Status added = AddSensorMessage(event, Where(*reader, event), pass);
    if (!added) return added.error();
  }
  return OkStatus();
}

// Why a scan has no sensor messages: the nearest came before BEGIN or after END, or the log has
// none of the kind the sensor file reads (another layout, other channels).
std::string WhyNoSensorMessages(const ScanData& scan, SensorLayout layout,
                                const RecordingOptions& options,
                                const std::map<std::string, ChannelSummary>& channels) {
  if (scan.has_outside) {
    return ": the nearest on " + scan.outside_channel + " is stamped " +
           Milliseconds(static_cast<double>(std::llabs(scan.outside_us))) +
           (scan.outside_us > 0 ? " after its END (late)" : " before its BEGIN (early)");
  }
  std::string found;
  for (const auto& [channel, summary] : channels) {
    if (channel == options.channels.joint_state || channel == options.channels.scan_marker)
      continue;
    found += (found.empty() ? "" : ", ") + channel + " (" + summary.type + ", " +
             std::to_string(summary.messages) +
             (summary.messages == 1 ? " message)" : " messages)");
  }
  return std::string(": a ") + kSensorLayoutNames.Name(layout) + " sensor file reads " +
         ExpectedMessages(layout, options) + "; the log has " +
         (found.empty() ? std::string("no sensor messages at all") : found);
}

// --- Assembly: a scan's messages -> one grid, and a host time per pose --------------------------

// The columns of a line scanner or LiDAR scan side by side in time order; `pose_times` gets the
// host time [us] of every pose (per column, or per point for a LiDAR, whose columns' times and
// ray periods the dataset keeps: Dataset::PoseUtime).
Status AssembleColumns(std::vector<Column>& columns, SensorLayout layout, const std::string& name,
                       Dataset& dataset, std::vector<double>& pose_times) {
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
    for (const Column& column : columns) {
      dataset.pose_utime.push_back(static_cast<double>(column.utime));
      dataset.ray_period_s.push_back(column.time_per_point_s);
    }
    pose_times.resize(n);
    for (std::size_t pose = 0; pose < n; ++pose) pose_times[pose] = dataset.PoseUtime(pose);
  }
  columns.clear();
  columns.shrink_to_fit();
  return OkStatus();
}

// The joints of every pose of `dataset`, interpolated to its time + its joint_latency_s. A
// measurement whose joint states lie further apart than max_gap_us (the arm's driver stalled) is
// dropped, with a warning, rather than placed by joints interpolated across a motion nobody
// recorded; a scan whose every measurement fell into gaps is an error.
Status InterpolatePoseJoints(Dataset& dataset, const std::vector<double>& pose_times,
                             const calib::JointStateSeries& series, std::int64_t max_gap_us,
                             const std::string& name, std::vector<std::string>& warnings) {
  if (series.size() == 0) {
    return Error{name + ": no joint state within " + Milliseconds(static_cast<double>(max_gap_us)) +
                 " of any scan"};
  }
  const std::size_t joint_count = series.joint_count;
  dataset.pose_joints.resize(pose_times.size() * joint_count);
  std::vector<bool> dropped(pose_times.size(), false);
  std::size_t dropped_count = 0;
  Status first_gap = OkStatus();
  for (std::size_t pose = 0; pose < pose_times.size(); ++pose) {
    const double utime = pose_times[pose] + dataset.joint_latency_s * 1e6;
    const std::span<double> joints(dataset.pose_joints.data() + pose * joint_count, joint_count);
    const Status status =
        calib::InterpolateJoints(series, utime, static_cast<double>(max_gap_us), joints);
    if (status) continue;
    const bool inside = utime > static_cast<double>(series.utime.front()) &&
                        utime < static_cast<double>(series.utime.back());
    if (!inside) return Error{name + ": " + status.error().message};
    if (first_gap) first_gap = status;
    dropped[pose] = true;
    ++dropped_count;
    calib::JointsAt(series, utime, joints);  // keeps the arrays dense; the points go
  }
  if (dropped_count == 0) return OkStatus();
  for (std::size_t point = 0; point < dataset.PointCount(); ++point) {
    if (!dropped[dataset.PoseOf(point)]) continue;
    dataset.x[point] = dataset.y[point] = dataset.z[point] = kNan;
  }
  if (dataset.ValidPointCount() == 0) return Error{name + ": " + first_gap.error().message};
  warnings.push_back(name + ": " + std::to_string(dropped_count) + " of " +
                     std::to_string(pose_times.size()) +
                     " measurements dropped, their joint states too far apart; the first: " +
                     first_gap.error().message);
  return OkStatus();
}

// One scan's dataset: its grid, and the joints of every pose interpolated to its time + latency.
Expected<Dataset> AssembleDataset(
    const ScanWindow& scan, ScanData& scan_data, const SensorConfig& sensor,
    const calib::JointStateSeries& series, const std::string& path, const RecordingOptions& options,
    std::int64_t max_gap_us, const std::map<std::string, ChannelSummary>& channels,
    const std::shared_ptr<const calib::JointStateSeries>& joint_states,
    std::vector<std::string>& warnings) {
  const std::string name = path + ": " + scan.Name();
  Dataset dataset;
  std::vector<double> pose_times;  // host time [us] of every pose
  if (scan_data.frames == 0 && scan_data.columns.empty()) {
    return Error{name + ": no " +
                 (sensor.layout == SensorLayout::kDepthCamera ? "depth frame" : "sensor messages") +
                 " between its BEGIN and END markers" +
                 WhyNoSensorMessages(scan_data, sensor.layout, options, channels)};
  }
  if (sensor.layout == SensorLayout::kDepthCamera) {
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
  dataset.joint_latency_s = options.latency_s.value_or(sensor.latency_s);
  dataset.recording = options.recording;
  const Status joints =
      InterpolatePoseJoints(dataset, pose_times, series, max_gap_us, name, warnings);
  if (!joints) return joints.error();
  if (joint_states == nullptr) {  // no RecordingOptions::joint_timing
    dataset.pose_utime = {};
    dataset.ray_period_s = {};
  } else {
    if (dataset.ray_period_s.empty()) dataset.pose_utime = std::move(pose_times);
    dataset.joint_states = joint_states;
    // A LiDAR point's joints follow from its time as the engine needs them (Dataset::JointsOfPose,
    // the same interpolation): not keeping them saves 7 doubles a point.
    if (dataset.layout == PoseLayout::kOnePerPoint) {
      dataset.pose_joints.clear();
      dataset.pose_joints.shrink_to_fit();
    }
  }
  return dataset;
}

}  // namespace

Expected<Recording> ReadRecording(const std::string& path, const RobotModel& robot,
                                  const SensorConfig& sensor, const RecordingOptions& options) {
  const std::int64_t max_gap_us =
      static_cast<std::int64_t>(std::llround(options.max_joint_gap_s * 1e6));
  auto markers = ReadMarkersAndJoints(path, robot, options);
  if (!markers) return markers.error();
  Recording recording;
  recording.incomplete = IncompleteEnd(path, *markers);
  if (!recording.incomplete.empty() && !options.allow_incomplete) {
    return Error{recording.incomplete};
  }
  const auto scans = ScanWindows(path, *markers, options);
  if (!scans) return scans.error();
  const auto series = JointSeries(path, markers->joint_states, *scans, robot, max_gap_us);
  if (!series) return series.error();
  std::shared_ptr<const calib::JointStateSeries> joint_states;  // kept only on request
  if (options.joint_timing) joint_states = std::make_shared<calib::JointStateSeries>(*series);
  SensorPass pass{sensor, options, *scans, {}, SensorFit(sensor)};
  if (const Status read = ReadSensorMessages(path, pass); !read) return read.error();
  recording.datasets.reserve(scans->size());
  std::vector<std::string> gap_warnings;
  for (std::size_t s = 0; s < scans->size(); ++s) {
    auto dataset = AssembleDataset((*scans)[s], pass.data[s], sensor, *series, path, options,
                                   max_gap_us, markers->channels, joint_states, gap_warnings);
    if (!dataset) return dataset.error();
    recording.datasets.push_back(std::move(*dataset));
  }
  pass.fit.CheckViewRange(recording.datasets);
  recording.warnings = pass.fit.warnings();
  recording.warnings.insert(recording.warnings.end(), gap_warnings.begin(), gap_warnings.end());
  return recording;
}

Expected<std::vector<Dataset>> LoadRecording(const std::string& path, const RobotModel& robot,
                                             const SensorConfig& sensor,
                                             const RecordingOptions& options) {
  auto recording = ReadRecording(path, robot, sensor, options);
  if (!recording) return recording.error();
  return std::move(recording->datasets);
}

calib::CalibrationOptions CalibrationOptionsFromSensor(const SensorConfig& sensor) {
  calib::CalibrationOptions options;
  options.filter_n = sensor.filter_n;
  options.filter_m = sensor.filter_m;
  options.g_min = sensor.g_min;
  options.flying_pixel_angle_deg = sensor.flying_pixel_angle_deg;
  options.d_max = sensor.d_max;
  options.f_min = sensor.f_min;
  options.query_stride = sensor.query_stride;
  options.coarse_stride = sensor.coarse_stride;
  options.epsilon = sensor.epsilon;
  options.i_max = sensor.i_max;
  options.reject_coverage_border = sensor.layout == SensorLayout::kLineScanner;  // deviation 10
  if (!sensor.border_rule.empty()) {                                             // deviation 12
    options.reject_coverage_border = sensor.border_rule != "off";
    options.surface_border = sensor.border_rule == "surface";
  }
  options.sigma_abs = sensor.sigma_abs;
  options.sigma_rel = sensor.sigma_rel;
  // Deviation 16: a sweeping sensor scans while the arm moves, so its latency against the joint
  // states moves every pose (10 mm per 20 ms at 0.5 m/s); measured on the wenglor-bunny twin
  // (docs/accuracy.md), estimating it is what brings the field error down. A depth camera's
  // stationary views cannot show it. The sensor file may say otherwise.
  options.estimate_latency =
      sensor.estimate_latency.value_or(sensor.layout != SensorLayout::kDepthCamera);
  // Deviation 17: a LiDAR's range offset is seen from many distances in every sweep, and
  // calibrating it halved the field error of the Hokuyo twins (docs/accuracy.md). Not its scale:
  // a gauge with every length free, and where a remastering keeps the lengths, 6 sweeps took the
  // twin's incidence bias for it (-0.7 to -1.0 % for 0.2 %) and worsened the result. The sensor
  // file may say otherwise (its reader checked it).
  options.ChooseIntrinsics(
      !sensor.calibrate_intrinsics.empty()
          ? sensor.calibrate_intrinsics
          : (sensor.layout == SensorLayout::kRotatingLidar ? "offset" : "none"));
  options.intrinsic_scale_sd = sensor.intrinsics_uncertainty.scale;
  options.intrinsic_offset_sd_m = sensor.intrinsics_uncertainty.offset_m;
  options.intrinsic_focal_sd = sensor.intrinsics_uncertainty.focal;
  return options;
}

void RecordingOptions::SetSensorChannel(SensorLayout layout, const std::string& channel) {
  switch (layout) {
    case SensorLayout::kRotatingLidar:
      channels.range_scan = channel;
      break;
    case SensorLayout::kLineScanner:
      channels.line_profile = channel;
      break;
    case SensorLayout::kDepthCamera:
      channels.depth_image = channel;
      channels.organized_cloud = channel;
      break;
  }
}

}  // namespace selfcal::recording
