// Settings of the Wenglor driver: where the vendor library is, how to reach the sensor, how to
// acquire, where to publish. Read from a YAML file (config/drivers/wenglor.yaml) and flags.
#pragma once

#include <string>

#include "core/util/enum_names.h"
#include "core/util/expected.h"
#include "protocols/lcm/channels.h"

namespace selfcal::wenglor {

// SetTriggerSource values (DLL interface description §6.1).
enum class TriggerSource { kInternal = 0, kHardwareSyncIn = 1, kEncoder = 2, kSoftware = 3 };

// The configuration's spelling of each trigger source.
inline constexpr EnumNames<TriggerSource, 4> kTriggerSourceNames{{
    {TriggerSource::kInternal, "internal"},
    {TriggerSource::kHardwareSyncIn, "sync_in"},
    {TriggerSource::kEncoder, "encoder"},
    {TriggerSource::kSoftware, "software"},
}};

struct WenglorConfig {
  // The vendor's library; tests point this at our simulator (tools/sim_wenglor).
  std::string library_path = "/usr/lib/wenglor/libEthernetScanner.so";
  std::string ip = "192.168.100.1";  // the sensor's factory address
  std::string port = "32001";        // the SDK's TCP port
  int connect_timeout_ms = 3000;     // EthernetScanner_Connect timeout and our wait for "connected"
  // Internal trigger only: no profile for this long while connected counts as a lost link.
  int data_timeout_ms = 1000;
  int reconnect_interval_ms = 1000;  // wait between reconnection attempts
  int poll_interval_us = 200;        // sleep when the library has no new profile

  // Acquisition.
  int exposure_time_us = 150;  // SetExposureTime, 26 .. 100000 us
  int line_time_us = 2000;     // SetAcquisitionLineTime [us]: 2000 us = 500 Hz
  TriggerSource trigger_source = TriggerSource::kInternal;
  int encoder_step = 1;        // SetTriggerEncoderStep, encoder trigger only
  int signal_selection = 0;    // SetSignalSelection, sent verbatim (vendor code)
  int signals_per_column = 1;  // buffer entries per column the selection produces (1 or 2)

  // Time mapping (docs/wenglor.md): bound on the drift between the sensor's line clock and the
  // host.
  double max_clock_drift_ppm = 200;

  // Publishing.
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string channel = channels::kLineProfile;
  int queue_profiles = 256;  // profiles buffered between the receive and publish threads
};

// Checks ranges and combinations; the error names the key.
Status ValidateConfig(const WenglorConfig& config);

// Reads `path` strictly (unknown keys are errors naming file and key) over the defaults.
Expected<WenglorConfig> ReadWenglorConfig(const std::string& path);
Expected<WenglorConfig> ParseWenglorConfig(const std::string& text, const std::string& name);

}  // namespace selfcal::wenglor
