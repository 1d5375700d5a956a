// selfcal-canopen: joint states of a CANopen (CiA 402) arm over SocketCAN (canopen_driver.h).
#include <spdlog/spdlog.h>

#include "drivers/canopen/canopen_driver.h"
#include "protocols/program/program.h"

namespace {

namespace program = selfcal::program;

constexpr program::About kAbout{
    "selfcal-canopen",
    "selfcal-canopen: joint states of a CANopen (CiA 402) arm over SocketCAN. Starts "
    "the nodes (NMT), watches heartbeats, produces or follows SYNC, reads the position "
    "actual value from SYNC-triggered TPDOs and publishes selfcal.joint_state_t with "
    "SYNC-based host timestamps."};

struct Settings {
  selfcal::canopen::CanopenDriverOptions driver;
  std::string config_path = program::InstalledConfig("drivers/canopen.yaml");
  std::string lcm_url;
  double duration_s = 0;
};

void DescribeOptions(program::Program& p, Settings& s) {
  auto& d = s.driver;
  p.Option("--config", s.config_path, "Driver configuration (YAML)");
  p.LcmUrlOption(s.lcm_url);
  p.Option("--joint-state-channel", d.joint_state_channel, "selfcal.joint_state_t out");
  p.Option("--status-channel", d.status_channel, "selfcal.robot_driver_status_t out");
  p.Option("--clock-settle", d.clock.settle_s, "Seconds of SYNCs before joint states are published")
      ->check(program::kNonNegative);
  p.Option("--clock-settle-samples", d.clock.settle_samples,
           "SYNCs before joint states are published (at least 2)");
  p.DurationOption(s.duration_s);
}

int Run(selfcal::canopen::CanopenDriver& driver, double duration_s) {
  const int exit = program::RunUntilStopped(
      duration_s, [&driver] { return driver.SpinOnce(std::chrono::microseconds(500)); });
  if (exit != program::kExitOk) return exit;
  spdlog::info("stopping: {} SYNCs, {} incomplete, {} bad frames, {} joint states",
               driver.source().syncs() + 1, driver.source().incomplete_syncs(),
               driver.source().bad_frames(), driver.published());
  return program::kExitOk;
}

// Everything after the command line: read files, open the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  auto config = selfcal::canopen::ReadCanopenConfig(s.config_path);
  if (!config.ok()) return program::Fail(config.error().message);
  s.driver.config = *config;
  if (s.driver.clock.settle_samples < 2) s.driver.clock.settle_samples = 2;
  s.driver.clock.bins = static_cast<int>(std::min<std::size_t>(8, s.driver.clock.settle_samples));
  auto bus = program.OpenBus(s.lcm_url);
  if (!bus.ok()) return program::Fail(bus.error().message);
  auto socket = selfcal::canopen::CanSocket::OpenSocketCan(s.driver.config.interface);
  if (!socket.ok()) return program::Fail(socket.error().message);
  selfcal::canopen::DescribeSettings(program, s.driver.config);
  program.LogConfiguration();
  selfcal::canopen::CanopenDriver driver(s.driver, std::move(*socket), **bus);
  return Run(driver, s.duration_s);
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}
