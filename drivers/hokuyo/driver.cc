#include "drivers/hokuyo/driver.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <thread>

#include "core/timing/clock_jump.h"
#include "core/timing/counter_unwrapper.h"
#include "core/timing/exchange_clock_filter.h"
#include "core/timing/host_clock.h"
#include "drivers/hokuyo/scan_timer.h"
#include "drivers/hokuyo/usb_discovery.h"
#include "protocols/scip/block.h"
#include "protocols/scip/units.h"

namespace selfcal::hokuyo {
namespace {

using std::chrono::microseconds;
using timing::MonotonicUs;
using timing::RealtimeMinusMonotonicUs;

using scip::SimpleCommand;

// A command without tag: never fails to encode.
std::string Encode(SimpleCommand command) { return scip::EncodeSimple(command).value(); }

// A sensor that is still booting answers "denied" (10) to TM0 and BM for a few seconds (urg_sim's
// UTM model; real UTMs accept the connection before they are ready). Ask again at this short
// step instead of waiting out a backoff grown while the sensor was away; after kBootWaitMaxS of
// such answers they count as a failure like any other.
constexpr double kBootRetryS = 0.1;
constexpr double kBootWaitMaxS = 30.0;

}  // namespace

// One connection's conversation: handshake, clock sync, streaming. Any error ends it.
class HokuyoDriver::Session {
 public:
  Session(HokuyoDriver& driver, Transport& transport)
      : driver_(driver), config_(driver.config_), transport_(transport) {}

  Status Handshake(SensorInfo& info);
  Status Stream(const std::atomic<bool>& stop, const SensorInfo& info);
  // Whether the session ended because the sensor denied a command in its current state.
  bool sensor_booting() const { return sensor_booting_; }

  // Sends `command` and returns the block whose echo matches it; other blocks are skipped.
  Expected<scip::Block> Command(const std::string& command, double timeout_s,
                                const std::atomic<bool>* stop = nullptr);

 private:
  // Reads until a block is available; nullopt on timeout.
  Expected<std::optional<scip::Block>> NextBlock(double deadline_us);
  Status SyncBurst();
  // The refusal in `block`, as the error that ends a session; a "denied" is noted.
  Status Accept(const scip::Block& block);
  void OnTimeReply(const scip::Block& block, double receive_us);
  // Publishes one scan. An error drops the scan; a clock jump ends the session.
  Expected<timing::ClockJump> OnScan(const scip::Block& block, const scip::ScanEcho& echo,
                                     const SensorInfo& info, double receive_us);

  HokuyoDriver& driver_;
  const HokuyoConfig& config_;
  Transport& transport_;
  scip::BlockFramer framer_;
  char buffer_[16384];
  // The 24-bit millisecond counter (wraps every 4.66 h), read by TM1 and in scans: the two
  // interleave out of order, so a step back is followed, not taken for a restart.
  timing::CounterUnwrapper unwrapper_{
      timing::CounterOptions::Bits(24, timing::CounterOptions::Backwards::kFollow)};
  timing::ExchangeClockFilter clock_;
  std::optional<ScanTimer> timer_;
  // Outstanding TM1 commands by tag ("TM1;<n>", echoed back by the sensor): a reply is matched
  // to its own send time even when replies are late or lost, so no interval is ever wrong.
  std::array<double, 64> tm1_sent_us_{};
  std::uint64_t tm1_next_ = 0;
  std::string SendTm1Command();
  scip::ScanData scan_data_;
  RangeScan scan_;
  std::int64_t counter_base_ = 0;
  std::int64_t last_index_ = -1;
  std::int64_t last_scan_ms_ = 0;
  bool sensor_booting_ = false;
};

Status HokuyoDriver::Session::Accept(const scip::Block& block) {
  const auto refusal = scip::RefusalOf(block);
  if (!refusal) return OkStatus();
  if (refusal->kind == scip::StatusKind::kDenied) sensor_booting_ = true;
  return Error{refusal->Describe()};
}

Expected<std::optional<scip::Block>> HokuyoDriver::Session::NextBlock(double deadline_us) {
  while (true) {
    while (auto block = framer_.Next()) {
      if (block->ok()) return std::optional<scip::Block>(std::move(**block));
      driver_.stats_.blocks_rejected.fetch_add(1);
      driver_.LogRepeated(LogLevel::kWarning, "rejected block",
                          transport_.Describe() + ": " + block->error().message);
    }
    const double now = MonotonicUs();
    if (now >= deadline_us) return std::optional<scip::Block>();
    auto n = transport_.Read(buffer_, sizeof(buffer_),
                             microseconds(static_cast<std::int64_t>(deadline_us - now)));
    if (!n) return n.error();
    framer_.Append(std::string_view(buffer_, *n));
  }
}

Expected<scip::Block> HokuyoDriver::Session::Command(const std::string& command, double timeout_s,
                                                     const std::atomic<bool>* stop) {
  const std::string echo(scip::EchoOf(command));
  if (auto status = transport_.Write(command); !status) return status.error();
  const double deadline = MonotonicUs() + timeout_s * 1e6;
  while (true) {
    if (stop && stop->load()) return Error{"stopped"};
    auto block = NextBlock(deadline);
    if (!block) return block.error();
    if (!block->has_value()) {
      return Error{"no reply to " + echo + " within " + std::to_string(timeout_s) + " s"};
    }
    if ((*block)->echo == echo) return std::move(**block);
  }
}

Status HokuyoDriver::Session::Handshake(SensorInfo& info) {
  // Stop whatever the sensor was doing; a sensor left in time-adjust mode answers 0E: TM2.
  auto qt = Command(Encode(SimpleCommand::kQT), config_.reply_timeout_s);
  if (!qt) return qt.error();
  if (auto refusal = scip::RefusalOf(*qt);
      refusal && refusal->kind == scip::StatusKind::kTimeAdjustMode) {
    auto tm2 = Command(Encode(SimpleCommand::kTM2), config_.reply_timeout_s);
    if (!tm2) return tm2.error();
    qt = Command(Encode(SimpleCommand::kQT), config_.reply_timeout_s);
    if (!qt) return qt.error();
  }
  if (auto status = Accept(*qt); !status) return status;
  auto vv = Command(Encode(SimpleCommand::kVV), config_.reply_timeout_s);
  if (!vv) return vv.error();
  auto version = scip::DecodeVersion(*vv);
  if (!version) return Error{"VV: " + version.error().message};
  auto pp = Command(Encode(SimpleCommand::kPP), config_.reply_timeout_s);
  if (!pp) return pp.error();
  auto parameters = scip::DecodeParameters(*pp);
  if (!parameters) return Error{"PP: " + parameters.error().message};
  auto ii = Command(Encode(SimpleCommand::kII), config_.reply_timeout_s);
  if (!ii) return ii.error();
  if (auto status = scip::DecodeInfo(*ii); !status) return Error{"II: " + status.error().message};
  info.version = *version;
  info.parameters = *parameters;
  return SyncBurst();
}

std::string HokuyoDriver::Session::SendTm1Command() {
  const std::uint64_t n = tm1_next_++;
  tm1_sent_us_[n % tm1_sent_us_.size()] = MonotonicUs();
  return scip::EncodeNumbered(SimpleCommand::kTM1, n);
}

void HokuyoDriver::Session::OnTimeReply(const scip::Block& block, double receive_us) {
  // Only replies to one of the last 64 commands count.
  const auto sequence = scip::SequenceOf(block.echo, SimpleCommand::kTM1);
  if (!sequence) return;
  const std::uint64_t n = *sequence;
  if (n >= tm1_next_ || n + tm1_sent_us_.size() < tm1_next_) return;
  const double sent = tm1_sent_us_[n % tm1_sent_us_.size()];
  auto time = scip::DecodeTime(block);
  if (!time) {
    driver_.LogRepeated(LogLevel::kWarning, "TM1 reply",
                        transport_.Describe() + ": TM1: " + time.error().message);
    return;
  }
  clock_.AddExchange(sent, receive_us, unwrapper_.Update(*time).unwrapped);
  driver_.stats_.clock_exchanges.fetch_add(1);
}

Status HokuyoDriver::Session::SyncBurst() {
  auto tm0 = Command(Encode(SimpleCommand::kTM0), config_.reply_timeout_s);
  if (!tm0) return tm0.error();
  if (auto status = Accept(*tm0); !status) return status;
  clock_.Reset();
  for (int i = 0; i < config_.sync_exchanges; ++i) {
    auto tm1 = Command(SendTm1Command(), config_.reply_timeout_s);
    if (!tm1) return tm1.error();
    OnTimeReply(*tm1, MonotonicUs());
    // Spread the exchanges over different phases of the device's millisecond.
    std::this_thread::sleep_for(microseconds(137 + 71 * (i % 7)));
  }
  auto tm2 = Command(Encode(SimpleCommand::kTM2), config_.reply_timeout_s);
  if (!tm2) return tm2.error();
  if (!clock_.ready()) return Error{"no TM1 reply could be decoded"};
  return OkStatus();
}

Expected<timing::ClockJump> HokuyoDriver::Session::OnScan(const scip::Block& block,
                                                          const scip::ScanEcho& echo,
                                                          const SensorInfo& info,
                                                          double /*receive_us*/) {
  if (auto status = scip::DecodeScan(block, echo, scan_data_); !status) return status.error();
  const scip::Parameters& p = info.parameters;
  const std::int64_t timestamp_ms = unwrapper_.Update(scan_data_.timestamp_ms).unwrapped;
  if (const timing::ClockJump jump = timer_->Check(timestamp_ms);
      jump != timing::ClockJump::kNone) {
    return jump;
  }
  const double device_start_us = timer_->Add(timestamp_ms);
  const double period_us = timer_->period_us();
  const double step_device_us = period_us / p.steps_per_rotation;
  const int cluster = std::max(1, echo.request.cluster);
  const int start = echo.request.start_step;

  scan_.host_monotonic_us = clock_.HostFromDevice(device_start_us + start * step_device_us);
  scan_.utime = std::llround(scan_.host_monotonic_us + RealtimeMinusMonotonicUs());
  scan_.device_utime = timestamp_ms * 1000;
  if (last_index_ < 0 && driver_.last_scan_.index >= 0) {
    // The first scan after a reconnect: the counter goes on by the rotations that passed since
    // the last published scan (host times of both, on the previous session's period), so an
    // outage shows as a gap and in lost_scans like any other loss.
    const LastScan& last = driver_.last_scan_;
    const double period = last.period_host_us > 0 ? last.period_host_us : scip::RotationPeriodUs(p);
    const std::int64_t rotations =
        std::max<std::int64_t>(1, std::llround((scan_.host_monotonic_us - last.host_us) / period));
    counter_base_ = last.index + rotations - static_cast<std::int64_t>(timer_->last_index());
    last_index_ = last.index;
  }
  const std::int64_t index = counter_base_ + static_cast<std::int64_t>(timer_->last_index());
  if (last_index_ >= 0 && index > last_index_ + 1 + config_.skip) {
    driver_.stats_.lost_scans.fetch_add((index - last_index_ - 1) / (1 + config_.skip));
  }
  last_index_ = index;
  last_scan_ms_ = timestamp_ms;
  scan_.scan_counter = index;
  scan_.time_per_ray = step_device_us * cluster * clock_.rate() * 1e-6;
  scan_.angle_increment = scip::ValueIncrement(p, echo.request);
  scan_.angle_first = scip::StepAngle(p, start);
  scan_.timing_margin_us = timer_->margin_us();
  scip::RangesToMetres(p, scan_data_.ranges_mm, scan_.ranges);
  scan_.intensities.resize(scan_data_.intensities.size());
  for (std::size_t i = 0; i < scan_data_.intensities.size(); ++i) {
    scan_.intensities[i] = static_cast<float>(scan_data_.intensities[i]);
  }
  driver_.on_scan_(scan_);
  driver_.stats_.scans_published.fetch_add(1);
  driver_.last_scan_ = {index, scan_.host_monotonic_us, period_us * clock_.rate()};
  return timing::ClockJump::kNone;
}

Status HokuyoDriver::Session::Stream(const std::atomic<bool>& stop, const SensorInfo& info) {
  const scip::Parameters& p = info.parameters;
  scip::ScanRequest request;
  request.type = config_.scan_type;
  request.start_step = config_.start_step < 0 ? p.first_step : config_.start_step;
  request.end_step = config_.end_step < 0 ? p.last_step : config_.end_step;
  request.cluster = config_.cluster;
  request.skip = config_.skip;
  request.count = 0;
  if (request.start_step < p.first_step || request.end_step > p.last_step) {
    return Error{"requested steps " + std::to_string(request.start_step) + ".." +
                 std::to_string(request.end_step) + " outside the sensor's " +
                 std::to_string(p.first_step) + ".." + std::to_string(p.last_step)};
  }
  auto command = scip::EncodeScanRequest(request);
  if (!command) return command.error();
  timer_.emplace(scip::RotationPeriodUs(p));
  scan_.ranges.reserve(static_cast<std::size_t>(scip::ValuesPerScan(request)));
  scan_.intensities.reserve(static_cast<std::size_t>(scip::ValuesPerScan(request)));

  auto ack = Command(*command, config_.reply_timeout_s, &stop);
  if (!ack) return ack.error();
  if (auto status = Accept(*ack); !status) return status;
  double last_scan_us = MonotonicUs();
  // sync_interval_s 0: no TM1 while streaming, so the next exchange is never due.
  double next_sync_us = config_.sync_interval_s > 0 ? MonotonicUs() + config_.sync_interval_s * 1e6
                                                    : std::numeric_limits<double>::infinity();
  while (!stop.load()) {
    driver_.repeated_log_.Flush();
    const double now = MonotonicUs();
    if (now - last_scan_us > config_.stall_timeout_s * 1e6) {
      return Error{"stream stalled: no scan for " + std::to_string(config_.stall_timeout_s) + " s"};
    }
    if (config_.sync_interval_s > 0 && now >= next_sync_us) {
      // TM1 between scans: the sensor answers it while streaming (docs/hokuyo.md).
      if (auto status = transport_.Write(SendTm1Command()); !status) return status;
      next_sync_us = now + config_.sync_interval_s * 1e6;
    }
    const double deadline = std::min(next_sync_us, last_scan_us + config_.stall_timeout_s * 1e6);
    // Wake at least every 50 ms to check `stop`.
    auto block = NextBlock(std::min(deadline, MonotonicUs() + 50e3));
    if (!block) return block.error();
    if (!block->has_value()) continue;
    const double receive_us = MonotonicUs();
    const scip::Block& b = **block;
    if (scip::SequenceOf(b.echo, SimpleCommand::kTM1)) {
      OnTimeReply(b, receive_us);
      continue;
    }
    if (!scip::IsEchoOf(b.echo, request)) {
      driver_.Log(LogLevel::kDebug, "ignoring reply '" + b.echo + "'");
      continue;
    }
    auto echo = scip::ParseScanEcho(b.echo);
    if (!echo) {
      driver_.stats_.scans_dropped.fetch_add(1);
      driver_.LogRepeated(LogLevel::kWarning, "dropped scan",
                          transport_.Describe() + ": byte " + std::to_string(b.offset) + ": " +
                              echo.error().message);
      continue;
    }
    const scip::StatusKind kind = scip::ClassifyStatus(b.echo, b.status);
    if (kind == scip::StatusKind::kDone && b.lines.empty()) continue;  // a repeated acknowledgement
    if (kind != scip::StatusKind::kScanData) {
      // The sensor stopped the stream (hardware trouble, 21..49 verify error): say so, restart.
      return Error{"scan stream ended with status " + b.status + " (" +
                   scip::StatusMeaning(b.echo, b.status) + ")"};
    }
    auto jump = OnScan(b, *echo, info, receive_us);
    if (!jump) {
      driver_.stats_.scans_dropped.fetch_add(1);
      driver_.LogRepeated(LogLevel::kWarning, "dropped scan",
                          transport_.Describe() + ": dropped scan: " + jump.error().message);
      continue;
    }
    if (*jump != timing::ClockJump::kNone) {
      return Error{"device clock " + std::string(timing::ToString(*jump)) + " after the scan at " +
                   std::to_string(last_scan_ms_) + " ms (reboot?)"};
    }
    last_scan_us = receive_us;
  }
  (void)transport_.Write(Encode(SimpleCommand::kQT));
  return OkStatus();
}

HokuyoDriver::HokuyoDriver(HokuyoConfig config, ScanCallback on_scan, LogSink log)
    : config_(std::move(config)),
      on_scan_(std::move(on_scan)),
      log_(std::move(log)),
      repeated_log_(log_) {}

Status HokuyoDriver::Validate(const HokuyoConfig& c) {
  const int sources = (c.device.empty() ? 0 : 1) + (c.host.empty() ? 0 : 1) + (c.usb ? 1 : 0);
  if (sources != 1) return Error{"give exactly one of device, host or usb"};
  if (c.port <= 0 || c.port > 65535)
    return Error{"port " + std::to_string(c.port) + " outside 1..65535"};
  if (c.baud != 0 && !IsSupportedBaud(c.baud))
    return Error{"baud " + std::to_string(c.baud) + " is not a termios rate"};
  if (c.target_baud != 0 && !IsSupportedBaud(c.target_baud)) {
    return Error{"target_baud " + std::to_string(c.target_baud) + " is not a termios rate"};
  }
  if (c.scan_type != scip::ScanType::kMD && c.scan_type != scip::ScanType::kME) {
    return Error{"scan type must be MD or ME"};
  }
  if (c.cluster < 1 || c.cluster > 99) return Error{"cluster outside 1..99"};
  if (c.skip < 0 || c.skip > 9) return Error{"skip outside 0..9"};
  if (c.start_step >= 0 && c.end_step >= 0 && c.end_step < c.start_step) {
    return Error{"end_step before start_step"};
  }
  if (c.sync_exchanges < 1) return Error{"sync_exchanges must be at least 1"};
  if (!(c.sync_interval_s >= 0) || !std::isfinite(c.sync_interval_s)) {
    return Error{
        "sync_interval_s must be 0 (no TM1 while streaming) or a positive number of "
        "seconds, not " +
        std::to_string(c.sync_interval_s)};
  }
  if (c.reply_timeout_s <= 0 || c.stall_timeout_s <= 0 || c.backoff_initial_s <= 0 ||
      c.backoff_max_s < c.backoff_initial_s) {
    return Error{"timeouts and backoff must be positive (backoff_max >= backoff_initial)"};
  }
  return OkStatus();
}

Expected<std::unique_ptr<Transport>> HokuyoDriver::Connect(int& baud) {
  baud = 0;
  if (!config_.host.empty()) {
    return OpenTcp(config_.host, config_.port,
                   std::chrono::milliseconds(static_cast<int>(config_.reply_timeout_s * 1000)));
  }
  std::string path = config_.device;
  if (config_.usb) {
    auto devices = ListHokuyoUsb();
    if (!devices) return devices.error();
    const auto found = std::find_if(devices->begin(), devices->end(),
                                    [](const UsbDevice& d) { return !d.tty.empty(); });
    if (found == devices->end()) {
      return Error{"no Hokuyo (USB vendor 0x15d1) with a tty attached"};
    }
    path = found->tty;
  }
  // Detect the rate: the sensor answers QT only at its own (USB answers at any).
  std::vector<int> candidates;
  if (config_.baud != 0) candidates.push_back(config_.baud);
  for (const int b : kProbeBauds) {
    if (b != config_.baud) candidates.push_back(b);
  }
  auto transport = OpenSerial(path, candidates.front());
  if (!transport) return transport.error();
  // Errors of the open transport do not name the link (transport.h): name it here.
  const auto named = [&path](const Error& error) { return Error{path + ": " + error.message}; };
  for (const int candidate : candidates) {
    if (auto status = (*transport)->SetBaud(candidate); !status) return named(status.error());
    (*transport)->DiscardInput();
    // The leading LF ends whatever half command the sensor holds from a wrong rate.
    std::string probe(1, '\n');
    probe += Encode(SimpleCommand::kQT);
    if (auto status = (*transport)->Write(probe); !status) return named(status.error());
    const double deadline = MonotonicUs() + config_.reply_timeout_s * 1e6 * 0.5;
    scip::BlockFramer framer;
    char buffer[1024];
    bool answered = false;
    while (!answered && MonotonicUs() < deadline) {
      auto n = (*transport)
                   ->Read(buffer, sizeof(buffer),
                          microseconds(static_cast<std::int64_t>(deadline - MonotonicUs())));
      if (!n) return named(n.error());
      framer.Append(std::string_view(buffer, *n));
      while (auto block = framer.Next()) {
        if (block->ok() && (*block)->echo == scip::SimpleCommandName(SimpleCommand::kQT)) {
          answered = true;
        }
      }
    }
    if (answered) {
      baud = candidate;
      if (config_.target_baud != 0 && config_.target_baud != candidate) {
        const std::string ss = scip::EncodeBaudChange(config_.target_baud).value();
        if (auto status = (*transport)->Write(ss); !status) return named(status.error());
        const double ss_deadline = MonotonicUs() + config_.reply_timeout_s * 1e6;
        std::string status_code;  // empty while no reply came
        while (status_code.empty() && MonotonicUs() < ss_deadline) {
          auto n = (*transport)->Read(buffer, sizeof(buffer), microseconds(20000));
          if (!n) return named(n.error());
          framer.Append(std::string_view(buffer, *n));
          while (auto block = framer.Next()) {
            if (block->ok() && (*block)->echo == scip::EchoOf(ss)) status_code = (*block)->status;
          }
        }
        if (scip::ClassifyBaudChange(status_code) == scip::BaudChange::kSwitched) {
          if (auto status = (*transport)->SetBaud(config_.target_baud); !status) {
            return named(status.error());
          }
          baud = config_.target_baud;
        } else {
          Log(LogLevel::kWarning, path + ": SS to " + std::to_string(config_.target_baud) +
                                      " answered '" + status_code + "' (" +
                                      scip::StatusMeaning("SS", status_code) + "); staying at " +
                                      std::to_string(candidate));
        }
      }
      (*transport)->DiscardInput();
      return transport;
    }
  }
  return Error{path + ": no SCIP reply at any of the probed bit rates"};
}

double HokuyoDriver::NextWait(const Status& status, bool sensor_booting, double& backoff_s) {
  if (!status && sensor_booting) {
    const double now = MonotonicUs();
    if (booting_since_us_ < 0) booting_since_us_ = now;
    if (now - booting_since_us_ < kBootWaitMaxS * 1e6) return std::min(kBootRetryS, backoff_s);
  } else {
    booting_since_us_ = -1;
  }
  const double wait_s = backoff_s;
  backoff_s = std::min(backoff_s * 2, config_.backoff_max_s);
  return wait_s;
}

void HokuyoDriver::Run(const std::atomic<bool>& stop) {
  double backoff_s = config_.backoff_initial_s;
  auto sleep_interruptibly = [&](double seconds) {
    const double until = MonotonicUs() + seconds * 1e6;
    while (!stop.load() && MonotonicUs() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  };
  while (!stop.load()) {
    repeated_log_.Flush();
    int baud = 0;
    auto transport = Connect(baud);
    if (!transport) {
      // Connection refused or no device: the sensor is away, not booting.
      const double wait_s = NextWait(transport.error(), false, backoff_s);
      LogRepeated(LogLevel::kWarning, "connect",
                  "connect failed: " + transport.error().message + "; retrying in " +
                      std::to_string(wait_s) + " s");
      sleep_interruptibly(wait_s);
      continue;
    }
    stats_.sessions.fetch_add(1);
    Session session(*this, **transport);
    SensorInfo info;
    info.transport = (*transport)->Describe();
    info.baud = baud;
    Status status = session.Handshake(info);
    if (status) {
      Log(LogLevel::kInfo, info.transport + ": " + info.parameters.model + " serial " +
                               info.version.serial + ", firmware " + info.version.firmware +
                               ", steps " + std::to_string(info.parameters.first_step) + ".." +
                               std::to_string(info.parameters.last_step) + ", " +
                               std::to_string(info.parameters.rotation_rpm) + " rpm");
      if (on_info_) on_info_(info);
      const std::int64_t published_before = stats_.scans_published.load();
      status = session.Stream(stop, info);
      if (stats_.scans_published.load() > published_before) backoff_s = config_.backoff_initial_s;
    }
    if (stop.load()) break;
    const double wait_s = NextWait(status, session.sensor_booting(), backoff_s);
    // Errors of a session never name the link (transport.h): it is named here, once.
    LogRepeated(LogLevel::kWarning, "reconnect",
                info.transport + ": " +
                    (status ? std::string("session ended") : status.error().message) +
                    "; reconnecting in " + std::to_string(wait_s) + " s");
    transport->reset();
    sleep_interruptibly(wait_s);
  }
  repeated_log_.FlushAll();
}

}  // namespace selfcal::hokuyo
