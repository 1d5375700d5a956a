// selfcal-sim-fri: a simulated KUKA Sunrise controller speaking FRI to a client on UDP
// (fri_simulator.h). Optionally publishes its ground truth (true joint positions, stamped with
// true host time) as selfcal.joint_state_t for tests and demos.
#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>

#include "protocols/bus/bus.h"
#include "protocols/lcm/channels.h"
#include "protocols/model_file/model_file.h"
#include "protocols/program/program.h"
#include "selfcal/joint_state_t.hpp"
#include "tools/sim_fri/fri_simulator.h"

namespace {

namespace program = selfcal::program;
using selfcal::sim::FriSimOptions;

constexpr program::About kAbout{
    "selfcal-sim-fri",
    "selfcal-sim-fri: simulated KUKA controller (robot side of FRI) on UDP. Walks "
    "the session states, follows commanded positions through a joint servo model, "
    "reports noisy measured positions with a drifting controller clock; packet loss "
    "and delay on demand."};

struct Settings {
  FriSimOptions sim;
  std::string model_path = program::InstalledConfig("robots/kuka_lbr_iiwa_r840.yaml");
  std::string truth_url;
  std::string truth_channel = selfcal::channels::kSimJointTruth;
  std::vector<double> initial;
  std::vector<double> loss_burst;  // {probability, seconds}: a burst of loss on SIGUSR1
  double duration_s = 0;
};

// Set by SIGUSR1: a fault injector (tests/faults/run_faults) asks for a burst of loss.
std::atomic<bool> burst_requested{false};
void RequestBurst(int) { burst_requested = true; }

void DescribeOptions(program::Program& p, Settings& s) {
  auto& o = s.sim;
  p.Option("--model", s.model_path, "Robot model file (joint count and limits)");
  p.Option("--client-host", o.client_host, "IPv4 address of the FRI client");
  p.Option("--client-port", o.client_port, "UDP port of the FRI client");
  p.Option("--period", o.period_s, "FRI send period [s]")->check(CLI::Range(0.001, 0.1));
  p.Option("--receive-multiplier", o.receive_multiplier, "Send periods per expected reply");
  p.Option("--drift-ppm", o.drift_ppm, "Controller clock drift [ppm]");
  p.Option("--noise", o.position_noise_rad, "Measured position noise sigma [rad]");
  p.Option("--loss", o.loss_probability, "Loss probability of each datagram")
      ->check(CLI::Range(0.0, 1.0));
  p.Option("--delay-probability", o.delay_probability, "Probability that a datagram is delayed")
      ->check(CLI::Range(0.0, 1.0));
  p.Option("--delay", o.delay_s, "Delay of a delayed datagram [s]");
  p.Option("--seed", o.seed, "Random seed (noise, loss, delay)");
  p.Option("--loss-burst", s.loss_burst,
           "P S: on SIGUSR1, drop each datagram with probability P for S seconds, then --loss "
           "again")
      ->expected(2);
  p.Option("--command-after", o.command_after_s,
           "Start commanding this long after MONITORING_READY [s] (< 0: never)");
  p.Option("--initial-position", s.initial, "Initial joint positions [rad]")->expected(-1);
  p.Option("--truth-lcm-url", s.truth_url,
           "Publish ground truth joint states on this LCM URL (empty: do not)");
  p.Option("--truth-channel", s.truth_channel, "Channel of the ground truth");
  p.DurationOption(s.duration_s);
}

// Publishes the simulator's true joint positions, stamped with true host time.
class TruthPublisher {
 public:
  TruthPublisher(selfcal::Bus* bus, std::string channel, const selfcal::RobotModel& model)
      : bus_(bus), channel_(std::move(channel)) {
    message_.num_joints = static_cast<std::int32_t>(model.JointCount());
    for (const selfcal::JointSpec& joint : model.joints) message_.names.push_back(joint.name);
    message_.velocities.assign(model.JointCount(), 0.0);
    message_.efforts.assign(model.JointCount(), std::nan(""));
  }
  void Publish(const selfcal::sim::FriSimSample& sample) {
    if (bus_ == nullptr) return;
    message_.utime = sample.host_us;
    message_.device_utime = sample.controller_us;
    message_.positions.assign(sample.true_position.data(),
                              sample.true_position.data() + sample.true_position.size());
    (void)bus_->Publish(channel_, message_);
  }

 private:
  selfcal::Bus* bus_;
  std::string channel_;
  selfcal::joint_state_t message_;
};

// A burst of loss: from SIGUSR1 for its seconds, then the configured loss again.
class LossBurst {
 public:
  LossBurst(std::vector<double> burst, double base) : burst_(std::move(burst)), base_(base) {
    if (burst_.size() == 2) std::signal(SIGUSR1, RequestBurst);
  }
  void Poll(selfcal::sim::FriSimulator& simulator) {
    const auto now = std::chrono::steady_clock::now();
    if (burst_requested.exchange(false) && burst_.size() == 2) {
      simulator.SetLoss(burst_[0]);
      end_ = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                       std::chrono::duration<double>(burst_[1]));
      active_ = true;
      spdlog::info("loss burst: {} of the datagrams for {} s", burst_[0], burst_[1]);
    } else if (active_ && now >= end_) {
      simulator.SetLoss(base_);
      active_ = false;
      spdlog::info("loss burst over");
    }
  }

 private:
  std::vector<double> burst_;
  double base_;
  bool active_ = false;
  std::chrono::steady_clock::time_point end_;
};

void Run(selfcal::sim::FriSimulator& simulator, TruthPublisher& truth, LossBurst& burst,
         double duration_s) {
  simulator.Start();
  selfcal::fri::SessionState last_state = selfcal::fri::SessionState::kIdle;
  spdlog::info("FRI session: IDLE");
  (void)program::RunUntilStopped(duration_s, [&]() -> selfcal::Status {
    // The truth feeds the sensor simulators, which cast each ray from the newest truth they have:
    // a 20 ms batch left rays cast from poses up to 20 ms old (a 5 mm floor in the demo chain).
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    burst.Poll(simulator);
    for (const selfcal::sim::FriSimSample& sample : simulator.TakeSamples()) {
      if (sample.state != last_state) {
        spdlog::info("FRI session: {}", selfcal::fri::ToString(sample.state));
        last_state = sample.state;
      }
      truth.Publish(sample);
    }
    return selfcal::OkStatus();
  });
  simulator.Stop();
  const auto stats = simulator.stats();
  spdlog::info(
      "stopping: {} cycles, {} sent, {} dropped, {} delayed, {} replies ({} late, {} "
      "dropped), {} velocity violations, {} sessions lost",
      stats.cycles, stats.sent, stats.dropped, stats.delayed, stats.replies, stats.late_replies,
      stats.replies_dropped, stats.velocity_violations, stats.sessions_lost);
}

// Everything after the command line: read files, open the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  auto model = selfcal::ReadModelFile(s.model_path);
  if (!model.ok()) return program::Fail(model.error().message);
  s.sim.model = model->model;
  if (!s.initial.empty()) {
    s.sim.initial_position =
        Eigen::Map<Eigen::VectorXd>(s.initial.data(), static_cast<Eigen::Index>(s.initial.size()));
  }
  std::unique_ptr<selfcal::Bus> truth_bus;
  if (!s.truth_url.empty()) {
    auto bus = program.OpenBus(s.truth_url);
    if (!bus.ok()) return program::Fail(bus.error().message);
    truth_bus = std::move(*bus);
  }
  auto simulator = selfcal::sim::FriSimulator::Create(s.sim);
  if (!simulator.ok()) return program::Fail(simulator.error().message);
  program.EchoValue("joints", [&] { return std::to_string(s.sim.model.JointCount()); });
  program.LogConfiguration();
  if (!s.loss_burst.empty() &&
      (s.loss_burst[0] < 0 || s.loss_burst[0] > 1 || !(s.loss_burst[1] > 0))) {
    return program::Fail("--loss-burst: want a probability in [0, 1] and seconds > 0",
                         program::kExitUsage);
  }
  TruthPublisher truth(truth_bus.get(), s.truth_channel, s.sim.model);
  LossBurst burst(s.loss_burst, s.sim.loss_probability);
  Run(**simulator, truth, burst, s.duration_s);
  return program::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}
