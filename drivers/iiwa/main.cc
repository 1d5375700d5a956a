// selfcal-iiwa: KUKA LBR iiwa FRI client publishing joint states over LCM and executing
// trajectories (see iiwa_driver.h and docs/robot-side.md).
#include <spdlog/spdlog.h>

#include "drivers/iiwa/iiwa_driver.h"
#include "protocols/model_file/model_file.h"
#include "protocols/program/program.h"

namespace {

namespace program = selfcal::program;

constexpr program::About kAbout{
    "selfcal-iiwa",
    "selfcal-iiwa: FRI client for the KUKA LBR iiwa. Publishes joint states "
    "(selfcal.joint_state_t, drake.lcmt_iiwa_status) with host time mapped from the "
    "controller clock, executes selfcal.joint_trajectory_t signed with the daemon's key "
    "(and, with --follow-iiwa-command, drake.lcmt_iiwa_command) within the limits of the robot "
    "model file."};

struct Settings {
  selfcal::iiwa::DriverOptions driver;
  std::string model_path = program::InstalledConfig("robots/kuka_lbr_iiwa_r840.yaml");
  std::string lcm_url;
  std::string key_file;
  double duration_s = 0;
};

void DescribeOptions(program::Program& p, Settings& s) {
  auto& d = s.driver;
  p.Option("--model", s.model_path, "Robot model file (joint names and limits)");
  p.Option("--fri-port", d.fri_port, "UDP port the controller sends to (0: any)");
  p.Option("--bind-host", d.bind_host, "Local IPv4 address to bind");
  p.LcmUrlOption(s.lcm_url);
  p.Option("--joint-state-channel", d.joint_state_channel, "selfcal.joint_state_t out");
  p.Option("--iiwa-status-channel", d.iiwa_status_channel, "drake.lcmt_iiwa_status out");
  p.Option("--iiwa-command-channel", d.iiwa_command_channel, "drake.lcmt_iiwa_command in");
  p.Option("--trajectory-channel", d.trajectory_channel, "selfcal.joint_trajectory_t in");
  p.Option("--status-channel", d.status_channel, "selfcal.robot_driver_status_t out");
  p.Option("--key-file", s.key_file,
           "The daemon's key (64 hex characters, mode 0600): trajectories must be signed with it; "
           "without one every trajectory is refused");
  p.Flag("--follow-iiwa-command", d.follow_iiwa_command,
         "Follow drake.lcmt_iiwa_command (INSECURE: it is unauthenticated, anyone who can send to "
         "the bus can move the arm)");
  p.Option("--start-tolerance", d.session.start_tolerance_rad,
           "A trajectory or command stream must start this close to the current commanded "
           "position [rad]")
      ->check(program::kPositive);
  p.Option("--command-expire", d.session.command_expire_s,
           "IIWA_COMMAND setpoints older than this stop the motion [s]")
      ->check(program::kPositive);
  p.Option("--velocity-filter-cutoff", d.velocity_filter_cutoff_hz, "[Hz]")
      ->check(program::kPositive);
  p.DurationOption(s.duration_s);
}

// Spins the driver until a stop signal or the duration ends, logging FRI session changes.
int Run(selfcal::iiwa::IiwaDriver& driver, double duration_s) {
  int last_state = -2;
  const int exit = program::RunUntilStopped(duration_s, [&]() -> selfcal::Status {
    auto spun = driver.SpinOnce(std::chrono::milliseconds(10));
    const int state = driver.session().session_state();
    if (spun.ok() && state != last_state) {
      spdlog::info("FRI session: {}",
                   state < 0
                       ? "no controller"
                       : selfcal::fri::ToString(static_cast<selfcal::fri::SessionState>(state)));
      last_state = state;
    }
    return spun;
  });
  if (exit != program::kExitOk) return exit;
  spdlog::info("stopping: {} monitoring messages, {} lost, {} late, {} bad, {} joint states",
               driver.session().messages_received(), driver.session().messages_lost(),
               driver.session().messages_late(), driver.decode_errors(),
               driver.published_joint_states());
  return program::kExitOk;
}

// Everything after the command line: read files, open the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  auto model = selfcal::ReadModelFile(s.model_path);
  if (!model.ok()) return program::Fail(model.error().message);
  s.driver.model = model->model;
  if (!s.key_file.empty()) {
    auto key = selfcal::auth::ReadKeyFile(s.key_file, /*require_private=*/true);
    if (!key.ok()) return program::Fail(key.error().message);
    s.driver.key = *key;
  } else {
    spdlog::warn("no --key-file: every trajectory is refused (stop requests are honoured)");
  }
  if (s.driver.follow_iiwa_command) {
    spdlog::warn(
        "INSECURE: following {} (--follow-iiwa-command): it is unauthenticated, anyone "
        "who can send to the bus can move the arm",
        s.driver.iiwa_command_channel);
  }
  auto bus = program.OpenBus(s.lcm_url);
  if (!bus.ok()) return program::Fail(bus.error().message);
  auto driver = selfcal::iiwa::IiwaDriver::Create(s.driver, **bus, program::Logger());
  if (!driver.ok()) return program::Fail(driver.error().message);
  program.EchoValue("joints", [&] { return std::to_string(s.driver.model.JointCount()); });
  program.EchoValue("bound-port", [&] { return std::to_string((*driver)->port()); });
  program.LogConfiguration();
  return Run(**driver, s.duration_s);
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}
