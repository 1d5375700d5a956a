#include "tools/sim_scip/sim_device.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "protocols/scip/block.h"
#include "protocols/scip/command_parser.h"
#include "protocols/scip/encoding.h"
#include "protocols/scip/replies.h"

namespace selfcal::sim_scip {
namespace {

constexpr int kSupportedBauds[] = {19200, 38400, 57600, 115200, 250000, 500000, 750000};

}  // namespace

SimDevice::SimDevice(SimDeviceConfig config, std::shared_ptr<RangeSource> source,
                     double power_on_us)
    : config_(std::move(config)),
      source_(std::move(source)),
      random_(config_.seed),
      power_on_us_(power_on_us),
      clock_offset_us_(config_.clock_offset_ms * 1000.0),
      serial_baud_(config_.serial_baud) {
  if (!source_) source_ = std::make_shared<PatternRangeSource>();
  motor_phase_us_ = std::uniform_real_distribution<double>(0, PeriodDeviceUs())(random_);
}

double SimDevice::DeviceUsAt(double host_us) const {
  return clock_offset_us_ + (host_us - power_on_us_) * (1.0 + config_.clock_drift_ppm * 1e-6);
}

double SimDevice::HostUsAt(double device_us) const {
  return power_on_us_ + (device_us - clock_offset_us_) / (1.0 + config_.clock_drift_ppm * 1e-6);
}

std::uint32_t SimDevice::CounterAt(double host_us) const {
  const double device_ms = std::floor(DeviceUsAt(host_us) / 1000.0);
  return static_cast<std::uint32_t>(static_cast<std::int64_t>(device_ms) & 0xFFFFFF);
}

double SimDevice::PeriodDeviceUs() const {
  return 60e6 / config_.rotation_rpm * (1.0 + config_.motor_speed_error);
}

double SimDevice::RotationStartDeviceUs(std::int64_t rotation) const {
  return motor_phase_us_ + static_cast<double>(rotation) * PeriodDeviceUs();
}

void SimDevice::ResetState() {
  laser_on_ = false;
  time_adjust_ = false;
  stream_.reset();
  line_.clear();
}

void SimDevice::PowerCycle(double power_on_us) {
  ResetState();
  incoming_.clear();
  outgoing_.clear();
  power_on_us_ = power_on_us;
  clock_offset_us_ = 0;  // the counter starts again at 0
  serial_baud_ = config_.serial_baud;
  last_due_us_ = 0;
  stalled_until_us_ = 0;
  booting_until_us_ = 0;
  motor_phase_us_ = std::uniform_real_distribution<double>(0, PeriodDeviceUs())(random_);
}

void SimDevice::PowerCycleAnswering(double now_us, double booted_us) {
  PowerCycle(now_us);  // the counter runs from the reboot on, as urg_sim's does
  booting_until_us_ = booted_us;
}

bool SimDevice::DeniedWhileBooting(const std::string& line, double now_us) {
  if (now_us >= booting_until_us_) return false;
  const auto parsed = scip::ParseCommandLine(line);
  const auto* command = std::get_if<scip::CommandLine>(&parsed);
  if (command == nullptr) return false;  // HandleLine answers the refusal
  const bool denied = command->name == scip::CommandName::kBM ||
                      command->name == scip::CommandName::kScan ||
                      (command->name == scip::CommandName::kTM && command->parameters != "1");
  if (!denied) return false;
  Reply(line, "10", "", now_us);
  return true;
}

void SimDevice::HostGone() {
  stream_.reset();
  laser_on_ = false;
  line_.clear();
  incoming_.clear();
  outgoing_.clear();
}

void SimDevice::CorruptNextScans(int count) { corrupt_scans_ += count; }
void SimDevice::StallUntil(double host_us) { stalled_until_us_ = host_us; }
void SimDevice::InjectJunk(std::string bytes, double now_us) { Enqueue(std::move(bytes), now_us); }

double SimDevice::OneWayDelay() {
  double delay = config_.latency_us;
  if (config_.latency_jitter_us > 0) {
    delay += std::uniform_real_distribution<double>(0, config_.latency_jitter_us)(random_);
  }
  return delay;
}

void SimDevice::Enqueue(std::string bytes, double ready_us) {
  double due = ready_us + OneWayDelay();
  due = std::max(due, last_due_us_);  // a byte stream never reorders
  last_due_us_ = due;
  outgoing_.push_back({due, std::move(bytes)});
}

void SimDevice::Receive(std::string_view bytes, double now_us, int line_rate) {
  if (now_us < power_on_us_ || now_us < stalled_until_us_) return;  // booting or hung
  if (serial_baud_ != 0 && line_rate != serial_baud_) {
    line_.clear();  // framing errors: the device sees garbage and drops it
    return;
  }
  for (const char c : bytes) {
    if (c == '\n' || c == '\r') {
      if (!line_.empty()) {
        // The command reaches the device's logic after the link's latency, in order.
        const double due = std::max(now_us + OneWayDelay(), last_incoming_us_);
        last_incoming_us_ = due;
        incoming_.push_back({due, line_});
      }
      line_.clear();
    } else if (line_.size() < 256) {
      line_.push_back(c);
    }
  }
}

void SimDevice::Reply(const std::string& echo, std::string_view status, const std::string& data,
                      double now_us) {
  std::string out = echo + "\n";
  scip::AppendStatusLine(out, status);
  out += data;
  out += "\n";
  Enqueue(std::move(out), now_us);
}

void SimDevice::HandleLine(const std::string& line, double now_us) {
  const auto parsed = scip::ParseCommandLine(line);
  if (const auto* refusal = std::get_if<scip::Refusal>(&parsed)) {
    return Reply(line, refusal->status, "", now_us);
  }
  const scip::CommandLine& command = std::get<scip::CommandLine>(parsed);
  if (time_adjust_ && !scip::AllowedInTimeAdjustMode(command.name)) {
    return Reply(line, "0E", "", now_us);
  }
  switch (command.name) {
    case scip::CommandName::kVV:
    case scip::CommandName::kPP:
    case scip::CommandName::kII:
      return Reply(line, "00", InfoData(command.name, now_us), now_us);
    case scip::CommandName::kBM:
      Reply(line, laser_on_ ? "02" : "00", "", now_us);
      laser_on_ = true;
      return;
    case scip::CommandName::kQT:
      stream_.reset();
      laser_on_ = false;
      return Reply(line, "00", "", now_us);
    case scip::CommandName::kRS:
    case scip::CommandName::kRT:
    case scip::CommandName::kRB:
      return HandleReset(command, now_us);
    case scip::CommandName::kTM:
      return HandleTimeCommand(command, now_us);
    case scip::CommandName::kSS:
      return HandleBaudChange(command, now_us);
    case scip::CommandName::kScan:
      return HandleScanCommand(command, now_us);
  }
}

std::string SimDevice::InfoData(scip::CommandName name, double now_us) const {
  std::string data;
  if (name == scip::CommandName::kVV) {
    scip::AppendVersion(
        data, {config_.vendor, config_.product, config_.firmware, "SCIP 2.0", config_.serial});
  } else if (name == scip::CommandName::kPP) {
    scip::AppendParameters(data, {config_.model, config_.min_range_mm, config_.max_range_mm,
                                  config_.steps_per_rotation, config_.first_step, config_.last_step,
                                  config_.front_step, config_.rotation_rpm});
  } else {
    scip::AppendInfoLine(data, "MODL", config_.model);
    scip::AppendInfoLine(data, "LASR", laser_on_ ? "ON" : "OFF");
    scip::AppendInfoLine(data, "SCSP", std::to_string(config_.rotation_rpm) + "[rpm]");
    scip::AppendInfoLine(data, "MESM", stream_ ? "Measuring by Sensitive Mode" : "Idle");
    scip::AppendInfoLine(data, "SBPS",
                         serial_baud_ ? std::to_string(serial_baud_) + "[bps]" : "USB only");
    scip::AppendInfoLine(data, "TIME", scip::EncodeValue(CounterAt(now_us), 4));
    scip::AppendInfoLine(data, "STAT", "Stable 000 no error.");
  }
  return data;
}

void SimDevice::HandleReset(const scip::CommandLine& command, double now_us) {
  const std::string line(command.text);
  if (command.name != scip::CommandName::kRB) {
    ResetState();
    // urg_sim resets the timestamp epoch on RS.
    clock_offset_us_ = 0;
    power_on_us_ = now_us;
    return Reply(line, "00", "", now_us);
  }
  // RB reboots only when it comes twice within a second.
  if (rb_armed_until_us_ >= now_us) {
    Reply(line, "00", "", now_us);
    PowerCycle(now_us + 1e6);
    rb_armed_until_us_ = -1;
  } else {
    rb_armed_until_us_ = now_us + 1e6;
    Reply(line, "01", "", now_us);
  }
}

void SimDevice::HandleTimeCommand(const scip::CommandLine& command, double now_us) {
  const std::string line(command.text);
  const auto code = scip::ParseTimeCommand(command);
  if (const auto* refusal = std::get_if<scip::Refusal>(&code)) {
    return Reply(line, refusal->status, "", now_us);
  }
  switch (std::get<scip::SimpleCommand>(code)) {
    case scip::SimpleCommand::kTM0:
      Reply(line, time_adjust_ ? "02" : "00", "", now_us);
      time_adjust_ = true;
      stream_.reset();
      laser_on_ = false;
      return;
    case scip::SimpleCommand::kTM1: {
      // Real sensors answer TM1 outside adjust mode too (urg_sim); the counter is read now.
      std::string data;
      scip::AppendDataLine(data, scip::EncodeValue(CounterAt(now_us), 4));
      return Reply(line, "00", data, now_us);
    }
    default:  // TM2
      Reply(line, time_adjust_ ? "00" : "03", "", now_us);
      time_adjust_ = false;
      return;
  }
}

void SimDevice::HandleBaudChange(const scip::CommandLine& command, double now_us) {
  const std::string line(command.text);
  const auto parsed = scip::ParseBaudChange(command);
  if (const auto* refusal = std::get_if<scip::Refusal>(&parsed)) {
    return Reply(line, refusal->status, "", now_us);
  }
  const int baud = std::get<int>(parsed);
  if (std::find(std::begin(kSupportedBauds), std::end(kSupportedBauds), baud) ==
      std::end(kSupportedBauds)) {
    return Reply(line, "02", "", now_us);
  }
  if (serial_baud_ == 0) return Reply(line, "00", "", now_us);  // USB: the rate is irrelevant
  Reply(line, baud == serial_baud_ ? "03" : "00", "", now_us);
  serial_baud_ = baud;  // the reply leaves at the old rate (already encoded)
}

void SimDevice::HandleScanCommand(const scip::CommandLine& command, double now_us) {
  const std::string line(command.text);
  const auto parsed =
      scip::ParseScanCommand(command, scip::StepRange{config_.first_step, config_.last_step});
  if (const auto* refusal = std::get_if<scip::Refusal>(&parsed)) {
    return Reply(line, refusal->status, "", now_us);
  }
  const scip::ScanEcho& echo = std::get<scip::ScanEcho>(parsed);
  const bool streaming = scip::Info(echo.request.type).streaming;
  if (!streaming && !laser_on_) return Reply(line, "10", "", now_us);
  Stream stream;
  stream.request = echo.request;
  stream.tag = echo.tag;
  stream.remaining = streaming ? echo.request.count : 1;
  // The first rotation that starts after the command arrived.
  const double device_now = DeviceUsAt(now_us);
  stream.next_rotation =
      static_cast<std::int64_t>(std::floor((device_now - motor_phase_us_) / PeriodDeviceUs())) + 1;
  if (streaming) {
    Reply(line, "00", "", now_us);
    laser_on_ = true;
  }
  stream_ = stream;
}

std::string SimDevice::BuildScan(const scip::ScanRequest& request, const std::string& echo,
                                 std::string_view status, std::int64_t rotation) {
  const scip::ScanTypeInfo& info = scip::Info(request.type);
  const double period = PeriodDeviceUs();
  const double drift = 1.0 + config_.clock_drift_ppm * 1e-6;
  ScanTruth truth;
  ScanTiming& timing = truth.timing;
  timing.device_time_us = RotationStartDeviceUs(rotation);
  timing.host_time_us = HostUsAt(timing.device_time_us);
  timing.host_us_per_step = period / config_.steps_per_rotation / drift;
  timing.timestamp_ms = static_cast<std::uint32_t>(
      static_cast<std::int64_t>(std::floor(timing.device_time_us / 1000.0)) & 0xFFFFFF);
  timing.first_step = request.start_step;
  timing.last_step = request.end_step;
  timing.front_step = config_.front_step;
  timing.steps_per_rotation = config_.steps_per_rotation;
  timing.cluster = request.cluster;
  const std::size_t values = static_cast<std::size_t>(scip::ValuesPerScan(request));
  ranges_.assign(values, 0);
  intensities_.assign(values, 0);
  source_->Ranges(timing, ranges_, intensities_);

  scip::ScanValues scan;
  scan.timestamp_ms = timing.timestamp_ms;
  scan.ranges_mm = ranges_;
  if (info.intensity) scan.intensities = intensities_;
  if (info.multi_echo) {
    // A second echo every 100th value (a pane of glass): exercises the '&' syntax.
    scan.extra_ranges.resize(values);
    scan.extra_intensities.resize(values);
    for (std::size_t i = 0; i < values; i += 100) {
      scan.extra_ranges[i] = {ranges_[i] + 500};
      scan.extra_intensities[i] = {intensities_[i] / 2};
    }
  }
  std::string out = echo + "\n";
  scip::AppendStatusLine(out, status);
  const std::size_t data_begin = out.size();
  scip::AppendScanData(out, request.type, scan);
  out += "\n";
  if (corrupt_scans_ > 0) {
    --corrupt_scans_;
    // Flip bit 0 of a payload byte (never an LF): the line's checksum no longer matches.
    std::uniform_int_distribution<std::size_t> pick(data_begin, out.size() - 2);
    std::size_t at = pick(random_);
    while (out[at] == '\n') --at;
    out[at] = static_cast<char>(out[at] ^ 0x01);
  }
  truth.echo = echo;
  if (truth_callback_) truth_callback_(truth);
  return out;
}

double SimDevice::NextScanReadyUs() const {
  if (!stream_) return std::numeric_limits<double>::infinity();
  const double ready_device =
      RotationStartDeviceUs(stream_->next_rotation) +
      (stream_->request.end_step + 1) * PeriodDeviceUs() / config_.steps_per_rotation;
  return HostUsAt(ready_device);
}

void SimDevice::EmitNextScan() {
  Stream& stream = *stream_;
  const double ready_host = NextScanReadyUs();
  const std::int64_t rotation = stream.next_rotation++;
  if (ready_host < stalled_until_us_) return;  // hung: rotations pass unsent
  if (stream.skip_left > 0) {
    --stream.skip_left;
    return;
  }
  stream.skip_left = stream.request.skip;
  const bool streaming = scip::Info(stream.request.type).streaming;
  scip::ScanRequest echoed = stream.request;
  // The echo carries the scans that remain (00 when endless).
  if (streaming && echoed.count > 0) echoed.count = stream.remaining - 1;
  std::string echo = scip::EncodeScanRequest(echoed, stream.tag).value();
  echo.pop_back();  // the LF
  Enqueue(BuildScan(stream.request, echo, streaming ? "99" : "00", rotation), ready_host);
  if (!streaming || stream.request.count > 0) {
    if (--stream.remaining <= 0) stream_.reset();
  }
}

void SimDevice::Advance(double now_us) {
  // Commands and scans in the order they happen on the device.
  while (true) {
    const double command_at =
        incoming_.empty() ? std::numeric_limits<double>::infinity() : incoming_.front().due_us;
    const double scan_at = NextScanReadyUs();
    if (std::min(command_at, scan_at) > now_us) return;
    if (command_at <= scan_at) {
      const Outgoing command = std::move(incoming_.front());
      incoming_.pop_front();
      if (command.due_us >= stalled_until_us_ &&
          !DeniedWhileBooting(command.bytes, command.due_us)) {
        HandleLine(command.bytes, command.due_us);
      }
    } else {
      EmitNextScan();
    }
  }
}

double SimDevice::NextEventUs() const {
  double next = NextScanReadyUs();
  if (!outgoing_.empty()) next = std::min(next, outgoing_.front().due_us);
  if (!incoming_.empty()) next = std::min(next, incoming_.front().due_us);
  return next;
}

void SimDevice::TakeDue(double now_us, std::string& out) {
  while (!outgoing_.empty() && outgoing_.front().due_us <= now_us) {
    if (now_us >= stalled_until_us_) out += outgoing_.front().bytes;
    outgoing_.pop_front();
  }
}

}  // namespace selfcal::sim_scip
