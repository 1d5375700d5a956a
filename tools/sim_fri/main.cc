// selfcal-sim-fri: a simulated KUKA Sunrise controller speaking FRI to a client on UDP
// (fri_simulator.h). Optionally publishes its ground truth (true joint positions, stamped with
// true host time) as selfcal.joint_state_t for tests and demos.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <iostream>
#include <thread>

#include "protocols/bus/bus.h"
#include "protocols/model_file/model_file.h"
#include "selfcal/joint_state_t.hpp"
#include "tools/sim_fri/fri_simulator.h"

namespace {
volatile std::sig_atomic_t stop_requested = 0;
void OnSignal(int) { stop_requested = 1; }
}  // namespace

int main(int argc, char** argv) {
  using namespace selfcal;
  CLI::App app{
      "selfcal-sim-fri: simulated KUKA controller (robot side of FRI) on UDP. Walks "
      "the session states, follows commanded positions through a joint servo model, "
      "reports noisy measured positions with a drifting controller clock; packet loss "
      "and delay on demand."};
  sim::FriSimOptions options;
  std::string model_path = "/etc/selfcal/robots/kuka_lbr_iiwa_r840.yaml";
  std::string truth_url;
  std::string truth_channel = "SELFCAL_SIM_JOINT_TRUTH";
  std::vector<double> initial;
  double duration_s = 0;
  app.add_option("--model", model_path, "Robot model file (joint count and limits)")
      ->capture_default_str();
  app.add_option("--client_host", options.client_host, "IPv4 address of the FRI client")
      ->capture_default_str();
  app.add_option("--client_port", options.client_port, "UDP port of the FRI client")
      ->capture_default_str();
  app.add_option("--period", options.period_s, "FRI send period [s]")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 0.1));
  app.add_option("--receive_multiplier", options.receive_multiplier)->capture_default_str();
  app.add_option("--drift_ppm", options.drift_ppm, "Controller clock drift [ppm]")
      ->capture_default_str();
  app.add_option("--noise", options.position_noise_rad, "Measured position noise sigma [rad]")
      ->capture_default_str();
  app.add_option("--loss", options.loss_probability, "Loss probability of each datagram")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--delay_probability", options.delay_probability)
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--delay", options.delay_s, "Delay of a delayed datagram [s]")
      ->capture_default_str();
  app.add_option("--seed", options.seed)->capture_default_str();
  app.add_option("--command_after", options.command_after_s,
                 "Start commanding this long after MONITORING_READY [s] (< 0: never)")
      ->capture_default_str();
  app.add_option("--initial_position", initial, "Initial joint positions [rad]")->expected(-1);
  app.add_option("--truth_lcm_url", truth_url,
                 "Publish ground truth joint states on this LCM URL (empty: do not)");
  app.add_option("--truth_channel", truth_channel)->capture_default_str();
  app.add_option("--duration", duration_s, "Exit after this many seconds (0: until SIGINT)")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-sim-fri"));
  auto model = ReadModelFile(model_path);
  if (!model.ok()) {
    std::cerr << "error: " << model.error().message << "\n";
    return 1;
  }
  options.model = model->model;
  if (!initial.empty()) {
    options.initial_position =
        Eigen::Map<Eigen::VectorXd>(initial.data(), static_cast<Eigen::Index>(initial.size()));
  }
  std::unique_ptr<Bus> truth_bus;
  if (!truth_url.empty()) {
    auto bus = OpenLcmBus(truth_url);
    if (!bus.ok()) {
      std::cerr << "error: " << bus.error().message << "\n";
      return 1;
    }
    truth_bus = std::move(*bus);
  }
  auto simulator = sim::FriSimulator::Create(options);
  if (!simulator.ok()) {
    std::cerr << "error: " << simulator.error().message << "\n";
    return 1;
  }
  spdlog::info(
      "model={} joints={} client={}:{} period={} receive_multiplier={} drift_ppm={} "
      "noise={} loss={} delay_probability={} delay={} seed={} command_after={} "
      "truth_lcm_url={} truth_channel={}",
      model_path, options.model.JointCount(), options.client_host, options.client_port,
      options.period_s, options.receive_multiplier, options.drift_ppm, options.position_noise_rad,
      options.loss_probability, options.delay_probability, options.delay_s, options.seed,
      options.command_after_s, truth_url, truth_channel);
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  (*simulator)->Start();
  selfcal::joint_state_t truth;
  truth.num_joints = static_cast<std::int32_t>(options.model.JointCount());
  for (const JointSpec& joint : options.model.joints) truth.names.push_back(joint.name);
  truth.velocities.assign(options.model.JointCount(), 0.0);
  truth.efforts.assign(options.model.JointCount(), std::nan(""));
  const auto start = std::chrono::steady_clock::now();
  fri::SessionState last_state = fri::SessionState::kIdle;
  spdlog::info("FRI session: IDLE");
  while (!stop_requested) {
    // The truth feeds the sensor simulators, which cast each ray from the newest truth they have:
    // a 20 ms batch left rays cast from poses up to 20 ms old (a 5 mm floor in the demo chain).
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    for (const sim::FriSimSample& sample : (*simulator)->TakeSamples()) {
      if (sample.state != last_state) {
        spdlog::info("FRI session: {}", fri::ToString(sample.state));
        last_state = sample.state;
      }
      if (!truth_bus) continue;
      truth.utime = sample.host_us;
      truth.device_utime = sample.controller_us;
      truth.positions.assign(sample.true_position.data(),
                             sample.true_position.data() + sample.true_position.size());
      (void)truth_bus->Publish(truth_channel, truth);
    }
    if (duration_s > 0 &&
        std::chrono::steady_clock::now() - start > std::chrono::duration<double>(duration_s)) {
      break;
    }
  }
  (*simulator)->Stop();
  const auto stats = (*simulator)->stats();
  spdlog::info(
      "stopping: {} cycles, {} sent, {} dropped, {} delayed, {} replies ({} late, {} "
      "dropped), {} velocity violations, {} sessions lost",
      stats.cycles, stats.sent, stats.dropped, stats.delayed, stats.replies, stats.late_replies,
      stats.replies_dropped, stats.velocity_violations, stats.sessions_lost);
  return 0;
}
