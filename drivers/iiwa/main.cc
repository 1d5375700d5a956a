// selfcal-iiwa: KUKA LBR iiwa FRI client publishing joint states over LCM and executing
// trajectories (see iiwa_driver.h and docs/robot-side.md).
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>

#include "drivers/iiwa/iiwa_driver.h"
#include "protocols/model_file/model_file.h"

namespace {
volatile std::sig_atomic_t stop_requested = 0;
void OnSignal(int) { stop_requested = 1; }
}  // namespace

int main(int argc, char** argv) {
  using namespace selfcal;
  CLI::App app{
      "selfcal-iiwa: FRI client for the KUKA LBR iiwa. Publishes joint states "
      "(selfcal.joint_state_t, drake.lcmt_iiwa_status) with host time mapped from the "
      "controller clock, executes selfcal.joint_trajectory_t and follows "
      "drake.lcmt_iiwa_command within the limits of the robot model file."};
  iiwa::DriverOptions options;
  std::string model_path = "/etc/selfcal/robots/kuka_lbr_iiwa_r840.yaml";
  std::string lcm_url;
  double duration_s = 0;
  app.add_option("--model", model_path, "Robot model file (joint names and limits)")
      ->capture_default_str();
  app.add_option("--fri_port", options.fri_port, "UDP port the controller sends to (0: any)")
      ->capture_default_str();
  app.add_option("--bind_host", options.bind_host, "Local IPv4 address to bind")
      ->capture_default_str();
  app.add_option("--lcm_url", lcm_url, "LCM URL (empty: LCM_DEFAULT_URL or liblcm's default)");
  app.add_option("--joint_state_channel", options.joint_state_channel)->capture_default_str();
  app.add_option("--iiwa_status_channel", options.iiwa_status_channel)->capture_default_str();
  app.add_option("--iiwa_command_channel", options.iiwa_command_channel)->capture_default_str();
  app.add_option("--trajectory_channel", options.trajectory_channel)->capture_default_str();
  app.add_option("--status_channel", options.status_channel)->capture_default_str();
  app.add_option("--start_tolerance", options.session.start_tolerance_rad,
                 "A trajectory or command stream must start this close to the current "
                 "commanded position [rad]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--command_expire", options.session.command_expire_s,
                 "IIWA_COMMAND setpoints older than this stop the motion [s]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--velocity_filter_cutoff", options.velocity_filter_cutoff_hz, "[Hz]")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--duration", duration_s, "Exit after this many seconds (0: run until SIGINT)")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-iiwa"));
  auto model = ReadModelFile(model_path);
  if (!model.ok()) {
    std::cerr << "error: " << model.error().message << "\n";
    return 1;
  }
  options.model = model->model;
  auto bus = OpenLcmBus(lcm_url);
  if (!bus.ok()) {
    std::cerr << "error: " << bus.error().message << "\n";
    return 1;
  }
  auto driver = iiwa::IiwaDriver::Create(options, **bus);
  if (!driver.ok()) {
    std::cerr << "error: " << driver.error().message << "\n";
    return 1;
  }
  spdlog::info(
      "model={} joints={} bind_host={} fri_port={} lcm_url={} joint_state_channel={} "
      "iiwa_status_channel={} iiwa_command_channel={} trajectory_channel={} "
      "status_channel={} start_tolerance={} command_expire={} velocity_filter_cutoff={}",
      model_path, options.model.JointCount(), options.bind_host, (*driver)->port(), (*bus)->url(),
      options.joint_state_channel, options.iiwa_status_channel, options.iiwa_command_channel,
      options.trajectory_channel, options.status_channel, options.session.start_tolerance_rad,
      options.session.command_expire_s, options.velocity_filter_cutoff_hz);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  const auto start = std::chrono::steady_clock::now();
  int last_state = -2;
  while (!stop_requested) {
    if (auto s = (*driver)->SpinOnce(std::chrono::milliseconds(10)); !s.ok()) {
      std::cerr << "error: " << s.error().message << "\n";
      return 1;
    }
    const int state = (*driver)->session().session_state();
    if (state != last_state) {
      spdlog::info("FRI session: {}", state < 0
                                          ? "no controller"
                                          : fri::ToString(static_cast<fri::SessionState>(state)));
      last_state = state;
    }
    if (duration_s > 0 &&
        std::chrono::steady_clock::now() - start > std::chrono::duration<double>(duration_s)) {
      break;
    }
  }
  spdlog::info("stopping: {} monitoring messages, {} lost, {} late, {} bad, {} joint states",
               (*driver)->session().messages_received(), (*driver)->session().messages_lost(),
               (*driver)->session().messages_late(), (*driver)->decode_errors(),
               (*driver)->published_joint_states());
  return 0;
}
