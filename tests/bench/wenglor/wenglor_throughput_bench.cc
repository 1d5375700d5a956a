// Throughput of the Wenglor driver: profiles at a given line rate (default 1 kHz) from the fake
// libEthernetScanner.so through the driver's receive loop, the publisher and LCM, for a given time
// (default 30 s), counted by a subscriber. Reports loss and CPU.
//
// Baseline, measured in the same run: the fake library polled alone (no decoding, no time
// mapping, no publishing) at the same rate, so the ratio isolates what the driver adds.
//
// Usage: wenglor_throughput_bench [--rate-hz 1000] [--seconds 30] [--lcm-url memq://]
//                                 [--library PATH] [--scene objects]
// For udpm:// run it inside tests/netns-run. Prints key=value lines.
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "drivers/wenglor/driver_loop.h"
#include "drivers/wenglor/ethernet_scanner_library.h"
#include "drivers/wenglor/profile_publisher.h"
#include "protocols/bus/bus.h"
#include "protocols/lcm/channels.h"
#include "selfcal/line_profile_t.hpp"

namespace {

using selfcal::wenglor::WenglorConfig;

double ProcessCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

double ThreadCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec) * 1e-9;
}

struct Options {
  double rate_hz = 1000;
  double seconds = 30;
  std::string lcm_url = "memq://";
  std::string library = SELFCAL_SIM_WENGLOR_LIBRARY;
  std::string scene = "objects";  // the simulator's scene (plane, box, sphere, objects, bunny)
};

int Fail(const std::string& reason) {
  std::cerr << "error: " << reason << "\n";
  return 1;
}

// The fake alone: connect, configure the line time, poll GetXZIExtended into buffers.
struct BaselineResult {
  long profiles = 0;
  long errors = 0;  // negative codes other than "no new scan"
  double first_profile_s = 0;
  double cpu_s = 0;
  double wall_s = 0;
};

selfcal::Expected<BaselineResult> RunBaseline(const Options& options, int line_time_us) {
  auto library = selfcal::wenglor::EthernetScannerLibrary::Load(options.library);
  if (!library.ok()) return library.error();
  auto& l = **library;
  std::string ip = "127.0.0.1", port = "32001";
  void* handle = l.connect(ip.data(), port.data(), 1000);
  if (handle == nullptr) return selfcal::Error{"baseline: no handle"};
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (status != 3 && std::chrono::steady_clock::now() < deadline) {
    l.get_connect_status(handle, &status);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (status != 3) return selfcal::Error{"baseline: not connected"};
  std::string command =
      "SetAcquisitionLineTime=" + std::to_string(line_time_us) + "\rSetAcquisitionStart";
  if (l.write_data(handle, command.data(), static_cast<int>(command.size())) < 0) {
    return selfcal::Error{"baseline: command rejected"};
  }
  std::vector<double> x(8192), z(8192);
  std::vector<int> intensity(8192), width(8192);
  BaselineResult result;
  const double cpu0 = ProcessCpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::duration<double>(options.seconds);
  while (std::chrono::steady_clock::now() < end) {
    unsigned int encoder = 0;
    unsigned char io = 0;
    int counter = 0;
    const int n = l.get_xzi_extended(handle, x.data(), z.data(), intensity.data(), width.data(),
                                     8192, &encoder, &io, 0, nullptr, 0, &counter);
    if (n > 0) {
      if (result.profiles == 0) {
        result.first_profile_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      }
      ++result.profiles;
    } else {
      if (n != -1) ++result.errors;
      std::this_thread::sleep_for(std::chrono::microseconds(200));  // the driver's poll interval
    }
  }
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.cpu_s = ProcessCpuSeconds() - cpu0;
  l.disconnect(handle);
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << "usage: wenglor_throughput_bench [--rate-hz HZ] [--seconds S] [--lcm-url URL] "
                   "[--library PATH] [--scene objects|bunny|...]\n";
      return 0;
    }
    if (i + 1 >= argc) return Fail(arg + " needs a value");
    const std::string value = argv[++i];
    if (arg == "--rate-hz")
      options.rate_hz = std::atof(value.c_str());
    else if (arg == "--seconds")
      options.seconds = std::atof(value.c_str());
    else if (arg == "--lcm-url")
      options.lcm_url = value;
    else if (arg == "--library")
      options.library = value;
    else if (arg == "--scene")
      options.scene = value;
    else
      return Fail("unknown option " + arg);
  }
  if (!(options.rate_hz >= 1 && options.rate_hz <= 10000)) return Fail("--rate-hz: 1 .. 10000");
  if (!(options.seconds > 0)) return Fail("--seconds must be positive");
  const int line_time_us = static_cast<int>(std::lround(1e6 / options.rate_hz));
  // The simulator reads its scene from a control file (docs/wenglor.md).
  char control_path[] = "/tmp/wenglor_bench_control_XXXXXX";
  const int control_fd = mkstemp(control_path);
  if (control_fd < 0) return Fail("cannot create a control file in /tmp");
  const std::string control = "1 set scene " + options.scene + "\n";
  if (write(control_fd, control.data(), control.size()) != static_cast<ssize_t>(control.size())) {
    return Fail("cannot write the control file");
  }
  close(control_fd);
  setenv("SELFCAL_SIM_WENGLOR_CONTROL", control_path, 1);
  struct RemoveOnExit {
    const char* path;
    ~RemoveOnExit() { unlink(path); }
  } remove_control{control_path};
  std::printf("rate_hz=%g line_time_us=%d seconds=%g lcm_url=%s library=%s scene=%s\n",
              options.rate_hz, line_time_us, options.seconds, options.lcm_url.c_str(),
              options.library.c_str(), options.scene.c_str());

  auto baseline = RunBaseline(options, line_time_us);
  if (!baseline.ok()) return Fail(baseline.error().message);
  const double baseline_cpu = baseline->cpu_s / baseline->wall_s;
  std::printf(
      "baseline_profiles=%ld baseline_errors=%ld baseline_first_profile_s=%.3f "
      "baseline_cpu_percent=%.2f\n",
      baseline->profiles, baseline->errors, baseline->first_profile_s, 100 * baseline_cpu);

  WenglorConfig config;
  config.library_path = options.library;
  config.ip = "127.0.0.1";
  config.line_time_us = line_time_us;
  config.exposure_time_us = std::min(150, line_time_us);
  config.lcm_url = options.lcm_url;
  auto scanner = selfcal::wenglor::WenglorScanner::Create(config);
  if (!scanner.ok()) return Fail(scanner.error().message);
  auto bus = selfcal::OpenLcmBus(options.lcm_url);
  if (!bus.ok()) return Fail(bus.error().message);
  long received = 0, out_of_order = 0, decode_errors = 0;
  std::int64_t last_counter = -1;
  std::int64_t first_counter = -1;
  (*bus)->Subscribe(selfcal::channels::kLineProfile, [&](const selfcal::BusMessage& message) {
    auto decoded = selfcal::DecodeLcm<selfcal::line_profile_t>(message.data, message.channel);
    if (!decoded.ok()) {
      ++decode_errors;
      return;
    }
    if (first_counter < 0) first_counter = decoded->device_counter;
    if (last_counter >= 0 && decoded->device_counter != last_counter + 1) ++out_of_order;
    last_counter = decoded->device_counter;
    ++received;
  });
  selfcal::wenglor::ProfilePublisher publisher(**bus, config.channel, config.queue_profiles,
                                               (*scanner)->capacity());
  std::atomic<bool> stop{false};
  const double cpu0 = ProcessCpuSeconds();
  const double subscriber_cpu0 = ThreadCpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  std::thread loop([&] {
    selfcal::wenglor::RunScanner(**scanner, stop,
                                 [&](const selfcal::wenglor::Profile& p) { publisher.Push(p); });
  });
  const auto end = start + std::chrono::duration<double>(options.seconds);
  while (std::chrono::steady_clock::now() < end) {
    auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(50));
    if (!handled.ok()) return Fail(handled.error().message);
  }
  stop = true;
  loop.join();
  publisher.Stop();
  while (true) {  // drain what is still queued in LCM
    auto handled = (*bus)->HandleOnce(std::chrono::milliseconds(100));
    if (!handled.ok() || !*handled) break;
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu = ProcessCpuSeconds() - cpu0;
  const double subscriber_cpu = ThreadCpuSeconds() - subscriber_cpu0;
  const auto& stats = (*scanner)->stats();
  const auto pub = publisher.stats();
  const double driver_cpu = (cpu - subscriber_cpu) / wall;
  std::printf(
      "profiles=%lld published=%lld received=%ld lost=%lld counter_gaps=%lld "
      "queue_dropped=%lld publish_errors=%lld out_of_order=%ld decode_errors=%ld "
      "link_losses=%lld\n",
      static_cast<long long>(stats.profiles), static_cast<long long>(pub.published), received,
      static_cast<long long>(stats.lost_profiles), static_cast<long long>(stats.counter_gaps),
      static_cast<long long>(pub.dropped_queue_full), static_cast<long long>(pub.publish_errors),
      out_of_order, decode_errors, static_cast<long long>(stats.link_losses));
  std::printf("achieved_rate_hz=%.1f wall_s=%.2f\n", static_cast<double>(received) / wall, wall);
  std::printf("cpu_percent_process=%.2f cpu_percent_subscriber=%.2f cpu_percent_driver=%.2f\n",
              100 * cpu / wall, 100 * subscriber_cpu / wall, 100 * driver_cpu);
  std::printf("ratio_driver_cpu_to_baseline=%.2f\n",
              baseline_cpu > 0 ? driver_cpu / baseline_cpu : 0.0);
  const bool no_loss = stats.lost_profiles == 0 && pub.dropped_queue_full == 0 &&
                       pub.publish_errors == 0 && out_of_order == 0 && decode_errors == 0 &&
                       received == stats.profiles;
  std::printf("no_loss=%s\n", no_loss ? "true" : "false");
  return no_loss ? 0 : 3;
}
