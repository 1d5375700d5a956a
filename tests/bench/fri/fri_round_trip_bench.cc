// Round-trip latency of the FRI client: a monitoring message (7 joints, COMMANDING_ACTIVE) sent
// over UDP on 127.0.0.1 to selfcal-iiwa's driver loop, until its command message comes back.
// The driver decodes, maps the clock, interpolates, encodes, replies and publishes joint states
// on memq://.
//
// Baseline, measured in the same run: a bare UDP echo thread that returns the same datagram
// without decoding, so the ratio isolates what the driver adds to the loopback round trip.
//
// Messages are paced at --rate-hz (FRI runs at 1 kHz at most), so the driver's clock filter
// settles and the round trips include publishing joint states.
// Usage: fri_round_trip_bench [--messages 5000] [--rate-hz 1000]   Prints key=value lines.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "drivers/iiwa/iiwa_driver.h"
#include "protocols/fri/fri_codec.h"
#include "protocols/model_file/model_file.h"

namespace {

using Clock = std::chrono::steady_clock;

int UdpSocket(sockaddr_in& address) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  address = {};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t n = sizeof(address);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &n);
  return fd;
}

std::vector<std::uint8_t> Message(std::uint32_t sequence, std::uint64_t device_us) {
  using namespace selfcal::fri;
  MonitoringMessage m;
  m.header = {kMonitorMessageId, sequence, 0};
  MonitorData d;
  d.measured_joint_position = JointValues{0.1, 0.4, -0.1, -1.2, 0.2, 0.7, 0.3};
  d.measured_torque = JointValues(7, 1.0);
  d.commanded_joint_position = d.measured_joint_position;
  d.commanded_torque = JointValues(7, 1.0);
  d.external_torque = JointValues(7, 0.0);
  const std::uint64_t us = 1000000000ULL + device_us;
  d.timestamp = TimeStamp{static_cast<std::uint32_t>(us / 1000000),
                          static_cast<std::uint32_t>(us % 1000000 * 1000)};
  m.monitor_data = d;
  m.connection_info =
      ConnectionInfo{SessionState::kCommandingActive, ConnectionQuality::kExcellent, 5u, 1u};
  IpoData ipo;
  ipo.joint_position = d.measured_joint_position;
  m.ipo_data = ipo;
  std::vector<std::uint8_t> bytes(kMaxMessageBytes);
  bytes.resize(EncodeMonitoringMessage(m, bytes).value());
  return bytes;
}

struct Result {
  double median_us = 0, p99_us = 0, max_us = 0;
  int lost = 0;
};

// Sends `count` messages to `target` at `rate_hz`, each after the previous reply.
Result Measure(const sockaddr_in& target, int count, double rate_hz) {
  sockaddr_in local;
  const int fd = UdpSocket(local);
  timeval timeout{0, 100000};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  std::vector<double> latencies;
  latencies.reserve(static_cast<std::size_t>(count));
  Result result;
  std::uint8_t reply[2048];
  const auto first = Clock::now();
  for (int i = 0; i < count; ++i) {
    std::this_thread::sleep_until(first + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(i / rate_hz)));
    // The controller clock runs with real time, so the driver's clock filter settles.
    const auto bytes = Message(
        static_cast<std::uint32_t>(i),
        static_cast<std::uint64_t>(
            std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - first).count()));
    const auto start = Clock::now();
    ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&target),
             sizeof(target));
    if (::recv(fd, reply, sizeof(reply), 0) <= 0) {
      ++result.lost;
      continue;
    }
    latencies.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
  }
  ::close(fd);
  std::sort(latencies.begin(), latencies.end());
  if (!latencies.empty()) {
    result.median_us = latencies[latencies.size() / 2];
    result.p99_us = latencies[latencies.size() * 99 / 100];
    result.max_us = latencies.back();
  }
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  int messages = 5000;
  double rate_hz = 1000;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << "Usage: fri_round_trip_bench [--messages N] [--rate-hz R]\n"
                   "Round trip of FRI monitoring -> command messages through selfcal-iiwa's "
                   "driver over UDP loopback, against a bare UDP echo.\n";
      return 0;
    }
    if (arg == "--messages" && i + 1 < argc) {
      messages = std::atoi(argv[++i]);
      continue;
    }
    if (arg == "--rate-hz" && i + 1 < argc) {
      rate_hz = std::atof(argv[++i]);
      continue;
    }
    std::cerr << "error: unknown argument '" << arg << "'\n";
    return 2;
  }
  if (messages < 100) {
    std::cerr << "error: --messages must be at least 100\n";
    return 2;
  }
  if (!(rate_hz > 0 && rate_hz <= 100000)) {
    std::cerr << "error: --rate-hz must be within (0, 100000]\n";
    return 2;
  }
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  auto model = selfcal::ReadModelFile(std::string(dir ? dir : ".") +
                                      "/config/robots/kuka_lbr_iiwa_r840.yaml");
  if (!model.ok()) {
    std::cerr << "error: " << model.error().message << " (set SELFCAL_SOURCE_DIR)\n";
    return 1;
  }
  std::printf("messages=%d rate_hz=%.0f joints=7\n", messages, rate_hz);

  // Baseline: bare UDP echo.
  std::atomic<bool> running{true};
  sockaddr_in echo_address;
  const int echo_fd = UdpSocket(echo_address);
  timeval timeout{0, 50000};
  ::setsockopt(echo_fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  std::thread echo([&] {
    std::uint8_t buffer[2048];
    while (running) {
      sockaddr_in from{};
      socklen_t n = sizeof(from);
      const ssize_t size =
          ::recvfrom(echo_fd, buffer, sizeof(buffer), 0, reinterpret_cast<sockaddr*>(&from), &n);
      if (size > 0) {
        ::sendto(echo_fd, buffer, static_cast<std::size_t>(size), 0,
                 reinterpret_cast<sockaddr*>(&from), n);
      }
    }
  });
  const Result baseline = Measure(echo_address, messages, rate_hz);
  running = false;
  echo.join();
  ::close(echo_fd);

  // The driver, spun in its own thread.
  auto bus = selfcal::OpenLcmBus("memq://");
  if (!bus.ok()) {
    std::cerr << "error: " << bus.error().message << "\n";
    return 1;
  }
  selfcal::iiwa::DriverOptions options;
  options.model = model->model;
  options.bind_host = "127.0.0.1";
  options.fri_port = 0;
  auto driver = selfcal::iiwa::IiwaDriver::Create(options, **bus);
  if (!driver.ok()) {
    std::cerr << "error: " << driver.error().message << "\n";
    return 1;
  }
  running = true;
  std::thread spin([&] {
    while (running) (void)(*driver)->SpinOnce(std::chrono::milliseconds(10));
  });
  sockaddr_in driver_address{};
  driver_address.sin_family = AF_INET;
  driver_address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  driver_address.sin_port = htons((*driver)->port());
  const Result with_driver = Measure(driver_address, messages, rate_hz);
  running = false;
  spin.join();

  std::printf(
      "baseline_median_us=%.1f baseline_p99_us=%.1f baseline_max_us=%.1f baseline_lost=%d\n",
      baseline.median_us, baseline.p99_us, baseline.max_us, baseline.lost);
  std::printf("driver_median_us=%.1f driver_p99_us=%.1f driver_max_us=%.1f driver_lost=%d\n",
              with_driver.median_us, with_driver.p99_us, with_driver.max_us, with_driver.lost);
  std::printf("median_ratio=%.2f p99_ratio=%.2f joint_states_published=%lld\n",
              with_driver.median_us / baseline.median_us, with_driver.p99_us / baseline.p99_us,
              static_cast<long long>((*driver)->published_joint_states()));
  return 0;
}
