// A fake libEthernetScanner.so: exports the C functions of Wenglor's EthernetScanner library
// (shared/protocols.md section 2) with the same signatures, and serves profiles of an analytic
// scene (tools/sim_wenglor/scene.h) at the configured line rate. No sockets: the "sensor" lives
// in the library, as the vendor's DLL hides its wire protocol too.
//
// Control (docs/wenglor.md): SELFCAL_SIM_WENGLOR_CONTROL names a text file, re-read when it
// changes; each line is "<id> <command> [argument]" and applies once, in id order:
//   set <key> <value>     scene (plane|box|sphere|objects|bunny), bunny_path, columns, noise_mm,
//                         connect_delay_ms, fifo_profiles, encoder_rate_hz, counter_start,
//                         speed, height, seed, scenario (a scenario file: replaces the scene,
//                         see scene.h), view (the scan of its plan to sweep)
//   disconnect            the link drops (status 0, no more data)
//   disconnecting         the link drops with status 2 ("disconnecting")
//   refuse_connect <n>    the next n connections stay "connecting" forever
//   connect_null <n>      the next n EthernetScanner_Connect calls return NULL
//   no_new_scan <ms>      no data for ms milliseconds; the profiles exposed meanwhile are lost
//   invalid_lin_data <n>  the next n profiles come back as -2
//   invalid_buffer <n>    the next n profiles come back as -3
//   unknown_code <n>      the next n profiles come back as -7 (undocumented)
//   oversize_count <n>    the next n calls report more values than the buffer holds
//   counter_jump <n>      the picture counter skips n values (no profile is lost in time)
//   counter_repeat <n>    the next n profiles repeat the previous picture counter
//   info_error <code>     the next GetInfo returns code (-1 .. -4)
//   info_garbage          the next GetInfo returns XML without <ordernumber>
//   read_error <code>     the next ReadData returns code (-1 .. -3)
//   read_mismatch         the next ReadData of a number returns it plus one
//   write_error <n>       the next n WriteData calls fail (-1)
// SELFCAL_SIM_WENGLOR_LOG names a file to which every call but the data polls is appended, one
// line each, so tests can check the connection and configuration sequence.
#include <sys/stat.h>

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/timing/host_clock.h"
#include "tools/sim_wenglor/scene.h"

namespace {

using Clock = std::chrono::steady_clock;
using selfcal::sim_wenglor::Column;
using selfcal::sim_wenglor::LineScannerScene;
using selfcal::sim_wenglor::SceneConfig;
using selfcal::timing::RealtimeUs;

constexpr int kDisconnected = 0;
constexpr int kConnecting = 1;
constexpr int kDisconnecting = 2;
constexpr int kConnected = 3;

// Settings that outlive a connection (the "sensor" and its surroundings).
struct Settings {
  SceneConfig scene;
  int connect_delay_ms = 20;
  int fifo_profiles = 2000;        // the DLL's FIFO; older profiles are dropped when it overflows
  double encoder_rate_hz = 10000;  // encoder counts per second while the scanner moves
  int counter_start = 0;
};

// One-shot faults, consumed by the calls they affect.
struct Faults {
  int refuse_connect = 0;
  int connect_null = 0;
  int invalid_lin_data = 0;
  int invalid_buffer = 0;
  int unknown_code = 0;
  int oversize_count = 0;
  int counter_jump = 0;
  int counter_repeat = 0;
  int info_error = 0;
  bool info_garbage = false;
  int read_error = 0;
  bool read_mismatch = false;
  int write_error = 0;
  bool disconnect = false;
  bool disconnecting = false;
  int no_new_scan_ms = 0;
};

struct Device {
  std::string ip, port;
  bool refused = false;
  Clock::time_point connect_time;
  int status = kConnecting;
  // Acquisition settings, as written with WriteData.
  int exposure_us = 150;
  int line_time_us = 2000;
  int trigger_source = 0;
  int encoder_step = 1;
  int signal_selection = 0;
  int amount_profiles_y = 0;
  bool acquiring = false;
  Clock::time_point start;
  std::int64_t exposed = 0;  // index of the next exposure not yet produced
  std::int64_t next = 0;     // index of the next exposure to deliver
  std::int64_t software_triggers = 0;
  std::int64_t counter_offset = 0;
  int last_counter = -1;
  Clock::time_point stall_until;
  std::vector<Column> columns;
};

struct Global {
  std::mutex mutex;
  Settings settings;
  // The scene built from settings.scene, rebuilt when a setting changes (the bunny's BVH takes a
  // while, so not per profile); null with `scene_error` when it cannot be built.
  std::unique_ptr<LineScannerScene> scene;
  bool scene_dirty = true;
  std::string scene_error;
  Faults faults;
  std::set<Device*> devices;
  long last_applied_id = 0;
  std::string control_path;
  timespec control_mtime{};
  off_t control_size = -1;
  Clock::time_point last_control_check;
};

Global& G() {
  // Never destroyed: calls may come during exit, and the scene's Embree objects must not be torn
  // down after TBB. LeakSanitizer is told, since dlclose() drops the only pointer to it.
  static Global* global = [] {
    auto* created = new Global();
#if defined(__SANITIZE_ADDRESS__)
    __lsan_ignore_object(created);
#endif
    return created;
  }();
  return *global;
}

void LogLine(const std::string& line) {
  const char* path = std::getenv("SELFCAL_SIM_WENGLOR_LOG");
  if (path == nullptr || *path == '\0') return;
  if (FILE* f = std::fopen(path, "a")) {
    std::fprintf(f, "%s\n", line.c_str());
    std::fclose(f);
  }
}

int ToInt(const std::string& text, int fallback) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  return (end == text.c_str()) ? fallback : static_cast<int>(value);
}

void ApplySetting(Global& g, const std::string& key, const std::string& value) {
  Settings& s = g.settings;
  g.scene_dirty = true;
  if (key == "scene")
    s.scene.scene = value;
  else if (key == "bunny_path")
    s.scene.bunny_path = value;
  else if (key == "columns")
    s.scene.columns = std::clamp(ToInt(value, 1280), 1, 2048);
  else if (key == "noise_mm")
    s.scene.noise_sigma = std::atof(value.c_str()) * 1e-3;
  else if (key == "speed")
    s.scene.speed = std::atof(value.c_str());
  else if (key == "height")
    s.scene.height = std::atof(value.c_str());
  else if (key == "seed")
    s.scene.seed = static_cast<std::uint64_t>(ToInt(value, 1));
  else if (key == "scenario")
    s.scene.scenario = value;
  else if (key == "view")
    s.scene.view = std::max(0, ToInt(value, 0));
  else if (key == "connect_delay_ms")
    s.connect_delay_ms = ToInt(value, 20);
  else if (key == "fifo_profiles")
    s.fifo_profiles = std::max(1, ToInt(value, 2000));
  else if (key == "encoder_rate_hz")
    s.encoder_rate_hz = std::atof(value.c_str());
  else if (key == "counter_start")
    s.counter_start = ToInt(value, 0);
  else
    LogLine("control: unknown setting " + key);
}

void ApplyCommand(Global& g, const std::string& command, const std::string& argument) {
  Faults& f = g.faults;
  const int n = ToInt(argument, 1);
  if (command == "disconnect")
    f.disconnect = true;
  else if (command == "disconnecting")
    f.disconnecting = true;
  else if (command == "refuse_connect")
    f.refuse_connect = n;
  else if (command == "connect_null")
    f.connect_null = n;
  else if (command == "no_new_scan")
    f.no_new_scan_ms = n;
  else if (command == "invalid_lin_data")
    f.invalid_lin_data = n;
  else if (command == "invalid_buffer")
    f.invalid_buffer = n;
  else if (command == "unknown_code")
    f.unknown_code = n;
  else if (command == "oversize_count")
    f.oversize_count = n;
  else if (command == "counter_jump")
    f.counter_jump = n;
  else if (command == "counter_repeat")
    f.counter_repeat = n;
  else if (command == "info_error")
    f.info_error = n;
  else if (command == "info_garbage")
    f.info_garbage = true;
  else if (command == "read_error")
    f.read_error = n;
  else if (command == "read_mismatch")
    f.read_mismatch = true;
  else if (command == "write_error")
    f.write_error = n;
  else
    LogLine("control: unknown command " + command);
}

// Re-reads the control file when it changed (at most every 2 ms); applies lines with new ids.
void CheckControl(Global& g, bool force = false) {
  const auto now = Clock::now();
  if (!force && now - g.last_control_check < std::chrono::milliseconds(2)) return;
  g.last_control_check = now;
  const char* path = std::getenv("SELFCAL_SIM_WENGLOR_CONTROL");
  if (path == nullptr || *path == '\0') return;
  struct stat info {};
  if (stat(path, &info) != 0) return;
  if (g.control_path == path && info.st_size == g.control_size &&
      info.st_mtim.tv_sec == g.control_mtime.tv_sec &&
      info.st_mtim.tv_nsec == g.control_mtime.tv_nsec) {
    return;
  }
  if (g.control_path != path) g.last_applied_id = 0;  // a new control file starts afresh
  g.control_path = path;
  g.control_size = info.st_size;
  g.control_mtime = info.st_mtim;
  std::ifstream file(path);
  std::string line;
  std::map<long, std::string> lines;
  while (std::getline(file, line)) {
    std::istringstream words(line);
    long id = 0;
    if (!(words >> id) || id <= g.last_applied_id) continue;
    const std::streamoff position = words.tellg();
    lines[id] = position < 0 ? std::string() : line.substr(static_cast<std::size_t>(position));
  }
  for (const auto& [id, rest] : lines) {
    std::istringstream words(rest);
    std::string command, a, b;
    words >> command >> a >> b;
    if (command == "set")
      ApplySetting(g, a, b);
    else
      ApplyCommand(g, command, a);
    g.last_applied_id = id;
    LogLine("control " + std::to_string(id) + " " + command + " " + a + " " + b);
  }
}

const LineScannerScene* CurrentScene(Global& g) {
  if (g.scene_dirty) {
    g.scene_dirty = false;
    auto scene = LineScannerScene::Create(g.settings.scene);
    g.scene = scene.ok() ? std::move(*scene) : nullptr;
    g.scene_error = scene.ok() ? std::string() : scene.error().message;
    if (!scene.ok()) LogLine("scene error: " + g.scene_error);
  }
  return g.scene.get();
}

bool Valid(Global& g, void* handle) {
  return handle != nullptr && g.devices.count(static_cast<Device*>(handle)) > 0;
}

void UpdateStatus(Global& g, Device& d) {
  if (g.faults.disconnect || g.faults.disconnecting) {
    for (Device* other : g.devices) {
      other->status = g.faults.disconnect ? kDisconnected : kDisconnecting;
      other->acquiring = false;
    }
    g.faults.disconnect = g.faults.disconnecting = false;
    LogLine("link dropped");
  }
  if (d.status == kConnecting && !d.refused &&
      Clock::now() - d.connect_time >= std::chrono::milliseconds(g.settings.connect_delay_ms)) {
    d.status = kConnected;
  }
}

// Number of exposures the sensor has made by now.
std::int64_t ExposuresDue(const Global& g, const Device& d) {
  if (!d.acquiring) return d.exposed;
  const double elapsed = std::chrono::duration<double>(Clock::now() - d.start).count();
  switch (d.trigger_source) {
    case 0:  // internal: one exposure per line time, the first at the start
      return static_cast<std::int64_t>(elapsed * 1e6 / d.line_time_us) + 1;
    case 2:  // encoder: one exposure per encoder_step counts
      return static_cast<std::int64_t>(elapsed * g.settings.encoder_rate_hz / d.encoder_step);
    case 3:  // software
      return d.software_triggers;
    default:  // hardware sync-in: no input wired to the simulator
      return 0;
  }
}

double ExposureTime(const Global& g, const Device& d, std::int64_t index) {
  if (d.trigger_source == 2)
    return static_cast<double>(index + 1) * d.encoder_step / g.settings.encoder_rate_hz;
  return static_cast<double>(index) * d.line_time_us * 1e-6;
}

[[maybe_unused]] std::string InfoXml(const Global& g) {
  const SceneConfig& s = g.settings.scene;
  const double half_tan = std::tan(0.5 * s.fan_angle);
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<info>\n <general>\n"
      << "  <ordernumber>MLSL236</ordernumber>\n  <serialnumber>SIM000001</serialnumber>\n"
      << "  <firmware>sim</firmware>\n </general>\n <range>\n"
      << "  <workingrange_z_start>" << s.z_start * 1e3 << "</workingrange_z_start>\n"
      << "  <measuringrange_z>" << s.z_range * 1e3 << "</measuringrange_z>\n"
      << "  <fieldwidth_x_start>" << 2e3 * s.z_start * half_tan << "</fieldwidth_x_start>\n"
      << "  <fieldwidth_x_end>" << 2e3 * (s.z_start + s.z_range) * half_tan
      << "</fieldwidth_x_end>\n"
      << "  <pixel_x_max>" << s.columns << "</pixel_x_max>\n </range>\n</info>\n";
  return xml.str();
}

const LineScannerScene* CurrentScene(Global& g);

// Applies one ASCII command; false when the sensor would reject it.
bool ApplyWrite(Global& g, Device& d, const std::string& command) {
  const std::size_t equals = command.find('=');
  const std::string name = command.substr(0, equals);
  const bool has_value = equals != std::string::npos;
  const int value = has_value ? ToInt(command.substr(equals + 1), -1) : 0;
  if (name == "SetAcquisitionStart" && !has_value) {
    CurrentScene(g);  // build the scene now (the bunny's BVH), not during the first exposures
    d.acquiring = true;
    // Realtime first: the logged start is never later than the true one, so tests that check
    // "mapped time >= exposure time" against it cannot fail by the microseconds in between.
    const std::int64_t start_realtime_us = RealtimeUs();
    d.start = Clock::now();
    d.exposed = d.next = 0;
    d.software_triggers = 0;
    d.counter_offset = g.settings.counter_start;
    d.last_counter = -1;
    LogLine("start realtime_us=" + std::to_string(start_realtime_us) +
            " line_time_us=" + std::to_string(d.line_time_us) +
            " counter_start=" + std::to_string(g.settings.counter_start));
    return true;
  }
  if (name == "SetAcquisitionStop" && !has_value) {
    d.acquiring = false;
    return true;
  }
  if (name == "SetTriggerSoftware" && !has_value) {
    if (!d.acquiring || d.trigger_source != 3) return false;
    ++d.software_triggers;
    return true;
  }
  if (name == "SetResetSettings" || name == "SetReboot") return !has_value;
  if (!has_value || value < 0) return false;
  if (name == "SetExposureTime") {
    if (value < 26 || value > 100000) return false;
    d.exposure_us = value;
  } else if (name == "SetAcquisitionLineTime") {
    if (value < 100 || value > 1000000) return false;
    d.line_time_us = value;
  } else if (name == "SetTriggerSource") {
    if (value > 3) return false;
    d.trigger_source = value;
  } else if (name == "SetTriggerEncoderStep") {
    if (value < 1) return false;
    d.encoder_step = value;
  } else if (name == "SetSignalSelection") {
    // The simulator's convention: 1 selects two signals per column, anything else one.
    d.signal_selection = value;
  } else if (name == "SetTriggerAmountProfilesY") {
    d.amount_profiles_y = value;
  } else {
    return false;
  }
  return true;
}

int WriteValue(char* out, int out_bytes, const std::string& value) {
  if (out == nullptr || out_bytes <= static_cast<int>(value.size())) return -1;
  std::memcpy(out, value.c_str(), value.size() + 1);
  return 1;
}

}  // namespace

extern "C" {

__attribute__((visibility("default"))) void* EthernetScanner_Connect(char* ip, char* port,
                                                                     int timeout_ms) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  CheckControl(g, /*force=*/true);
  LogLine(std::string("Connect ") + (ip ? ip : "(null)") + " " + (port ? port : "(null)") + " " +
          std::to_string(timeout_ms));
  if (ip == nullptr || port == nullptr) return nullptr;
  if (g.faults.connect_null > 0) {
    --g.faults.connect_null;
    return nullptr;
  }
  auto* device = new Device();
  device->ip = ip;
  device->port = port;
  device->connect_time = Clock::now();
  if (g.faults.refuse_connect > 0) {
    --g.faults.refuse_connect;
    device->refused = true;
  }
  g.devices.insert(device);
  return device;
}

__attribute__((visibility("default"))) void EthernetScanner_ConnectEx(void* handle, char* ip,
                                                                      char* port, int timeout_ms) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  LogLine("ConnectEx " + std::to_string(timeout_ms));
  if (!Valid(g, handle) || ip == nullptr || port == nullptr) return;
  auto* device = static_cast<Device*>(handle);
  device->ip = ip;
  device->port = port;
  device->status = kConnecting;
  device->connect_time = Clock::now();
}

__attribute__((visibility("default"))) void* EthernetScanner_Disconnect(void* handle) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  LogLine("Disconnect");
  if (Valid(g, handle)) {
    g.devices.erase(static_cast<Device*>(handle));
    delete static_cast<Device*>(handle);
  }
  return nullptr;
}

__attribute__((visibility("default"))) void EthernetScanner_GetConnectStatus(void* handle,
                                                                             int* status) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  if (status == nullptr) return;
  if (!Valid(g, handle)) {
    *status = kDisconnected;
    return;
  }
  CheckControl(g);
  auto& device = *static_cast<Device*>(handle);
  UpdateStatus(g, device);
  *status = device.status;
}

__attribute__((visibility("default"))) int EthernetScanner_GetXZIExtended(
    void* handle, double* x_mm, double* z_mm, int* intensity, int* peak_width, int buffer_values,
    unsigned int* encoder, unsigned char* user_io, int /*timeout_ms*/, unsigned char* /*raw*/,
    int /*raw_bytes*/, int* picture_counter) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  if (!Valid(g, handle)) return -1;
  CheckControl(g);
  Device& d = *static_cast<Device*>(handle);
  UpdateStatus(g, d);
  if (d.status != kConnected || !d.acquiring) return -1;
  const auto now = Clock::now();
  if (g.faults.no_new_scan_ms > 0) {
    d.stall_until = now + std::chrono::milliseconds(g.faults.no_new_scan_ms);
    g.faults.no_new_scan_ms = 0;
  }
  const std::int64_t due = ExposuresDue(g, d);
  d.exposed = std::max(d.exposed, due);
  if (now < d.stall_until) {
    d.next = d.exposed;  // the stalled profiles never arrive
    return -1;
  }
  if (d.next >= d.exposed) return -1;
  // The DLL's FIFO overflows: the oldest profiles are lost.
  if (d.exposed - d.next > g.settings.fifo_profiles) d.next = d.exposed - g.settings.fifo_profiles;
  const std::int64_t index = d.next++;
  if (g.faults.counter_jump > 0) {
    d.counter_offset += g.faults.counter_jump;
    g.faults.counter_jump = 0;
  }
  int counter = static_cast<int>((index + d.counter_offset) % 65536);
  if (g.faults.counter_repeat > 0 && d.last_counter >= 0) {
    --g.faults.counter_repeat;
    --d.counter_offset;  // later profiles continue from the repeated value
    counter = d.last_counter;
  }
  d.last_counter = counter;
  if (picture_counter != nullptr) *picture_counter = counter;
  const double t = ExposureTime(g, d, index);
  if (encoder != nullptr) {
    *encoder = static_cast<unsigned int>(std::llround(t * g.settings.encoder_rate_hz));
  }
  if (user_io != nullptr) *user_io = 0;
  if (g.faults.invalid_lin_data > 0) {
    --g.faults.invalid_lin_data;
    return -2;
  }
  if (g.faults.invalid_buffer > 0) {
    --g.faults.invalid_buffer;
    return -3;
  }
  if (g.faults.unknown_code > 0) {
    --g.faults.unknown_code;
    return -7;
  }
  const int signals = d.signal_selection == 1 ? 2 : 1;
  const int columns = g.settings.scene.columns;
  if (g.faults.oversize_count > 0) {
    --g.faults.oversize_count;
    return buffer_values + signals;
  }
  if (buffer_values < columns * signals) return -3;
  const LineScannerScene* scene = CurrentScene(g);
  if (scene == nullptr) return -2;  // no scene, no linearised data (the log says why)
  scene->Measure(t, static_cast<std::uint64_t>(index), d.columns);
  for (int i = 0; i < columns; ++i) {
    const Column& c = d.columns[static_cast<std::size_t>(i)];
    for (int s = 0; s < signals; ++s) {
      const int j = i * signals + s;
      // Signal 2 (a second peak) is empty in our scenes.
      const bool hit = c.hit && s == 0;
      if (x_mm != nullptr) x_mm[j] = hit ? c.x * 1e3 : 0.0;
      if (z_mm != nullptr) z_mm[j] = hit ? c.z * 1e3 : 0.0;
      if (intensity != nullptr) intensity[j] = hit ? c.intensity : 0;
      if (peak_width != nullptr) peak_width[j] = hit ? c.peak_width : 0;
    }
  }
  return columns * signals;
}

#ifndef SIM_WENGLOR_OMIT_GET_INFO  // a variant without this symbol tests the loader's error
__attribute__((visibility("default"))) int EthernetScanner_GetInfo(void* handle, char* info,
                                                                   int info_bytes, char* mode) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  CheckControl(g, /*force=*/true);
  LogLine(std::string("GetInfo ") + (mode ? mode : "(null)"));
  if (!Valid(g, handle) || info == nullptr) return -1;
  if (g.faults.info_error < 0) {
    const int code = g.faults.info_error;
    g.faults.info_error = 0;
    return code;
  }
  std::string xml = InfoXml(g);
  if (g.faults.info_garbage) {
    g.faults.info_garbage = false;
    xml = "<info><general><serialnumber>SIM</serialnumber></general></info>";
  }
  if (mode == nullptr || std::string(mode) != "xml") return -3;
  if (info_bytes <= static_cast<int>(xml.size())) return -2;
  std::memcpy(info, xml.c_str(), xml.size() + 1);
  return 0;
}
#endif

__attribute__((visibility("default"))) int EthernetScanner_GetDllFiFoState(void* handle) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  if (!Valid(g, handle)) return -1;
  const Device& d = *static_cast<Device*>(handle);
  const std::int64_t queued = std::max<std::int64_t>(0, ExposuresDue(g, d) - d.next);
  return static_cast<int>(std::min<std::int64_t>(100, queued * 100 / g.settings.fifo_profiles));
}

__attribute__((visibility("default"))) int EthernetScanner_ResetDllFiFo(void* handle) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  LogLine("ResetDllFiFo");
  if (!Valid(g, handle)) return -1;
  Device& d = *static_cast<Device*>(handle);
  d.exposed = std::max(d.exposed, ExposuresDue(g, d));
  d.next = d.exposed;
  return 0;
}

__attribute__((visibility("default"))) int EthernetScanner_WriteData(void* handle, char* buffer,
                                                                     int buffer_bytes) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  CheckControl(g, /*force=*/true);
  if (!Valid(g, handle) || buffer == nullptr || buffer_bytes <= 0) return -1;
  const std::string text(buffer, static_cast<std::size_t>(buffer_bytes));
  LogLine("WriteData " + text);
  Device& d = *static_cast<Device*>(handle);
  UpdateStatus(g, d);
  if (d.status != kConnected) return -1;
  if (g.faults.write_error > 0) {
    --g.faults.write_error;
    return -1;
  }
  // Several commands may be chained with '\r'.
  std::size_t begin = 0;
  while (begin <= text.size()) {
    std::size_t end = text.find('\r', begin);
    if (end == std::string::npos) end = text.size();
    std::string command = text.substr(begin, end - begin);
    while (!command.empty() && (command.back() == '\0' || command.back() == '\n'))
      command.pop_back();
    if (!command.empty() && !ApplyWrite(g, d, command)) return -1;
    begin = end + 1;
  }
  return 0;
}

__attribute__((visibility("default"))) int EthernetScanner_ReadData(void* handle, char* property,
                                                                    char* value, int value_bytes,
                                                                    int cache_time_ms) {
  Global& g = G();
  std::lock_guard<std::mutex> lock(g.mutex);
  CheckControl(g, /*force=*/true);
  LogLine(std::string("ReadData ") + (property ? property : "(null)") + " " +
          std::to_string(cache_time_ms));
  if (!Valid(g, handle) || property == nullptr) return -3;
  if (g.faults.read_error < 0) {
    const int code = g.faults.read_error;
    g.faults.read_error = 0;
    return code;
  }
  const Device& d = *static_cast<Device*>(handle);
  const std::string name(property);
  long number = 0;
  if (name == "ExposureTime")
    number = d.exposure_us;
  else if (name == "AcquisitionLineTime")
    number = d.line_time_us;
  else if (name == "PictureCounter")
    number = (d.next + d.counter_offset) % 65536;
  else if (name == "SystemTime")
    number = static_cast<long>(RealtimeUs());
  else if (name == "ScannerState")
    number = d.acquiring ? 1 : 0;
  else if (name == "Temperature")
    number = 35;
  else if (name == "IOState" || name == "EncoderHTL" || name == "EncoderTTL")
    number = 0;
  else
    return -3;
  if (g.faults.read_mismatch) {
    g.faults.read_mismatch = false;
    ++number;
  }
  return WriteValue(value, value_bytes, std::to_string(number));
}

__attribute__((visibility("default"))) int EthernetScanner_GetVersion(unsigned char* buffer,
                                                                      int buffer_bytes) {
  const std::string version = "selfcal-sim-wenglor 1.0";
  if (buffer == nullptr || buffer_bytes <= static_cast<int>(version.size())) return -1;
  std::memcpy(buffer, version.c_str(), version.size() + 1);
  return 0;
}

}  // extern "C"
