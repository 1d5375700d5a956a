#include "drivers/wenglor/wenglor_scanner.h"

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <limits>
#include <thread>

#include "core/timing/host_clock.h"
#include "core/util/enum_names.h"

namespace selfcal::wenglor {
namespace {

using Clock = std::chrono::steady_clock;

// How often the connection status is asked while no profile arrives.
constexpr auto kStatusCheckInterval = std::chrono::milliseconds(100);
// How often the connection status is asked while waiting for "connected".
constexpr auto kConnectPollInterval = std::chrono::milliseconds(5);
constexpr double kMetresPerMillimetre = 1e-3;

// The vendor library's codes in words; return codes keep their number, as its manual lists them.
constexpr EnumNames<int, 4> kConnectStatusNames{{
    {api::kDisconnected, "disconnected"},
    {api::kConnecting, "connecting"},
    {api::kDisconnecting, "disconnecting"},
    {api::kConnected, "connected"},
}};
const char* ConnectStatusName(int status) {
  return kConnectStatusNames.Name(status, "unknown status");
}

// `rc` in words, or "unknown code N" for one that `names` does not hold.
template <std::size_t N>
std::string CodeName(const EnumNames<int, N>& names, int rc) {
  const char* name = names.Name(rc, nullptr);
  return name != nullptr ? name : "unknown code " + std::to_string(rc);
}

constexpr EnumNames<int, 4> kGetInfoCodeNames{{
    {api::kGetInfoError, "error (-1)"},
    {api::kGetInfoSmallBuffer, "buffer too small (-2)"},
    {api::kGetInfoNoValidInfo, "no valid info (-3)"},
    {api::kGetInfoInvalidXml, "invalid XML (-4)"},
}};
std::string GetInfoCodeName(int rc) { return CodeName(kGetInfoCodeNames, rc); }

constexpr EnumNames<int, 3> kReadDataCodeNames{{
    {api::kReadDataSmallBuffer, "buffer too small (-1)"},
    {api::kReadDataNotSupportedMode, "mode not supported (-2)"},
    {api::kReadDataFeatureNotDefined, "feature not defined (-3)"},
}};
std::string ReadDataCodeName(int rc) { return CodeName(kReadDataCodeNames, rc); }

// The sensor's clock is its picture counter x line time: mapped never earlier than the exposure
// (timing::ClockFilter, never_early; docs/wenglor.md). A counter that steps back restarts the
// mapping explicitly, so no receive time is taken for a jump.
timing::ClockFilterOptions ClockOptions(double max_drift_ppm) {
  timing::ClockFilterOptions options;
  options.never_early = true;
  options.max_drift = max_drift_ppm * 1e-6;
  options.reset_jump_s = std::numeric_limits<double>::infinity();
  return options;
}

}  // namespace

void Profile::Allocate(int capacity) {
  const auto size = static_cast<std::size_t>(capacity);
  x.assign(size, 0.0F);
  z.assign(size, 0.0F);
  intensity.assign(size, 0.0F);
  peak_width.assign(size, 0.0F);
}

Expected<std::unique_ptr<WenglorScanner>> WenglorScanner::Create(const WenglorConfig& config,
                                                                 LogSink logger) {
  const Status valid = ValidateConfig(config);
  if (!valid.ok()) return valid.error();
  auto library = EthernetScannerLibrary::Load(config.library_path);
  if (!library.ok()) return library.error();
  return std::unique_ptr<WenglorScanner>(
      new WenglorScanner(config, std::move(*library), std::move(logger)));
}

WenglorScanner::WenglorScanner(const WenglorConfig& config,
                               std::unique_ptr<EthernetScannerLibrary> library, LogSink logger)
    : config_(config),
      library_(std::move(library)),
      logger_(std::move(logger)),
      endpoint_(config.ip + ":" + config.port),
      counter_({.modulus = api::kPictureCounterModulo}),
      clock_(ClockOptions(config.max_clock_drift_ppm)) {
  library_version_ = library_->Version();
  // The largest buffer the library may fill: every column of the widest sensor, every signal.
  columns_capacity_ = api::kScanXMax;
  const auto values = static_cast<std::size_t>(api::kScanXMax * api::kPeaksPerColumnMax);
  x_mm_.assign(values, 0.0);
  z_mm_.assign(values, 0.0);
  intensity_.assign(values, 0);
  peak_width_.assign(values, 0);
}

WenglorScanner::~WenglorScanner() { Disconnect(); }

void WenglorScanner::Log(LogLevel level, const std::string& message) const {
  if (logger_) logger_(level, message);
}

int WenglorScanner::ConnectStatus() {
  int status = -1;
  library_->get_connect_status(handle_, &status);
  return status;
}

Status WenglorScanner::Connect() {
  Disconnect();
  std::string ip = config_.ip;
  std::string port = config_.port;
  handle_ = library_->connect(ip.data(), port.data(), config_.connect_timeout_ms);
  if (handle_ == nullptr) {
    last_error_ = "EthernetScanner_Connect(" + endpoint_ + ") returned no handle";
    return Error{last_error_};
  }
  for (Status (WenglorScanner::*step)() :
       {&WenglorScanner::WaitConnected, &WenglorScanner::ReadInfo, &WenglorScanner::Configure}) {
    const Status status = (this->*step)();
    if (!status.ok()) {
      last_error_ = status.error().message;
      Disconnect();
      return status;
    }
  }
  counter_.Reset();
  clock_.Reset();
  last_profile_time_ = Clock::now();
  last_status_check_ = last_profile_time_;
  ++stats_.connects;
  Log(LogLevel::kInfo, "connected to " + info_.order_number + " at " + endpoint_ + " (library " +
                           library_->path() + ", version '" + library_version_ + "')");
  return OkStatus();
}

Status WenglorScanner::WaitConnected() {
  // EthernetScanner_Connect returns at once; the library connects in the background.
  const auto deadline = Clock::now() + std::chrono::milliseconds(config_.connect_timeout_ms);
  int status = ConnectStatus();
  while (status != api::kConnected) {
    if (Clock::now() >= deadline) {
      return Error{"no connection to " + endpoint_ + " within " +
                   std::to_string(config_.connect_timeout_ms) +
                   " ms (status: " + ConnectStatusName(status) + ")"};
    }
    std::this_thread::sleep_for(kConnectPollInterval);
    status = ConnectStatus();
  }
  return OkStatus();
}

Status WenglorScanner::ReadInfo() {
  std::string xml(static_cast<std::size_t>(api::kGetInfoSizeMax), '\0');
  std::string mode = "xml";
  const int rc = library_->get_info(handle_, xml.data(), static_cast<int>(xml.size()), mode.data());
  if (rc < 0) {
    return Error{endpoint_ + ": EthernetScanner_GetInfo failed: " + GetInfoCodeName(rc)};
  }
  xml.resize(xml.find('\0') == std::string::npos ? xml.size() : xml.find('\0'));
  auto info = ParseScannerInfo(xml);
  if (!info.ok()) return Error{endpoint_ + ": " + info.error().message};
  if (info->pixel_x_max > api::kScanXMax) {
    return Error{endpoint_ + ": info XML reports " + std::to_string(info->pixel_x_max) +
                 " columns, more than the library's maximum " + std::to_string(api::kScanXMax)};
  }
  info_ = std::move(*info);
  return OkStatus();
}

Status WenglorScanner::WriteCommand(const std::string& command) {
  if (handle_ == nullptr) return Error{"not connected to " + endpoint_};
  std::string buffer = command;
  const int rc = library_->write_data(handle_, buffer.data(), static_cast<int>(buffer.size()));
  if (rc < 0) {
    return Error{endpoint_ + ": command '" + command + "' failed (EthernetScanner_WriteData " +
                 std::to_string(rc) + ")"};
  }
  return OkStatus();
}

Expected<std::string> WenglorScanner::ReadProperty(const std::string& name) {
  if (handle_ == nullptr) return Error{"not connected to " + endpoint_};
  std::string property = name;
  std::array<char, 1024> value{};
  const int rc = library_->read_data(handle_, property.data(), value.data(),
                                     static_cast<int>(value.size()), /*cache_time_ms=*/0);
  if (rc != api::kReadDataOk) {
    return Error{endpoint_ + ": reading property " + name + " failed: " + ReadDataCodeName(rc)};
  }
  value.back() = '\0';
  return std::string(value.data());
}

Status WenglorScanner::CheckProperty(const std::string& name, int expected) {
  auto text = ReadProperty(name);
  if (!text.ok()) return text.error();
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text->c_str(), &end, 10);
  if (text->empty() || *end != '\0' || errno != 0) {
    return Error{endpoint_ + ": property " + name + " is not an integer: '" + *text + "'"};
  }
  if (value != expected) {
    return Error{endpoint_ + ": property " + name + " reads back " + std::to_string(value) +
                 ", not the configured " + std::to_string(expected)};
  }
  return OkStatus();
}

Status WenglorScanner::Configure() {
  // Stop first: settings are only accepted reliably while the acquisition is stopped.
  std::vector<std::string> commands = {
      "SetAcquisitionStop",
      "SetTriggerSource=" + std::to_string(static_cast<int>(config_.trigger_source)),
      "SetExposureTime=" + std::to_string(config_.exposure_time_us)};
  if (config_.trigger_source == TriggerSource::kInternal) {
    commands.push_back("SetAcquisitionLineTime=" + std::to_string(config_.line_time_us));
  }
  if (config_.trigger_source == TriggerSource::kEncoder) {
    commands.push_back("SetTriggerEncoderStep=" + std::to_string(config_.encoder_step));
  }
  commands.push_back("SetSignalSelection=" + std::to_string(config_.signal_selection));
  for (const std::string& command : commands) {
    const Status status = WriteCommand(command);
    if (!status.ok()) return status;
  }
  if (Status s = CheckProperty("ExposureTime", config_.exposure_time_us); !s.ok()) return s;
  if (config_.trigger_source == TriggerSource::kInternal) {
    if (Status s = CheckProperty("AcquisitionLineTime", config_.line_time_us); !s.ok()) return s;
  }
  // Profiles queued before this configuration belong to the old settings.
  const int rc = library_->reset_dll_fifo(handle_);
  if (rc < 0) {
    return Error{endpoint_ + ": EthernetScanner_ResetDllFiFo failed (" + std::to_string(rc) + ")"};
  }
  return WriteCommand("SetAcquisitionStart");
}

void WenglorScanner::Disconnect() {
  if (handle_ == nullptr) return;
  if (ConnectStatus() == api::kConnected) {
    std::string stop = "SetAcquisitionStop";
    library_->write_data(handle_, stop.data(), static_cast<int>(stop.size()));
  }
  library_->disconnect(handle_);
  handle_ = nullptr;
}

int WenglorScanner::FifoFillPercent() {
  if (handle_ == nullptr) return -1;
  const int percent = library_->get_dll_fifo_state(handle_);
  return percent < 0 || percent > 100 ? -1 : percent;
}

Status WenglorScanner::TriggerSoftware() { return WriteCommand("SetTriggerSoftware"); }

PollResult WenglorScanner::LinkLost(const std::string& why) {
  last_error_ = endpoint_ + ": " + why;
  ++stats_.link_losses;
  Log(LogLevel::kWarning, "link lost: " + last_error_);
  return PollResult::kLinkLost;
}

PollResult WenglorScanner::DropFlagged(std::int64_t& count, int rc, const std::string& what) {
  if (count++ == 0) {
    Log(LogLevel::kWarning, endpoint_ + ": " + what + " dropped (GetXZIExtended " +
                                std::to_string(rc) + "; further ones are counted)");
  }
  return PollResult::kDropped;
}

void DecodeColumns(std::span<const double> x_mm, std::span<const double> z_mm,
                   std::span<const int> intensity, std::span<const int> peak_width, int columns,
                   int signals, Profile& profile) {
  constexpr float kNoReturn = std::numeric_limits<float>::quiet_NaN();
  // Beyond any weCat3D's range (and float's): a value the library should never write.
  constexpr double kMaxCoordinateMm = 1e6;
  const auto plausible = [](double mm) {
    return std::isfinite(mm) && std::abs(mm) < kMaxCoordinateMm;
  };
  for (int i = 0; i < columns; ++i) {
    // With two signals the buffer alternates signal 1 / signal 2 per column (PDF §7.1).
    const auto j = static_cast<std::size_t>(i * signals);
    const auto k = static_cast<std::size_t>(i);
    // The library writes 0 for both coordinates of a column outside the measuring range; a
    // coordinate that is not a finite, plausible number is no measurement either.
    const bool no_return =
        (x_mm[j] == 0.0 && z_mm[j] == 0.0) || !plausible(x_mm[j]) || !plausible(z_mm[j]);
    profile.x[k] = no_return ? kNoReturn : static_cast<float>(x_mm[j] * kMetresPerMillimetre);
    profile.z[k] = no_return ? kNoReturn : static_cast<float>(z_mm[j] * kMetresPerMillimetre);
    profile.intensity[k] = static_cast<float>(intensity[j]);
    profile.peak_width[k] = static_cast<float>(peak_width[j]);
  }
  profile.num_points = columns;
}

PollResult WenglorScanner::Poll(Profile& profile) {
  if (handle_ == nullptr) return PollResult::kLinkLost;
  if (static_cast<int>(profile.x.size()) < columns_capacity_) profile.Allocate(columns_capacity_);
  unsigned int encoder = 0;
  unsigned char user_io = 0;
  int picture_counter = 0;
  const int buffer_values = static_cast<int>(x_mm_.size());
  const int rc = library_->get_xzi_extended(handle_, x_mm_.data(), z_mm_.data(), intensity_.data(),
                                            peak_width_.data(), buffer_values, &encoder, &user_io,
                                            /*timeout_ms, unused: non-blocking*/ 0, /*raw=*/nullptr,
                                            /*raw_bytes=*/0, &picture_counter);
  const auto now = Clock::now();

  if (rc == api::kGetXziNoNewScan) {
    if (now - last_status_check_ >= kStatusCheckInterval) {
      last_status_check_ = now;
      const int status = ConnectStatus();
      if (status != api::kConnected) {
        return LinkLost(std::string("connection status is ") + ConnectStatusName(status));
      }
    }
    if (config_.trigger_source == TriggerSource::kInternal &&
        now - last_profile_time_ > std::chrono::milliseconds(config_.data_timeout_ms)) {
      return LinkLost("no profile for " + std::to_string(config_.data_timeout_ms) +
                      " ms with the internal trigger");
    }
    return PollResult::kNoNewScan;
  }
  if (rc == api::kGetXziInvalidLinData) {
    return DropFlagged(stats_.invalid_lin_data, rc, "profile with invalid linearised data");
  }
  if (rc == api::kGetXziInvalidBuffer)
    return DropFlagged(stats_.invalid_buffer, rc, "invalid buffer");
  if (rc < 0) {
    ++stats_.unknown_codes;
    Log(LogLevel::kWarning,
        endpoint_ + ": GetXZIExtended returned the undocumented code " + std::to_string(rc));
    return PollResult::kDropped;
  }
  const int signals = config_.signals_per_column;
  if (rc == 0 || rc > buffer_values || rc % signals != 0 || rc / signals > columns_capacity_) {
    ++stats_.invalid_buffer;
    Log(LogLevel::kWarning, endpoint_ + ": GetXZIExtended reported " + std::to_string(rc) +
                                " values for a buffer of " + std::to_string(buffer_values) +
                                " with " + std::to_string(signals) +
                                " signal(s) per column; profile dropped");
    return PollResult::kDropped;
  }

  const timing::CounterStep step = counter_.Update(picture_counter);
  if (step.repeated()) {
    ++stats_.duplicates;
    return PollResult::kDropped;
  }
  last_profile_time_ = now;
  last_status_check_ = now;
  if (step.lost > 0) {
    ++stats_.counter_gaps;
    stats_.lost_profiles += step.lost;
  }
  if (step.went_backwards()) {
    ++stats_.counter_restarts;
    clock_.Reset();
    Log(LogLevel::kWarning, endpoint_ + ": picture counter went backwards to " +
                                std::to_string(picture_counter) + "; time mapping restarted");
  }

  const int columns = rc / signals;
  DecodeColumns({x_mm_.data(), x_mm_.size()}, {z_mm_.data(), z_mm_.size()},
                {intensity_.data(), intensity_.size()}, {peak_width_.data(), peak_width_.size()},
                columns, signals, profile);
  profile.host_receive_utime = timing::RealtimeUs();
  profile.raw_counter = picture_counter;
  profile.counter = step.unwrapped;
  profile.lost_before = step.lost;
  profile.counter_restarted = step.went_backwards();
  profile.encoder = encoder;
  profile.user_io = user_io;
  if (config_.trigger_source == TriggerSource::kInternal) {
    // The sensor exposes one profile per line time, so the counter is its clock.
    profile.device_utime = step.unwrapped * config_.line_time_us;
    profile.utime = clock_.Map(profile.device_utime, profile.host_receive_utime);
  } else {
    // Triggered profiles carry no device time we can read: the receive time is the best we have.
    profile.device_utime = -1;
    profile.utime = profile.host_receive_utime;
  }
  ++stats_.profiles;
  return PollResult::kProfile;
}

}  // namespace selfcal::wenglor
