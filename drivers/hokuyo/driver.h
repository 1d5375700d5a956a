// The Hokuyo driver: connects (TCP, serial with bit-rate detection, or the first Hokuyo found on
// USB), identifies the sensor (VV, PP, II), maps its clock to the host's (TM), streams MD or ME,
// stamps every ray, and reconnects with backoff after a cable pull, a reboot or a stall. Scans go
// to a callback as selfcal types; only the publishing layer (publisher.h) knows LCM.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/util/expected.h"
#include "core/util/log.h"
#include "drivers/hokuyo/transport.h"
#include "protocols/scip/commands.h"
#include "protocols/scip/replies.h"

namespace selfcal::hokuyo {

struct HokuyoConfig {
  // Where the sensor is: exactly one of device, host, usb.
  std::string device;  // serial: /dev/ttyACM0, /dev/ttyS0, a pty, a udev link
  std::string host;    // Ethernet: sensor address
  int port = 10940;    // Ethernet: TCP port
  bool usb = false;    // find the first Hokuyo by USB vendor id and open its tty
  // Serial: the rate to open at (0: detect among kProbeBauds) and the rate to switch to with SS
  // once talking (0: keep). USB CDC-ACM ignores both.
  int baud = 0;
  int target_baud = 0;
  // Scan request: MD (ranges) or ME (ranges and intensities); -1 = the sensor's AMIN / AMAX.
  scip::ScanType scan_type = scip::ScanType::kMD;
  int start_step = -1;
  int end_step = -1;
  int cluster = 1;
  int skip = 0;
  // Clock: TM1 exchanges before streaming, and one every sync_interval_s while streaming
  // (0: none while streaming, for sensors that refuse TM1 then; the burst alone holds the mapping).
  int sync_exchanges = 30;
  double sync_interval_s = 0.02;
  // Timeouts and reconnection.
  double reply_timeout_s = 0.5;
  double stall_timeout_s = 0.5;  // no scan for this long: the stream is dead, reconnect
  double backoff_initial_s = 0.1;
  double backoff_max_s = 5.0;
};

// Serial rates urg_library probes (protocols.md 1.1).
inline constexpr int kProbeBauds[] = {19200, 57600, 115200, 250000, 500000, 750000};

struct RangeScan {
  std::int64_t utime = 0;          // host CLOCK_REALTIME [us] of the first ray
  double host_monotonic_us = 0;    // the same instant on CLOCK_MONOTONIC
  std::int64_t device_utime = 0;   // device timestamp [us] (its ms counter, unwrapped)
  std::int64_t scan_counter = 0;   // +1 per rotation; gaps = lost scans (also across reconnects)
  double time_per_ray = 0;         // [s] between consecutive values
  double angle_first = 0;          // [rad]
  double angle_increment = 0;      // [rad]
  std::vector<float> ranges;       // [m], NaN for error codes and out-of-range values
  std::vector<float> intensities;  // device units (ME only)
  double timing_margin_us = 0;     // half-width of the scan-phase interval (> 0 = consistent)
};

struct SensorInfo {
  scip::Version version;
  scip::Parameters parameters;
  std::string transport;
  int baud = 0;
};

struct DriverStats {
  std::atomic<std::int64_t> scans_published{0};
  std::atomic<std::int64_t> scans_dropped{0};    // scan blocks that failed to decode
  std::atomic<std::int64_t> blocks_rejected{0};  // bad checksum, junk, overlong: never used
  std::atomic<std::int64_t> lost_scans{0};       // gaps in the rotation count, outages included
  std::atomic<std::int64_t> sessions{0};
  std::atomic<std::int64_t> clock_exchanges{0};
};

class HokuyoDriver {
 public:
  using ScanCallback = std::function<void(const RangeScan&)>;
  using InfoCallback = std::function<void(const SensorInfo&)>;

  HokuyoDriver(HokuyoConfig config, ScanCallback on_scan, LogSink log = {});

  // Checks the configuration before any work (binaries report this as `error: ...`).
  static Status Validate(const HokuyoConfig& config);
  // Runs until `stop` becomes true: connect, stream, reconnect. Never returns on device errors.
  void Run(const std::atomic<bool>& stop);

  void SetInfoCallback(InfoCallback callback) { on_info_ = std::move(callback); }
  const DriverStats& stats() const { return stats_; }

 private:
  class Session;
  Expected<std::unique_ptr<Transport>> Connect(int& baud);
  void Log(LogLevel level, const std::string& message) const {
    if (log_) log_(level, message);
  }
  // For messages a faulty device or link can repeat without bound.
  void LogRepeated(LogLevel level, std::string_view kind, const std::string& message) {
    repeated_log_.Log(level, kind, message);
  }
  // How long to wait before the next connection after a session that ended with `status`.
  double NextWait(const Status& status, bool sensor_booting, double& backoff_s);

  HokuyoConfig config_;
  ScanCallback on_scan_;
  LogSink log_;
  RateLimitedLog repeated_log_;
  InfoCallback on_info_;
  DriverStats stats_;
  // The last published scan, kept across sessions so that the counter of the next session
  // continues by the rotations that passed while the link was down.
  struct LastScan {
    std::int64_t index = -1;
    double host_us = 0;         // CLOCK_MONOTONIC of its first ray
    double period_host_us = 0;  // rotation period in host time
  } last_scan_;
  double booting_since_us_ = -1;  // the first of consecutive "denied" answers (sensor booting)
};

}  // namespace selfcal::hokuyo
