// The simulated SCIP 2.0 device: a state machine fed with the host's bytes and the host clock,
// producing the bytes to send and when. No I/O here; SimServer carries the bytes over TCP or a
// pseudo-terminal. Replies are built with the codec of protocols/scip, whose encoders the golden
// tests pin to the captures of protocols.md, so the simulator speaks them byte for byte.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "protocols/scip/command_parser.h"
#include "tools/sim_scip/range_source.h"

namespace selfcal::sim_scip {

struct SimDeviceConfig {
  // Identity: a UTM-30LX-EW with the PP reply of protocols.md 1.6.
  std::string vendor = "Hokuyo Automatic Co.,Ltd.";
  std::string product = "SOKUIKI Sensor TOP-URG UTM-30LX-EW";
  std::string firmware = "1.1.2(selfcal-sim)";
  std::string serial = "H0000001";
  std::string model = "UTM-30LX-EW";
  int min_range_mm = 23;
  int max_range_mm = 60000;
  int steps_per_rotation = 1440;
  int first_step = 0;
  int last_step = 1080;
  int front_step = 540;
  int rotation_rpm = 2400;
  // Device clock: counter = offset + (host - power-on) * (1 + drift).
  double clock_drift_ppm = 0;
  double clock_offset_ms = 0;
  // The mirror's speed servo holds the rate of the device crystal to within this fraction; the
  // motor is not phase-locked to the millisecond counter (docs/hokuyo.md).
  double motor_speed_error = 1e-3;
  // One-way link latency, each way: a command is acted on latency + U(0, jitter) after it
  // arrives, a reply or scan leaves latency + U(0, jitter) after it is ready (docs/hokuyo.md).
  double latency_us = 100;
  double latency_jitter_us = 0;
  // RS-232 emulation: the device listens at this rate only (0 = USB CDC-ACM: any rate).
  int serial_baud = 0;
  // Reboot as urg_sim's UTM model does: the link is back at once and, until booted, the device
  // answers QT, VV, PP, II and TM1 but denies TM0, TM2, BM and scan requests with 10. Off: the
  // link stays down until booted (as a UST model, or a sensor behind a switch).
  bool answers_while_booting = false;
  std::uint64_t seed = 1;
};

// What the device truly did for one scan it sent (for tests: the truth behind the timestamps).
struct ScanTruth {
  ScanTiming timing;
  std::string echo;
};

class SimDevice {
 public:
  SimDevice(SimDeviceConfig config, std::shared_ptr<RangeSource> source, double power_on_us);

  // Bytes written by the host at host time `now_us`. `line_rate` is the host's serial bit rate
  // (0 on TCP); in RS-232 mode bytes at another rate arrive as garbage and are ignored.
  void Receive(std::string_view bytes, double now_us, int line_rate = 0);
  // Generates scans that became ready by `now_us`.
  void Advance(double now_us);
  // The next time Advance or TakeDue has work (host us); +inf when idle.
  double NextEventUs() const;
  // Appends the bytes due by `now_us` to `out`.
  void TakeDue(double now_us, std::string& out);

  // Faults.
  void PowerCycle(double power_on_us);  // reboot: state and clock reset at power_on_us
  // Reboot at `now_us` that answers while booting (answers_while_booting) until `booted_us`.
  void PowerCycleAnswering(double now_us, double booted_us);
  void CorruptNextScans(int count);  // flip a data byte of each of the next scans
  void StallUntil(double host_us);   // silent (no replies, no scans) until then
  void InjectJunk(std::string bytes, double now_us);
  // The link went away (TCP close, cable pull): streaming stops, unsent bytes are lost.
  void HostGone();

  void SetTruthCallback(std::function<void(const ScanTruth&)> callback) {
    truth_callback_ = std::move(callback);
  }
  int serial_baud() const { return serial_baud_; }
  bool answers_while_booting() const { return config_.answers_while_booting; }
  bool laser_on() const { return laser_on_; }
  bool streaming() const { return stream_.has_value(); }

  // Clock model (exposed for tests).
  double DeviceUsAt(double host_us) const;
  double HostUsAt(double device_us) const;
  std::uint32_t CounterAt(double host_us) const;

 private:
  struct Stream {
    scip::ScanRequest request;
    std::string tag;
    int remaining = 0;  // scans still to send (when request.count > 0)
    int skip_left = 0;
    std::int64_t next_rotation = 0;
  };
  struct Outgoing {
    double due_us;
    std::string bytes;
  };

  // One command line, parsed by protocols/scip's command parser; one handler per command family.
  void HandleLine(const std::string& line, double now_us);
  std::string InfoData(scip::CommandName name, double now_us) const;  // VV, PP, II
  void HandleReset(const scip::CommandLine& command, double now_us);  // RS, RT, RB
  void HandleTimeCommand(const scip::CommandLine& command, double now_us);
  void HandleBaudChange(const scip::CommandLine& command, double now_us);
  void HandleScanCommand(const scip::CommandLine& command, double now_us);
  // While booting: denies what a booting UTM denies (true: answered here).
  bool DeniedWhileBooting(const std::string& line, double now_us);
  void Reply(const std::string& echo, std::string_view status, const std::string& data,
             double now_us);
  std::string BuildScan(const scip::ScanRequest& request, const std::string& echo,
                        std::string_view status, std::int64_t rotation);
  void Enqueue(std::string bytes, double ready_us);
  double OneWayDelay();
  // The stream's next scan: when its data is ready (host us), +inf when not streaming.
  double NextScanReadyUs() const;
  void EmitNextScan();
  double RotationStartDeviceUs(std::int64_t rotation) const;
  double PeriodDeviceUs() const;
  void ResetState();

  SimDeviceConfig config_;
  std::shared_ptr<RangeSource> source_;
  std::function<void(const ScanTruth&)> truth_callback_;
  std::mt19937_64 random_;
  double power_on_us_;
  double clock_offset_us_;
  double motor_phase_us_ = 0;  // device time of rotation 0
  int serial_baud_;
  bool laser_on_ = false;
  bool time_adjust_ = false;
  std::optional<Stream> stream_;
  std::string line_;
  std::deque<Outgoing> incoming_;  // command lines and when the device acts on them
  double last_incoming_us_ = 0;
  std::deque<Outgoing> outgoing_;
  double last_due_us_ = 0;
  double stalled_until_us_ = 0;
  double booting_until_us_ = 0;
  int corrupt_scans_ = 0;
  double rb_armed_until_us_ = -1;
  std::vector<std::uint32_t> ranges_, intensities_;
};

}  // namespace selfcal::sim_scip
