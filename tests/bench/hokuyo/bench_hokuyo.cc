// Hokuyo streaming benchmark: selfcal-sim-scip (a separate process, TCP or pty) at 40 Hz for
// --seconds, through the real driver, the publisher and LCM, to a subscriber that decodes every
// range_scan_t. Reports lost scans and CPU per scan; the baseline, measured in the same run, is
// the SCIP codec alone (framing + decoding the same scans from memory).
// Output: key=value lines. Built with the project, never run by ctest.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <thread>

#include "drivers/hokuyo/driver.h"
#include "drivers/hokuyo/publisher.h"
#include "protocols/lcm/channels.h"
#include "protocols/scip/block.h"
#include "protocols/scip/replies.h"
#include "selfcal/range_scan_t.hpp"

extern char** environ;

namespace {

double CpuSeconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// CPU seconds per scan of framing and decoding 1081-step MD scans from memory.
double CodecBaselineSeconds(int scans) {
  std::string stream;
  for (int n = 0; n < scans; ++n) {
    stream += "MD0000108001000\n99b\n";
    selfcal::scip::ScanValues values;
    values.timestamp_ms = static_cast<std::uint32_t>(25 * n);
    for (std::uint32_t i = 0; i < 1081; ++i)
      values.ranges_mm.push_back(100 + (i * 37 + static_cast<std::uint32_t>(n)) % 29000);
    selfcal::scip::AppendScanData(stream, selfcal::scip::ScanType::kMD, values);
    stream += "\n";
  }
  selfcal::scip::ScanData data;
  const double begin = CpuSeconds(CLOCK_THREAD_CPUTIME_ID);
  selfcal::scip::BlockFramer framer;
  std::size_t decoded = 0;
  for (std::size_t i = 0; i < stream.size(); i += 4096) {
    framer.Append(std::string_view(stream).substr(i, 4096));
    while (auto block = framer.Next()) {
      if (!block->ok()) continue;
      auto echo = selfcal::scip::ParseScanEcho((*block)->echo);
      if (echo.ok() && selfcal::scip::DecodeScan(**block, *echo, data).ok()) ++decoded;
    }
  }
  const double seconds = CpuSeconds(CLOCK_THREAD_CPUTIME_ID) - begin;
  if (decoded != static_cast<std::size_t>(scans)) std::fprintf(stderr, "baseline decode failed\n");
  return seconds / scans;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_hokuyo: 40 Hz streaming through selfcal-sim-scip, the Hokuyo driver and LCM"};
  double seconds = 60;
  std::string url = "memq://";
  std::string transport = "tcp";
  std::string sim_binary = SELFCAL_SIM_SCIP_BIN;
  app.add_option("--seconds", seconds, "Streaming time");
  app.add_option("--lcm-url", url, "LCM URL (udpm only inside tests/netns-run)");
  app.add_option("--transport", transport, "tcp or pty")->check(CLI::IsMember({"tcp", "pty"}));
  app.add_option("--sim", sim_binary, "selfcal-sim-scip binary");
  CLI11_PARSE(app, argc, argv);
  std::printf("seconds=%g\nlcm_url=%s\ntransport=%s\n", seconds, url.c_str(), transport.c_str());

  // The simulator, in a process of its own so its CPU is not counted here.
  const std::string link = "/tmp/selfcal-bench-hokuyo-" + std::to_string(getpid());
  std::vector<std::string> args = {sim_binary};
  if (transport == "pty") {
    args.insert(args.end(), {"--pty", "--link", link});
  }
  int out[2];
  if (pipe(out) != 0) return 1;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], 1);
  posix_spawn_file_actions_addclose(&actions, out[0]);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  std::vector<char*> argv_sim;
  for (auto& a : args) argv_sim.push_back(a.data());
  argv_sim.push_back(nullptr);
  pid_t sim_pid = -1;
  if (posix_spawn(&sim_pid, argv_sim[0], &actions, nullptr, argv_sim.data(), environ) != 0) {
    std::cerr << "error: cannot start " << sim_binary << "\n";
    return 1;
  }
  close(out[1]);
  std::string first;
  char c;
  while (read(out[0], &c, 1) == 1 && c != '\n') first.push_back(c);

  selfcal::hokuyo::HokuyoConfig config;
  if (transport == "pty") {
    config.device = first.substr(4);
  } else {
    config.host = "127.0.0.1";
    config.port = std::stoi(first.substr(5));
  }
  auto bus = selfcal::OpenLcmBus(url);
  if (!bus) {
    std::cerr << "error: " << bus.error().message << "\n";
    kill(sim_pid, SIGTERM);
    return 1;
  }
  std::int64_t received = 0;
  std::int64_t first_counter = -1;
  std::int64_t last_counter = -1;
  std::int64_t decode_errors = 0;
  (*bus)->Subscribe(selfcal::channels::kRangeScan, [&](const selfcal::BusMessage& message) {
    auto scan = selfcal::DecodeLcm<selfcal::range_scan_t>(message.data, message.channel);
    if (!scan) {
      ++decode_errors;
      return;
    }
    if (first_counter < 0) first_counter = scan->scan_counter;
    last_counter = scan->scan_counter;
    ++received;
  });
  selfcal::hokuyo::ScanPublisher publisher(**bus, selfcal::channels::kRangeScan);
  std::atomic<double> driver_thread_cpu{0};
  selfcal::hokuyo::HokuyoDriver driver(config, [&](const selfcal::hokuyo::RangeScan& scan) {
    publisher.Submit(scan);
    driver_thread_cpu.store(CpuSeconds(CLOCK_THREAD_CPUTIME_ID));
  });
  std::atomic<bool> stop{false};
  const double cpu_begin = CpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
  std::thread thread([&] { driver.Run(stop); });
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<std::int64_t>(seconds * 1000));
  while (std::chrono::steady_clock::now() < until) {
    (void)(*bus)->HandleOnce(std::chrono::milliseconds(50));
  }
  stop.store(true);
  thread.join();
  publisher.Flush();
  while (*(*bus)->HandleOnce(std::chrono::milliseconds(100))) {
  }
  const double cpu = CpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - cpu_begin;
  kill(sim_pid, SIGTERM);
  int status = 0;
  waitpid(sim_pid, &status, 0);

  const auto& stats = driver.stats();
  const std::int64_t published = stats.scans_published.load();
  const std::int64_t span = last_counter >= 0 ? last_counter - first_counter + 1 : 0;
  const double baseline = CodecBaselineSeconds(2000);
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf(
      "scans_published=%lld\nscans_received=%lld\nscans_lost=%lld\n"
      "scans_dropped_by_publisher=%lld\nblocks_rejected=%lld\ndecode_errors=%lld\n"
      "sessions=%lld\nrate_hz=%.3f\n",
      static_cast<long long>(published), static_cast<long long>(received),
      static_cast<long long>(span - received), static_cast<long long>(publisher.dropped()),
      static_cast<long long>(stats.blocks_rejected.load()), static_cast<long long>(decode_errors),
      static_cast<long long>(stats.sessions.load()), static_cast<double>(received) / seconds);
  const double per_scan = published ? cpu / static_cast<double>(published) : 0;
  const double driver_per_scan =
      published ? driver_thread_cpu.load() / static_cast<double>(published) : 0;
  std::printf(
      "cpu_per_scan_us=%.1f\ndriver_thread_cpu_per_scan_us=%.1f\n"
      "baseline_codec_cpu_per_scan_us=%.1f\nratio_cpu_per_scan_to_baseline=%.2f\n"
      "ratio_driver_thread_to_baseline=%.2f\ncpu_percent_of_one_core=%.2f\n"
      "max_rss_kb=%ld\n",
      per_scan * 1e6, driver_per_scan * 1e6, baseline * 1e6, per_scan / baseline,
      driver_per_scan / baseline, 100 * cpu / seconds, usage.ru_maxrss);
  return (span - received == 0 && published > 0) ? 0 : 1;
}
