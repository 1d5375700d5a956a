// Camera throughput benchmark; built, never run by ctest. Run it in a network namespace:
//   tests/netns-run build/tests/bench/cameras/bench_cameras [--seconds 30]
// Rows (key=value):
//   aravis: PhotoNeo-sized frames (1120 x 800 Coord3D_ABC32f, 10.7 MB) at 20 Hz: libaravis' fake
//     GigE Vision camera -> selfcal-aravis -> LCM udpm (loopback) -> this process. Two rows:
//     pacing=off (liblcm sends each cloud's 165 fragments back to back) and the driver's default
//     pacing (1 MiB bursts, 1 ms apart; protocols/bus/udpm_sender.h).
//   openni2: Kinect-sized depth (640 x 576, 16 bit) at 30 Hz: our OpenNI2 plugin -> selfcal-openni2
//     -> LCM udpm -> this process.
// Baseline, measured in the same run: what the source produced (frames served by the fake camera,
// or the device frame counter), so `ratio` = frames received / frames produced (1.0: none lost).
// latency = receive time - exposure utime; cpu = process CPU time / wall time (1.0 = one core);
// lcm_socket_drops = fragments the kernel dropped at this process' own LCM socket; load = loadavg.
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "selfcal/depth_image_t.hpp"
#include "selfcal/organized_cloud_t.hpp"
#include "selfcal/scan_marker_t.hpp"
#include "tests/cameras/camera_test_util.h"

namespace {

using namespace std::chrono_literals;
using selfcal::testing::Child;

std::string g_scene = "analytic";                    // the fake camera's --scene
std::string g_burst_kb = "1024", g_gap_us = "1000";  // the paced row's driver options

// The subscriber's (this process') URL; --recv-buf-size changes it (0: liblcm's default buffer).
std::string g_url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
// The driver publishes on the same group without asking for a receive buffer.
constexpr const char* kDriverUrl = "udpm://239.255.76.67:7667?ttl=0";

// CPU seconds (user + system) of a process, from /proc/<pid>/stat.
double CpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// Load average (1, 5, 15 min) of the machine: the benchmark shares 2 cores with other work.
std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double one = 0, five = 0, fifteen = 0;
  in >> one >> five >> fifteen;
  char text[64];
  std::snprintf(text, sizeof text, "%.2f/%.2f/%.2f", one, five, fifteen);
  return text;
}

// UDP counters of this network namespace (/proc/net/snmp): datagrams delivered to sockets and
// datagrams the kernel dropped because a socket's receive buffer was full.
struct UdpCounters {
  long long in_datagrams = 0, rcvbuf_errors = 0;
};
UdpCounters ReadUdpCounters() {
  std::ifstream in("/proc/net/snmp");
  std::string names, values, line;
  while (std::getline(in, line)) {
    if (line.rfind("Udp: ", 0) == 0) {
      if (names.empty()) {
        names = line;
      } else {
        values = line;
        break;
      }
    }
  }
  std::istringstream n(names), v(values);
  std::string name, value;
  UdpCounters c;
  while (n >> name && v >> value) {
    if (name == "InDatagrams") c.in_datagrams = std::stoll(value);
    if (name == "RcvbufErrors") c.rcvbuf_errors = std::stoll(value);
  }
  return c;
}

// Datagrams the kernel dropped at this process' own LCM receive socket: the "drops" column of
// /proc/net/udp for the sockets bound to LCM's port (7667) whose inode is one of our descriptors.
// (The namespace-wide RcvbufErrors also counts GVSP packets that Aravis' unread UDP stream socket
// drops when Aravis receives through a packet socket, and other processes' LCM sockets.)
long long LcmSocketDrops() {
  std::set<std::string> own_inodes;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd")) {
    std::error_code error;
    const std::string target = std::filesystem::read_symlink(entry.path(), error).string();
    if (!error && target.rfind("socket:[", 0) == 0)
      own_inodes.insert(target.substr(8, target.size() - 9));
  }
  std::ifstream in("/proc/net/udp");
  std::string line;
  std::getline(in, line);  // header
  long long drops = 0;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::vector<std::string> f;
    for (std::string field; fields >> field;) f.push_back(field);
    // sl local rem st tx:rx tr:when retrnsmt uid timeout inode ref pointer drops
    if (f.size() < 13 || f[1].size() < 5 || f[1].substr(f[1].size() - 5) != ":1DF3") continue;
    if (own_inodes.count(f[9]) == 0) continue;
    drops += std::stoll(f.back());
  }
  return drops;
}

double SelfCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1e6;
}

struct Stats {
  std::vector<double> latency_ms;
  std::int64_t first_counter = -1, last_counter = -1;
  std::size_t received = 0;
  long long udp_in = 0, udp_rcvbuf_errors = 0;  // in this namespace, over the measurement
  long long lcm_socket_drops = 0;               // LCM fragments dropped by the kernel
  double subscriber_cpu = 0;                    // this process (LCM receive thread + decoding)
  void Add(std::int64_t utime, std::int64_t counter, std::int64_t receive_utime) {
    latency_ms.push_back(static_cast<double>(receive_utime - utime) / 1000.0);
    if (first_counter < 0) first_counter = counter;
    last_counter = counter;
    ++received;
  }
  double Percentile(double p) {
    if (latency_ms.empty()) return 0;
    std::sort(latency_ms.begin(), latency_ms.end());
    return latency_ms[static_cast<std::size_t>(p * static_cast<double>(latency_ms.size() - 1))];
  }
};

template <typename Message>
Stats Measure(selfcal::Bus& bus, const std::string& channel, Child& driver, double seconds,
              double& cpu, double& wall) {
  Stats stats;
  bus.Subscribe(channel, [&](const selfcal::BusMessage& m) {
    auto decoded = selfcal::DecodeLcm<Message>(m.data, m.channel);
    if (decoded) stats.Add(decoded->utime, decoded->frame_counter, selfcal::testing::NowUtime());
  });
  // Warm up until the first frame, then measure.
  const auto warm_end = std::chrono::steady_clock::now() + 15s;
  while (stats.received == 0 && std::chrono::steady_clock::now() < warm_end)
    (void)bus.HandleOnce(10ms);
  stats = Stats{};
  const UdpCounters udp_start = ReadUdpCounters();
  const long long lcm_drops_start = LcmSocketDrops();
  const double self_cpu_start = SelfCpuSeconds();
  const double cpu_start = CpuSeconds(driver.pid());
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) (void)bus.HandleOnce(10ms);
  wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  cpu = CpuSeconds(driver.pid()) - cpu_start;
  const UdpCounters udp_end = ReadUdpCounters();
  stats.udp_in = udp_end.in_datagrams - udp_start.in_datagrams;
  stats.udp_rcvbuf_errors = udp_end.rcvbuf_errors - udp_start.rcvbuf_errors;
  stats.lcm_socket_drops = LcmSocketDrops() - lcm_drops_start;
  stats.subscriber_cpu = (SelfCpuSeconds() - self_cpu_start) / wall;
  return stats;
}

// `pacing`: selfcal-aravis' --publish-burst-kb and --publish-gap-us ("0" "0": liblcm's burst).
void RunAravis(double seconds, const std::string& burst_kb, const std::string& gap_us) {
  // The fake camera in its own process, as a camera is: 1120 x 800 Coord3D_ABC32f at 20 Hz.
  Child camera({SELFCAL_FAKE_GEV_BINARY, "--frame-rate", "20", "--scene", g_scene},
               selfcal::testing::TempPath("bench-fake-gev.log"));
  if (!camera.WaitForLog("serving", 10s)) {
    std::printf("bench=aravis error=\"the fake camera did not start\"\n");
    return;
  }
  auto bus = selfcal::OpenLcmBus(g_url);
  if (!bus) {
    std::printf("bench=aravis error=\"%s\" (run inside tests/netns-run)\n",
                bus.error().message.c_str());
    return;
  }
  Child driver({SELFCAL_ARAVIS_BINARY, "--address", "127.0.0.1", "--trigger", "free-run",
                "--lcm-url", kDriverUrl, "--channel", "BENCH_CLOUD", "--packet-size", "8192",
                "--publish-burst-kb", burst_kb, "--publish-gap-us", gap_us},
               selfcal::testing::TempPath("bench-aravis.log"));
  double cpu = 0, wall = 0;
  const double camera_cpu_start = CpuSeconds(camera.pid());
  Stats stats =
      Measure<selfcal::organized_cloud_t>(**bus, "BENCH_CLOUD", driver, seconds, cpu, wall);
  const double camera_cpu = CpuSeconds(camera.pid()) - camera_cpu_start;
  driver.Stop();
  camera.Stop();
  // The baseline: frames the camera sent in the window (the span of GVSP block ids received).
  const std::int64_t span = stats.last_counter - stats.first_counter + 1;
  std::printf(
      "bench=aravis pacing=%s frame=1120x800xXYZ32f seconds=%.1f camera_fps=%.2f received=%zu "
      "fps=%.2f "
      "lost_in_span=%lld ratio=%.4f latency_ms_p50=%.1f latency_ms_p99=%.1f driver_cpu=%.3f "
      "camera_cpu=%.3f subscriber_cpu=%.3f driver_dropped=%lld udp_in=%lld udp_rcvbuf_errors=%lld "
      "lcm_socket_drops=%lld load=%s\n",
      burst_kb == "0" ? "off" : (burst_kb + "KiB/" + gap_us + "us").c_str(), wall,
      static_cast<double>(span) / wall, stats.received, static_cast<double>(stats.received) / wall,
      static_cast<long long>(span - static_cast<std::int64_t>(stats.received)),
      span > 0 ? static_cast<double>(stats.received) / static_cast<double>(span) : 0.0,
      stats.Percentile(0.5), stats.Percentile(0.99), cpu / wall, camera_cpu / wall,
      stats.subscriber_cpu, driver.Counter("dropped"), stats.udp_in, stats.udp_rcvbuf_errors,
      stats.lcm_socket_drops, LoadAverage().c_str());
}

// One frame per request, as the daemon asks at each scan pose: `requests` BEGIN markers, each
// after the previous cloud arrived (and 100 ms of rest), PhotoNeo-sized, paced (driver default).
// request_to_cloud = cloud received - marker published; exposure_after_request = cloud utime -
// marker utime (the exposure must follow the request).
void RunAravisTrigger(int requests) {
  Child camera({SELFCAL_FAKE_GEV_BINARY, "--frame-rate", "20", "--scene", g_scene},
               selfcal::testing::TempPath("bench-fake-gev-trigger.log"));
  if (!camera.WaitForLog("serving", 10s)) {
    std::printf("bench=aravis-trigger error=\"the fake camera did not start\"\n");
    return;
  }
  auto bus = selfcal::OpenLcmBus(g_url);
  if (!bus) {
    std::printf("bench=aravis-trigger error=\"%s\"\n", bus.error().message.c_str());
    return;
  }
  Child driver(
      {SELFCAL_ARAVIS_BINARY, "--address", "127.0.0.1", "--trigger", "software", "--lcm-url",
       kDriverUrl, "--channel", "BENCH_CLOUD", "--trigger-channel", "BENCH_MARKER", "--packet-size",
       "8192", "--publish-burst-kb", g_burst_kb, "--publish-gap-us", g_gap_us},
      selfcal::testing::TempPath("bench-aravis-trigger.log"));
  if (!driver.WaitForLog("connected to", 15s)) {
    std::printf("bench=aravis-trigger error=\"the driver did not connect\"\n");
    return;
  }
  std::int64_t received_utime = 0, cloud_utime = 0;
  std::size_t received = 0;
  (*bus)->Subscribe("BENCH_CLOUD", [&](const selfcal::BusMessage& m) {
    auto cloud = selfcal::DecodeLcm<selfcal::organized_cloud_t>(m.data, m.channel);
    if (!cloud) return;
    received_utime = selfcal::testing::NowUtime();
    cloud_utime = cloud->utime;
    ++received;
  });
  std::vector<double> request_to_cloud_ms, exposure_after_ms;
  int answered = 0, late_exposure = 0;
  const double driver_cpu_start = CpuSeconds(driver.pid());
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < requests; ++k) {
    selfcal::scan_marker_t marker{};
    marker.utime = selfcal::testing::NowUtime();
    marker.event = selfcal::scan_marker_t::BEGIN;
    marker.scan_index = k;
    marker.plan_name = "bench";
    marker.session_id = "bench";
    const std::size_t before = received;
    (void)(*bus)->Publish("BENCH_MARKER", marker);
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (received == before && std::chrono::steady_clock::now() < deadline)
      (void)(*bus)->HandleOnce(5ms);
    if (received == before) continue;
    ++answered;
    request_to_cloud_ms.push_back(static_cast<double>(received_utime - marker.utime) / 1000.0);
    exposure_after_ms.push_back(static_cast<double>(cloud_utime - marker.utime) / 1000.0);
    if (cloud_utime <= marker.utime) ++late_exposure;
    const auto rest_end = std::chrono::steady_clock::now() + 100ms;
    while (std::chrono::steady_clock::now() < rest_end) (void)(*bus)->HandleOnce(5ms);
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double driver_cpu = (CpuSeconds(driver.pid()) - driver_cpu_start) / wall;
  driver.Stop();
  camera.Stop();
  const auto percentile = [](std::vector<double> v, double p) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
  };
  std::printf(
      "bench=aravis-trigger frame=1120x800xXYZ32f requests=%d answered=%d extra_clouds=%lld "
      "request_to_cloud_ms_p50=%.1f request_to_cloud_ms_max=%.1f "
      "exposure_after_request_ms_p50=%.1f "
      "exposure_not_after_request=%d driver_cpu=%.3f load=%s\n",
      requests, answered, static_cast<long long>(received) - answered,
      percentile(request_to_cloud_ms, 0.5), percentile(request_to_cloud_ms, 1.0),
      percentile(exposure_after_ms, 0.5), late_exposure, driver_cpu, LoadAverage().c_str());
}

void RunOpenNi2(double seconds) {
  ::setenv("LD_LIBRARY_PATH", OPENNI2_ROOT, 1);
  auto bus = selfcal::OpenLcmBus(g_url);
  if (!bus) {
    std::printf("bench=openni2 error=\"%s\" (run inside tests/netns-run)\n",
                bus.error().message.c_str());
    return;
  }
  Child driver({SELFCAL_OPENNI2_BINARY, "--uri", "selfcal-sim://depth?width=640&height=576&fps=30",
                "--lcm-url", kDriverUrl, "--channel", "BENCH_DEPTH"},
               selfcal::testing::TempPath("bench-openni2.log"));
  double cpu = 0, wall = 0;
  Stats stats = Measure<selfcal::depth_image_t>(**bus, "BENCH_DEPTH", driver, seconds, cpu, wall);
  driver.Stop();
  const std::int64_t span = stats.last_counter - stats.first_counter + 1;
  // The plugin renders frames inside the driver process: its CPU is part of driver_cpu.
  std::printf(
      "bench=openni2 frame=640x576x16 seconds=%.1f produced=%lld received=%zu fps=%.2f "
      "lost_in_span=%lld ratio=%.4f latency_ms_p50=%.1f latency_ms_p99=%.1f driver_cpu=%.3f "
      "subscriber_cpu=%.3f udp_in=%lld udp_rcvbuf_errors=%lld lcm_socket_drops=%lld load=%s\n",
      wall, static_cast<long long>(span), stats.received,
      static_cast<double>(stats.received) / wall,
      static_cast<long long>(span - static_cast<std::int64_t>(stats.received)),
      span > 0 ? static_cast<double>(stats.received) / static_cast<double>(span) : 0.0,
      stats.Percentile(0.5), stats.Percentile(0.99), cpu / wall, stats.subscriber_cpu, stats.udp_in,
      stats.udp_rcvbuf_errors, stats.lcm_socket_drops, LoadAverage().c_str());
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 30.0;
  std::string which = "all";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help") {
      std::printf(
          "usage: tests/netns-run bench_cameras [--seconds S] [--only "
          "aravis|aravis-off|aravis-paced|aravis-trigger|openni2] "
          "[--scene analytic|tabletop-teapot|office|lab|corner] [--recv-buf-size BYTES (0: liblcm "
          "default)] "
          "[--burst-kb K --gap-us U (paced row; default 1024, 1000)]\n");
      return 0;
    } else if (arg == "--seconds" && i + 1 < argc) {
      seconds = std::atof(argv[++i]);
    } else if (arg == "--recv-buf-size" && i + 1 < argc) {
      const long size = std::atol(argv[++i]);
      g_url = "udpm://239.255.76.67:7667?ttl=0" +
              (size > 0 ? "&recv_buf_size=" + std::to_string(size) : "");
    } else if (arg == "--burst-kb" && i + 1 < argc) {
      g_burst_kb = argv[++i];
    } else if (arg == "--gap-us" && i + 1 < argc) {
      g_gap_us = argv[++i];
    } else if (arg == "--scene" && i + 1 < argc) {
      g_scene = argv[++i];
    } else if (arg == "--only" && i + 1 < argc) {
      which = argv[++i];
    } else {
      std::fprintf(stderr, "error: unknown argument '%s'\n", arg.c_str());
      return 2;
    }
  }
  if (!(seconds > 0)) {
    std::fprintf(stderr, "error: --seconds must be positive\n");
    return 2;
  }
  std::printf("seconds=%.1f only=%s scene=%s subscriber_url=%s\n", seconds, which.c_str(),
              g_scene.c_str(), g_url.c_str());
  // Baseline first (liblcm sends each cloud in one burst), then the driver's default pacing.
  if (which == "all" || which == "aravis" || which == "aravis-off") RunAravis(seconds, "0", "0");
  if (which == "all" || which == "aravis" || which == "aravis-paced")
    RunAravis(seconds, g_burst_kb, g_gap_us);
  if (which == "all" || which == "aravis-trigger") RunAravisTrigger(20);
  if (which == "all" || which == "openni2") RunOpenNi2(seconds);
  return 0;
}
