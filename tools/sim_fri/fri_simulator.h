// A simulated KUKA Sunrise controller, the robot side of FRI, on UDP: it walks the session
// states IDLE -> MONITORING_WAIT -> MONITORING_READY -> COMMANDING_WAIT -> COMMANDING_ACTIVE,
// sends monitoring messages every period to the client's port, takes commanded positions from
// the replies, moves a simple joint servo model (critically damped, velocity feed-forward) and
// reports measured positions with noise, stamped with a controller clock that drifts. Packet
// loss and delay on demand. Used as a process (selfcal-sim-fri) and in-process by tests.
//
// Session rules of this simulator (ours; the real controller's thresholds are not public):
//  - IDLE for `idle_cycles`; the client must not answer.
//  - MONITORING_WAIT until the last `quality_window` cycles were answered well (quality GOOD).
//  - MONITORING_READY; commanding starts when requested (RequestCommanding or
//    `command_after_s`) and the quality is at least GOOD.
//  - COMMANDING_WAIT until `commanding_wait_cycles` replies in a row echo the IPO position.
//  - COMMANDING_ACTIVE until commanding is ended (-> MONITORING_READY) or the quality drops to
//    POOR (-> MONITORING_WAIT: the session is lost, the arm holds).
//  Quality: share of the last `quality_window` cycles answered before the next cycle:
//  >= 0.95 EXCELLENT, >= 0.8 GOOD, >= 0.6 FAIR, else POOR.
//  A commanded step faster than the joint's velocity limit is counted as a violation, clamped.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "protocols/fri/fri_messages.h"

namespace selfcal::sim {

struct FriSimOptions {
  std::string client_host = "127.0.0.1";
  std::uint16_t client_port = 30200;
  RobotModel model;                  // joint count and limits
  Eigen::VectorXd initial_position;  // rad; empty = zeros
  double period_s = 0.005;           // FRI send period
  std::uint32_t receive_multiplier = 1;
  double drift_ppm = 0.0;            // controller clock runs fast by this much
  double clock_offset_s = 1.0e6;     // controller clock at start [s]
  double position_noise_rad = 1e-5;  // measured = true + N(0, sigma)
  double servo_bandwidth_hz = 15.0;  // natural frequency of the joint servo
  double loss_probability = 0.0;     // each monitoring message and each reply
  double delay_probability = 0.0;    // a monitoring message is held back by delay_s
  double delay_s = 0.003;
  std::uint32_t seed = 1;
  int idle_cycles = 20;
  int quality_window = 100;
  int commanding_wait_cycles = 10;
  double command_after_s = 0.0;  // commanding starts this long after each MONITORING_READY;
                                 // < 0: only RequestCommanding() starts it
};

// One simulated cycle, for tests and the truth channel.
struct FriSimSample {
  std::int64_t host_us = 0;        // host time (CLOCK_REALTIME) at which the sample was taken
  std::int64_t controller_us = 0;  // the controller clock at that instant (sent in the message)
  fri::SessionState state = fri::SessionState::kIdle;
  Eigen::VectorXd true_position;  // the servo model's position, no noise
  Eigen::VectorXd commanded;      // commanded position in effect
  bool command_received = false;  // a fresh commanded position arrived for this cycle
};

struct FriSimStats {
  std::uint64_t cycles = 0, sent = 0, dropped = 0, delayed = 0;
  std::uint64_t replies = 0, replies_dropped = 0, late_replies = 0, decode_errors = 0;
  std::uint64_t replies_in_idle = 0;      // protocol violations by the client
  std::uint64_t wrong_reflection = 0;     // reply reflects no sequence we sent
  std::uint64_t velocity_violations = 0;  // commanded steps above the velocity limit
  std::uint64_t sessions_lost = 0;        // COMMANDING_ACTIVE -> MONITORING_WAIT
  double max_step_ratio = 0;              // largest commanded step / (v_max * cycles)
};

// The joint servo over one controller cycle that lasted `interval_s` (a loaded machine makes a
// cycle run later than the period): the interpolator ramps the reference from `commanded -
// feed_forward * interval_s` to `commanded` over the interval (as the controller's IPO does), and
// the servo, critically damped at `bandwidth_hz` with velocity feed-forward, follows it from
// `position`, `velocity`. Semi-implicit Euler steps h with w h <= 0.05 (w = 2 pi bandwidth),
// however long the interval: the step is stable only for w h < 2 sqrt(2) - 2 = 0.83, and the
// fixed 10 steps it once took left that bound for cycles over 88 ms late at 15 Hz (tools/demo on
// a loaded machine: one cycle 104 ms late turned a 20 mrad tracking error into a 0.58 rad jump of
// the simulated arm, and selfcald failed the session on its deviation check).
void AdvanceServo(double bandwidth_hz, double interval_s, const Eigen::VectorXd& commanded,
                  const Eigen::VectorXd& feed_forward, Eigen::VectorXd& position,
                  Eigen::VectorXd& velocity);

class FriSimulator {
 public:
  static Expected<std::unique_ptr<FriSimulator>> Create(const FriSimOptions& options);
  ~FriSimulator();

  void Start();  // runs the controller loop in a thread
  void Stop();

  fri::SessionState state() const;
  fri::ConnectionQuality quality() const;
  FriSimStats stats() const;
  std::uint16_t local_port() const { return local_port_; }

  // The robot application starts (true) or ends (false) an FRI overlay motion.
  void RequestCommanding(bool on);
  void SetLoss(double probability);
  void SetDelay(double probability, double delay_s);

  // Truth: host time [us] of a controller timestamp [us].
  std::int64_t ControllerToHostUs(std::int64_t controller_us) const;
  // Samples recorded since the last call (the loop keeps at most the last 60 s).
  std::vector<FriSimSample> TakeSamples();
  Eigen::VectorXd TruePosition() const;

 private:
  explicit FriSimulator(const FriSimOptions& options);
  void Loop();
  void Cycle(std::int64_t host_us);
  void ReceiveReplies();
  void SendDue(std::int64_t now_host_us, bool flush_all);
  void UpdateState();

  FriSimOptions options_;
  int socket_ = -1;
  std::uint16_t local_port_ = 0;
  std::thread thread_;
  std::atomic<bool> running_{false};
  mutable std::mutex mutex_;

  std::mt19937_64 random_;
  std::int64_t start_host_us_ = 0;
  std::int64_t start_controller_us_ = 0;
  fri::SessionState state_ = fri::SessionState::kIdle;
  fri::ConnectionQuality quality_ = fri::ConnectionQuality::kPoor;
  int cycles_in_state_ = 0;
  int echo_cycles_ = 0;
  bool commanding_requested_ = false;
  std::uint32_t sequence_ = 0;
  std::vector<bool> answered_;  // ring over quality_window cycles
  std::size_t answered_head_ = 0;
  bool answered_this_cycle_ = false;
  std::uint64_t cycles_since_command_ = 1;
  std::int64_t last_sent_stamp_us_ = 0;      // controller time of the last message sent
  std::int64_t last_command_stamp_us_ = -1;  // ... of the message the last setpoint answered
  std::int64_t previous_cycle_host_us_ = -1;

  Eigen::VectorXd true_position_, true_velocity_, commanded_, previous_commanded_, feed_forward_;
  std::optional<Eigen::VectorXd> pending_command_;
  bool pending_echo_ok_ = false;

  struct Outgoing {
    std::int64_t due_host_us;
    std::vector<std::uint8_t> bytes;
  };
  std::vector<Outgoing> outgoing_;
  std::vector<FriSimSample> samples_;
  FriSimStats stats_;
};

}  // namespace selfcal::sim
