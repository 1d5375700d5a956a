// One Wenglor weCat3D line scanner reached through the vendor's EthernetScanner library:
// connection (non-blocking connect, status polling, timeout), configuration, info XML, profile
// reading and decoding (mm -> m), lost-profile detection, time mapping, link-loss detection.
// Library code: it never prints; it reports through the LogSink it is given.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/timing/clock_filter.h"
#include "core/timing/counter_unwrapper.h"
#include "core/util/expected.h"
#include "core/util/log.h"
#include "drivers/wenglor/ethernet_scanner_library.h"
#include "drivers/wenglor/wenglor_config.h"
#include "protocols/wenglor/scanner_info.h"

namespace selfcal::wenglor {

// One decoded profile. The arrays are allocated once (to the largest profile the library can
// deliver); only the first `num_points` entries are valid.
struct Profile {
  std::int64_t host_receive_utime = 0;  // host CLOCK_REALTIME [us] when the library handed it over
  std::int64_t utime = 0;          // host time [us] of the exposure, mapped from the device clock
  std::int64_t device_utime = -1;  // device time [us] (picture counter x line time); -1 unknown
  std::int64_t counter = 0;        // picture counter, unwrapped over this connection
  int raw_counter = 0;             // picture counter as reported (16 bit)
  std::int64_t lost_before = 0;    // profiles lost between the previous profile and this one
  bool counter_restarted = false;
  std::uint32_t encoder = 0;      // encoder count at the exposure, as reported
  std::uint8_t user_io = 0;       // user I/O state, as reported
  int num_points = 0;             // columns (signal 1 only when two signals are selected)
  std::vector<float> x;           // m, sensor frame; NaN where the column had no return
  std::vector<float> z;           // m, sensor frame; NaN where the column had no return
  std::vector<float> intensity;   // 0 .. 1023, device units
  std::vector<float> peak_width;  // px, 0 .. 31

  void Allocate(int capacity);
};

// Fills the first `columns` entries of `profile` from the library's buffers (`signals` entries per
// column, signal 1 first): mm to m; a column without return (0/0) or with a coordinate that is
// not a finite, plausible number becomes NaN. The buffers hold at least columns * signals values.
void DecodeColumns(std::span<const double> x_mm, std::span<const double> z_mm,
                   std::span<const int> intensity, std::span<const int> peak_width, int columns,
                   int signals, Profile& profile);

struct ScannerStats {
  std::int64_t profiles = 0;       // decoded and handed out
  std::int64_t lost_profiles = 0;  // from picture counter gaps
  std::int64_t counter_gaps = 0;   // number of gaps
  std::int64_t counter_restarts = 0;
  std::int64_t duplicates = 0;        // repeated counters, dropped
  std::int64_t invalid_lin_data = 0;  // GetXZIExtended -2
  std::int64_t invalid_buffer = 0;    // GetXZIExtended -3, and counts our buffer cannot hold
  std::int64_t unknown_codes = 0;     // other negative return codes
  std::int64_t connects = 0;          // successful connections (the first and every reconnection)
  std::int64_t link_losses = 0;
};

enum class PollResult {
  kProfile,    // `profile` holds a new profile
  kNoNewScan,  // nothing new yet
  kDropped,    // the library reported an invalid profile (counted in the stats); poll again
  kLinkLost,   // the connection is gone or silent: Disconnect() and Connect() again
};

class WenglorScanner {
 public:
  // Loads the library named by `config.library_path` (errors name the path and the symbol).
  static Expected<std::unique_ptr<WenglorScanner>> Create(const WenglorConfig& config,
                                                          LogSink logger = nullptr);
  ~WenglorScanner();
  WenglorScanner(const WenglorScanner&) = delete;
  WenglorScanner& operator=(const WenglorScanner&) = delete;

  // Connects (polling the status until connected or connect_timeout_ms), reads the info XML,
  // configures the acquisition, reads the settings back and starts the acquisition.
  Status Connect();
  // Stops the acquisition (best effort) and releases the connection. Safe to call twice.
  void Disconnect();
  bool connected() const { return handle_ != nullptr; }

  // Reads at most one profile into `profile` (allocated with Allocate() beforehand or here).
  PollResult Poll(Profile& profile);

  // How full the library's profile FIFO is [percent]; -1 when not connected or not reported.
  // A FIFO that keeps filling means the receive loop cannot keep up (profiles will be lost).
  int FifoFillPercent();

  // Triggers one profile (trigger_source: software).
  Status TriggerSoftware();
  // One property through EthernetScanner_ReadData (e.g. "ExposureTime").
  Expected<std::string> ReadProperty(const std::string& name);
  // Sends ASCII commands (several may be joined with '\r').
  Status WriteCommand(const std::string& command);

  const ScannerInfo& info() const { return info_; }
  const ScannerStats& stats() const { return stats_; }
  const WenglorConfig& config() const { return config_; }
  const std::string& library_version() const { return library_version_; }
  int capacity() const { return columns_capacity_; }
  // The last error of a link loss or a failed Connect(), for logs.
  const std::string& last_error() const { return last_error_; }
  void Log(LogLevel level, const std::string& message) const;

 private:
  WenglorScanner(const WenglorConfig& config, std::unique_ptr<EthernetScannerLibrary> library,
                 LogSink logger);
  Status WaitConnected();
  Status ReadInfo();
  Status Configure();
  Status CheckProperty(const std::string& name, int expected);
  int ConnectStatus();
  PollResult LinkLost(const std::string& why);
  // A profile the library flagged with `rc`: counted in `count`, and logged the first time only.
  PollResult DropFlagged(std::int64_t& count, int rc, const std::string& what);

  WenglorConfig config_;
  std::unique_ptr<EthernetScannerLibrary> library_;
  LogSink logger_;
  void* handle_ = nullptr;
  std::string endpoint_;  // "ip:port", for messages
  std::string library_version_;
  ScannerInfo info_;
  ScannerStats stats_;
  std::string last_error_;

  // Buffers handed to GetXZIExtended, allocated once.
  int columns_capacity_ = 0;
  std::vector<double> x_mm_;
  std::vector<double> z_mm_;
  std::vector<int> intensity_;
  std::vector<int> peak_width_;

  // The 16-bit picture counter: one count per exposure, so a gap is lost profiles; it steps
  // back only when the sensor restarted counting.
  timing::CounterUnwrapper counter_;
  timing::ClockFilter clock_;
  std::chrono::steady_clock::time_point last_profile_time_;
  std::chrono::steady_clock::time_point last_status_check_;
};

}  // namespace selfcal::wenglor
