// selfcal-iiwa against the FRI simulator over UDP on 127.0.0.1 (both real sockets; the driver
// binds port 0 and the simulator sends to it). Session walk-through, trajectories, refusals,
// expiring setpoints, loss and delay, clock mapping, Drake's IIWA_STATUS.
#include <gtest/gtest.h>

#include <cmath>

#include "core/timing/host_clock.h"
#include "core/trajectory/motion.h"
#include "drake/lcmt_iiwa_command.hpp"
#include "protocols/trajectory/trajectory_message.h"
#include "protocols/trajectory/trajectory_signature.h"
#include "tests/iiwa/fri_harness.h"

namespace selfcal::testing {
namespace {

using fri::SessionState;
using Status_t = selfcal::robot_driver_status_t;

sim::FriSimOptions FastSim() {
  sim::FriSimOptions o;
  o.period_s = 0.002;
  o.idle_cycles = 10;
  o.quality_window = 50;
  o.commanding_wait_cycles = 5;
  o.command_after_s = 0.05;
  return o;
}

// Signed with the harness's key, as the daemon signs what it sends.
selfcal::joint_trajectory_t Signed(selfcal::joint_trajectory_t message) {
  SignTrajectory(message, TestKey());
  return message;
}

// Drake's IIWA_COMMAND is followed only when asked to.
iiwa::DriverOptions FollowingIiwaCommand() {
  iiwa::DriverOptions o;
  o.follow_iiwa_command = true;
  return o;
}

std::vector<std::string> Names() { return {"A1", "A2", "A3", "A4", "A5", "A6", "A7"}; }

trajectory::JointLimits Limits() { return trajectory::LimitsFromModel(IiwaModel()); }

// The simulated arm's servo over one cycle, the cycle on time (5 ms) or late (a loaded machine:
// 55 ms, and 100 ms, the longest the simulator integrates): tracking a ramp at 0.87 rad/s with a
// 20 mrad error and the ramp's velocity, the error decays as the critically damped servo's does,
// e(t) = e0 (1 + w t) exp(-w t), within 1 mrad (the discrete reference leads by one step, ff h),
// and the velocity as the ramp's plus -e'(t) = e0 w^2 t exp(-w t), within 0.05 rad/s.
// With a fixed 10 steps a 100 ms cycle came out 0.21 rad off: the step was unstable.
TEST(IiwaFri, TheSimulatedServoFollowsItsModelWhenACycleRunsLate) {
  const double bandwidth_hz = sim::FriSimOptions{}.servo_bandwidth_hz;
  const double w = 2 * M_PI * bandwidth_hz;
  for (const double interval : {0.005, 0.055, 0.1}) {
    const Eigen::VectorXd commanded = Eigen::VectorXd::Constant(7, 1.0);
    const Eigen::VectorXd feed_forward = Eigen::VectorXd::Constant(7, 0.87);
    const double e0 = 0.02;
    Eigen::VectorXd position = commanded - feed_forward * interval;
    position.array() -= e0;
    Eigen::VectorXd velocity = feed_forward;
    sim::AdvanceServo(bandwidth_hz, interval, commanded, feed_forward, position, velocity);
    const double error = e0 * (1 + w * interval) * std::exp(-w * interval);
    const double speed = 0.87 + e0 * w * w * interval * std::exp(-w * interval);
    EXPECT_NEAR(commanded[0] - position[0], error, 1e-3) << "cycle of " << interval << " s";
    EXPECT_NEAR(velocity[0], speed, 0.05) << "cycle of " << interval << " s";
  }
}

// Latest measured joint state as published (waits for the clock filter to settle first).
Eigen::VectorXd LastMeasured(FriHarness& h) {
  EXPECT_TRUE(h.SpinUntil([&] { return !h.joint_states.empty(); }, 3.0));
  if (h.joint_states.empty()) return Eigen::VectorXd::Zero(7);
  const auto& p = h.joint_states.back().positions;
  return Eigen::Map<const Eigen::VectorXd>(p.data(), 7);
}

TEST(IiwaFri, FullSessionWalkThrough) {
  sim::FriSimOptions o = FastSim();
  o.command_after_s = -1;  // the robot application starts commanding when we say so
  FriHarness h(o);
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kMonitoringReady, 5.0));
  h.SpinFor(0.05);
  h.sim().RequestCommanding(true);
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  // Joint states start once the clock filter has settled (0.5 s of samples).
  ASSERT_TRUE(h.SpinUntil([&] { return h.joint_states.size() >= 10; }, 3.0));
  // The simulator left COMMANDING_ACTIVE only when asked.
  h.sim().RequestCommanding(false);
  ASSERT_TRUE(h.WaitForState(SessionState::kMonitoringReady, 2.0));
  h.SpinFor(0.1);

  // The controller walked every state in order, and the driver saw each change.
  std::vector<SessionState> walked;
  for (const auto& s : h.sim().TakeSamples()) {
    if (walked.empty() || walked.back() != s.state) walked.push_back(s.state);
  }
  const std::vector<SessionState> expected = {SessionState::kIdle,
                                              SessionState::kMonitoringWait,
                                              SessionState::kMonitoringReady,
                                              SessionState::kCommandingWait,
                                              SessionState::kCommandingActive,
                                              SessionState::kMonitoringReady};
  EXPECT_EQ(walked, expected);
  std::vector<std::string> seen;
  for (const auto& s : h.statuses) {
    if (s.event == Status_t::EVENT_SESSION) seen.push_back(s.message);
  }
  EXPECT_EQ(seen,
            (std::vector<std::string>{"IDLE", "MONITORING_WAIT", "MONITORING_READY",
                                      "COMMANDING_WAIT", "COMMANDING_ACTIVE", "MONITORING_READY"}));
  // Reply rules: nothing in IDLE, every reply reflects the message it answers.
  const auto stats = h.sim().stats();
  EXPECT_EQ(stats.replies_in_idle, 0u);
  EXPECT_EQ(stats.wrong_reflection, 0u);
  EXPECT_EQ(stats.decode_errors, 0u);
  EXPECT_GT(stats.replies, 100u);
  EXPECT_EQ(h.driver().decode_errors(), 0);
  // Joint states were published, with the model's names, once the clock had settled.
  ASSERT_FALSE(h.joint_states.empty());
  EXPECT_EQ(h.joint_states.front().names, Names());
  EXPECT_TRUE(h.driver().clock().settled());
  EXPECT_EQ(h.iiwa_status_bytes.size(), h.joint_states.size());

  // The controller goes silent: the driver reports it.
  h.sim().Stop();
  ASSERT_TRUE(h.SpinUntil([&] { return h.driver().session().session_state() == -1; }, 2.0));
  h.SpinFor(0.15);
  EXPECT_EQ(h.statuses.back().session_state, -1);
  bool reported = false;
  for (const auto& s : h.statuses) {
    reported = reported || s.message.find("controller silent") != std::string::npos;
  }
  EXPECT_TRUE(reported);
}

// Plans from the published measured state, as the daemon does.
selfcal::joint_trajectory_t PlanMove(const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                     const std::string& id) {
  auto t = trajectory::PointToPoint(from, to, Limits());
  EXPECT_TRUE(t.ok());
  return ToMessage(*t, Names(), id, timing::RealtimeUs());
}

TEST(IiwaFri, TrajectoryIsTrackedWithinTheStatedBound) {
  FriHarness h(FastSim());
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd from = LastMeasured(h);
  Eigen::VectorXd to = from;
  to[0] += 0.6;
  to[3] += 0.3;
  to[6] -= 0.5;
  auto planned = trajectory::PointToPoint(from, to, Limits());
  ASSERT_TRUE(planned.ok());
  ASSERT_TRUE(h.bus()
                  .Publish(channels::kJointTrajectory,
                           Signed(ToMessage(*planned, Names(), "move-1", timing::RealtimeUs())))
                  .ok());
  h.sim().TakeSamples();
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_ACCEPTED, "move-1", 1.0))
      << (h.statuses.empty() ? "" : h.statuses.back().message);
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_COMPLETED, "move-1", planned->duration() + 2.0));
  h.SpinFor(0.3);
  const std::int64_t start_us = h.driver().session().trajectory_start_device_us();
  ASSERT_GT(start_us, 0);
  const auto samples = h.sim().TakeSamples();
  // Setpoints: the command arriving in cycle k was computed for the message of cycle k-1.
  double setpoint_error = 0, true_error = 0, lagged_error = 0, max_lag = 0;
  int compared = 0, stalls = 0;
  const double period = 0.002;
  std::int64_t stall_end_us = -1;
  for (std::size_t k = 1; k < samples.size(); ++k) {
    // A simulator thread descheduled for more than 10 periods (a machine overloaded by other
    // tests) is not a controller any more: the 50 ms after such a stall are not judged.
    if (samples[k].controller_us - samples[k - 1].controller_us > 10 * 2000) {
      ++stalls;
      stall_end_us = samples[k].controller_us + 50000;
    }
    if (samples[k].controller_us <= stall_end_us) continue;
    const double t = static_cast<double>(samples[k - 1].controller_us - start_us) * 1e-6;
    if (t < 0 || t > planned->duration()) continue;
    if (samples[k].command_received) {
      setpoint_error =
          std::max(setpoint_error,
                   (samples[k].commanded - planned->Evaluate(t).position).cwiseAbs().maxCoeff());
      ++compared;
    }
    const double t_true = static_cast<double>(samples[k].controller_us - start_us) * 1e-6;
    true_error = std::max(
        true_error,
        (samples[k].true_position - planned->Evaluate(t_true).position).cwiseAbs().maxCoeff());
    // Path error: distance to the nearest point of the plan within the last 25 cycles (the arm
    // lags the plan in time: one cycle for the reply, one for the servo, more when a reply
    // misses its cycle and the controller holds).
    double nearest = 1e9, nearest_lag = 0;
    for (int j = 0; j <= 500; ++j) {
      const double lag = 25 * period * j / 500.0;
      const double e = (samples[k].true_position - planned->Evaluate(t_true - lag).position)
                           .cwiseAbs()
                           .maxCoeff();
      if (e < nearest) {
        nearest = e;
        nearest_lag = lag;
      }
    }
    lagged_error = std::max(lagged_error, nearest);
    max_lag = std::max(max_lag, nearest_lag);
  }
  std::printf(
      "trajectory: %.3f s, %d setpoints compared, max setpoint error %.2e rad, "
      "max true-arm error %.2e rad at the same instant, max path error %.2e rad, "
      "largest lag %.1f ms, %d simulator stalls excluded\n",
      planned->duration(), compared, setpoint_error, true_error, lagged_error, max_lag * 1e3,
      stalls);
  // Most cycles carried a fresh setpoint (a loaded machine may delay a few replies).
  if (stalls == 0) {
    EXPECT_GT(compared, static_cast<int>(planned->duration() / 0.002) / 2);
  }
  // Stated bounds: setpoints follow the plan to within the start offset (measured vs commanded,
  // <= 1e-4 rad here); the simulated arm stays within 1 mrad of the planned path. In time it
  // lags (two cycles, more when a reply misses its cycle on a loaded machine): the error at
  // the same instant is printed, not bounded.
  EXPECT_LT(setpoint_error, 1e-4);
  EXPECT_LT(lagged_error, 1e-3);
  // The arm ended where planned and no command was faster than the limits.
  EXPECT_LT((h.sim().TruePosition() - to).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_EQ(h.sim().stats().velocity_violations, 0u);
  EXPECT_LE(h.sim().stats().max_step_ratio, 1.01);
  // The driver's guard clamps a step only after a stall (its time step is capped at 0.1 s).
  EXPECT_LE(h.driver().session().limited_cycles(), stalls);
}

TEST(IiwaFri, OutOfLimitAndBadTrajectoriesAreRefusedWithAReason) {
  sim::FriSimOptions o = FastSim();
  o.command_after_s = -1;
  FriHarness h(o, FollowingIiwaCommand());
  // Before commanding: refused because of the session state.
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kMonitoringReady, 5.0));
  {
    Eigen::VectorXd from = LastMeasured(h), to = from;
    to[0] += 0.1;
    ASSERT_TRUE(
        h.bus().Publish(channels::kJointTrajectory, Signed(PlanMove(from, to, "early"))).ok());
    ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_REFUSED, "early", 1.0));
    EXPECT_NE(h.statuses[static_cast<std::size_t>(h.FindEvent(Status_t::EVENT_REFUSED, "early"))]
                  .message.find("not COMMANDING_ACTIVE"),
              std::string::npos);
  }
  h.sim().RequestCommanding(true);
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd here = LastMeasured(h);
  const Eigen::VectorXd commanded_before = h.driver().session().commanded();
  auto expect_refused = [&](const selfcal::joint_trajectory_t& message, const std::string& words) {
    const std::size_t from = h.statuses.size();
    ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, Signed(message)).ok());
    ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_REFUSED, message.trajectory_id, 1.0, from))
        << message.trajectory_id;
    const auto& status = h.statuses[static_cast<std::size_t>(
        h.FindEvent(Status_t::EVENT_REFUSED, message.trajectory_id, from))];
    EXPECT_NE(status.message.find(words), std::string::npos)
        << message.trajectory_id << ": " << status.message;
    EXPECT_EQ(h.FindEvent(Status_t::EVENT_ACCEPTED, message.trajectory_id), -1);
  };
  // Beyond A2's position limit (2.094 rad), planned with wider limits.
  {
    trajectory::JointLimits wide = Limits();
    wide.lower.array() -= 1.0;
    wide.upper.array() += 1.0;
    Eigen::VectorXd to = here;
    to[1] = 2.5;
    auto t = trajectory::PointToPoint(here, to, wide);
    ASSERT_TRUE(t.ok());
    expect_refused(ToMessage(*t, Names(), "beyond-position", timing::RealtimeUs()), "A2 at t=");
  }
  // Too fast: planned with twice the velocity and acceleration limits.
  {
    trajectory::JointLimits fast = Limits();
    fast.max_velocity *= 2;
    fast.max_acceleration *= 2;
    fast.max_jerk *= 2;
    Eigen::VectorXd to = here;
    to[0] += 1.5;
    auto t = trajectory::PointToPoint(here, to, fast);
    ASSERT_TRUE(t.ok());
    expect_refused(ToMessage(*t, Names(), "too-fast", timing::RealtimeUs()), "above the limit");
  }
  // Not starting at the current position.
  {
    Eigen::VectorXd from = here, to = here;
    from[4] += 0.05;
    to[4] += 0.2;
    expect_refused(PlanMove(from, to, "elsewhere"), "rad from the current position at A5");
  }
  // Wrong joint names.
  {
    Eigen::VectorXd to = here;
    to[0] += 0.1;
    auto message = PlanMove(here, to, "names");
    message.joint_names[2] = "J3";
    expect_refused(message, "joint_names[2]");
  }
  // Knots out of order.
  {
    Eigen::VectorXd to = here;
    to[0] += 0.1;
    auto message = PlanMove(here, to, "order");
    std::swap(message.time_from_start[1], message.time_from_start[2]);
    expect_refused(message, "does not increase");
  }
  // An IIWA_COMMAND beyond the limits.
  {
    drake::lcmt_iiwa_command command;
    command.utime = timing::RealtimeUs();
    command.num_joints = 7;
    command.joint_position.assign(here.data(), here.data() + 7);
    command.joint_position[6] = 3.2;
    command.num_torques = 0;
    const std::size_t from = h.statuses.size();
    ASSERT_TRUE(h.bus().Publish(channels::kIiwaCommand, command).ok());
    ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_REFUSED, "IIWA_COMMAND", 1.0, from));
  }
  h.SpinFor(0.1);
  // Nothing moved.
  EXPECT_LT((h.driver().session().commanded() - commanded_before).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((h.sim().TruePosition() - here).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(IiwaFri, ExpiredSetpointsStopTheMotion) {
  FriHarness h(FastSim(), FollowingIiwaCommand());
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  Eigen::VectorXd q = h.driver().session().commanded();
  const double speed = 0.8;  // rad/s on A1
  drake::lcmt_iiwa_command command;
  command.num_joints = 7;
  command.num_torques = 0;
  // Stream 200 Hz setpoints for 0.6 s, then fall silent.
  const auto start = std::chrono::steady_clock::now();
  auto last_send = start - std::chrono::seconds(1);
  const double stream_s = 0.6;
  bool first = true;
  while (std::chrono::steady_clock::now() - start < std::chrono::duration<double>(stream_s)) {
    if (std::chrono::steady_clock::now() - last_send >= std::chrono::milliseconds(5)) {
      if (!first) q[0] += speed * 0.005;  // the stream starts where the arm is
      first = false;
      command.utime = timing::RealtimeUs();
      command.joint_position.assign(q.data(), q.data() + 7);
      ASSERT_TRUE(h.bus().Publish(channels::kIiwaCommand, command).ok());
      last_send = std::chrono::steady_clock::now();
    }
    ASSERT_TRUE(h.driver().SpinOnce(std::chrono::microseconds(500)).ok());
  }
  ASSERT_GE(h.FindEvent(Status_t::EVENT_ACCEPTED), 0);
  h.sim().TakeSamples();
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_STOPPED, "", 1.0));
  const auto& stopped = h.statuses[static_cast<std::size_t>(h.FindEvent(Status_t::EVENT_STOPPED))];
  EXPECT_NE(stopped.message.find("expired"), std::string::npos) << stopped.message;
  h.SpinFor(0.5);
  const auto samples = h.sim().TakeSamples();
  ASSERT_GT(samples.size(), 100u);
  // The commanded motion decelerated within A1's acceleration limit (5 rad/s^2, a little margin
  // for the discrete steps) and came to rest: the last 0.2 s do not move.
  // Only over three consecutive cycles with fresh setpoints: a missing reply makes the simulator
  // hold one cycle, which is no deceleration of the command.
  // The setpoint arriving in cycle k was computed for the message of cycle k-1: its time step
  // is the controller time between the messages k-2 and k-1.
  double max_deceleration = 0;
  auto stamp = [&](std::size_t k) { return static_cast<double>(samples[k].controller_us) * 1e-6; };
  for (std::size_t k = 3; k < samples.size(); ++k) {
    if (!samples[k].command_received || !samples[k - 1].command_received ||
        !samples[k - 2].command_received) {
      continue;
    }
    const double dt = stamp(k - 1) - stamp(k - 2);
    const double dt_before = stamp(k - 2) - stamp(k - 3);
    const double v = (samples[k].commanded[0] - samples[k - 1].commanded[0]) / dt;
    const double v_before = (samples[k - 1].commanded[0] - samples[k - 2].commanded[0]) / dt_before;
    max_deceleration = std::max(max_deceleration, -(v - v_before) / dt);
  }
  EXPECT_LT(max_deceleration, 5.0 * 1.1);
  const auto& last = samples.back().commanded;
  const auto& earlier = samples[samples.size() - 100].commanded;  // 0.2 s before
  EXPECT_LT((last - earlier).cwiseAbs().maxCoeff(), 1e-12);
  // Stopping distance after the last setpoint: at most v^2 / (2 a) + the expiry interval.
  EXPECT_LT(last[0] - q[0], speed * speed / (2 * 5.0) + speed * 0.05 + 1e-3);
  EXPECT_EQ(h.driver().session().command_source(), Status_t::SOURCE_HOLD);
  EXPECT_EQ(h.sim().stats().velocity_violations, 0u);
}

TEST(IiwaFri, LossAndDelayAreReportedWithoutJumps) {
  sim::FriSimOptions o = FastSim();
  // Drake's 5 ms period: at 2 ms a loaded test machine adds its own missed replies to the 5 %,
  // and the simulator may then (rightly) end the session.
  o.period_s = 0.005;
  o.loss_probability = 0.05;
  o.delay_probability = 0.05;
  o.delay_s = 0.007;  // longer than the period: delayed messages arrive after newer ones
  o.seed = 7;
  FriHarness h(o);
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 8.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd from = LastMeasured(h);
  Eigen::VectorXd to = from;
  to[1] += 0.4;
  to[5] -= 0.6;
  auto planned = trajectory::PointToPoint(from, to, Limits());
  ASSERT_TRUE(planned.ok());
  h.sim().TakeSamples();
  ASSERT_TRUE(h.bus()
                  .Publish(channels::kJointTrajectory,
                           Signed(ToMessage(*planned, Names(), "lossy", timing::RealtimeUs())))
                  .ok());
  const bool completed =
      h.WaitForEvent(Status_t::EVENT_COMPLETED, "lossy", planned->duration() + 3.0);
  for (const auto& s : h.statuses) {
    if (!completed && s.event != Status_t::EVENT_PERIODIC)
      std::printf("event %d: %s\n", s.event, s.message.c_str());
  }
  ASSERT_TRUE(completed);
  h.SpinFor(0.25);
  const auto samples = h.sim().TakeSamples();
  const auto stats = h.sim().stats();
  std::printf(
      "sim: %llu cycles, %llu dropped, %llu delayed, %llu replies dropped, "
      "%llu late replies; driver: lost %lld, late %lld\n",
      static_cast<unsigned long long>(stats.cycles), static_cast<unsigned long long>(stats.dropped),
      static_cast<unsigned long long>(stats.delayed),
      static_cast<unsigned long long>(stats.replies_dropped),
      static_cast<unsigned long long>(stats.late_replies),
      static_cast<long long>(h.driver().session().messages_lost()),
      static_cast<long long>(h.driver().session().messages_late()));
  // Reported: the status counts losses and late messages.
  h.SpinFor(0.15);
  ASSERT_FALSE(h.statuses.empty());
  EXPECT_GT(h.statuses.back().messages_lost, 0);
  EXPECT_GT(h.statuses.back().messages_late, 0);
  EXPECT_GT(stats.dropped, 0u);
  // No jumps: no commanded step faster than the velocity limit, no session lost.
  EXPECT_EQ(stats.velocity_violations, 0u);
  EXPECT_LE(stats.max_step_ratio, 1.01);
  EXPECT_EQ(stats.sessions_lost, 0u);
  // No jump of the arm: between samples no joint moved faster than 1.2 times its limit (the
  // servo may overshoot a little when it catches up after a held cycle).
  const trajectory::JointLimits limits = Limits();
  double worst_ratio = 0;
  for (std::size_t k = 1; k < samples.size(); ++k) {
    const double dt =
        static_cast<double>(samples[k].controller_us - samples[k - 1].controller_us) * 1e-6;
    const Eigen::VectorXd v = (samples[k].true_position - samples[k - 1].true_position) / dt;
    worst_ratio = std::max(worst_ratio, v.cwiseAbs().cwiseQuotient(limits.max_velocity).maxCoeff());
  }
  std::printf("fastest joint between samples: %.2f of its velocity limit\n", worst_ratio);
  EXPECT_LT(worst_ratio, 1.2);
  EXPECT_LT((h.sim().TruePosition() - to).cwiseAbs().maxCoeff(), 1e-3);
  // Published joint states keep increasing in time.
  for (std::size_t k = 1; k < h.joint_states.size(); ++k) {
    ASSERT_GT(h.joint_states[k].device_utime, h.joint_states[k - 1].device_utime);
    ASSERT_GT(h.joint_states[k].utime, h.joint_states[k - 1].utime);
  }
}

void ExpectTimestampsWithinHalfAMillisecond(double drift_ppm) {
  sim::FriSimOptions o = FastSim();
  o.period_s = 0.002;
  o.drift_ppm = drift_ppm;
  o.command_after_s = -1;
  FriHarness h(o);
  h.Start();
  ASSERT_TRUE(h.SpinUntil([&] { return h.joint_states.size() >= 1000; }, 8.0));
  double worst_us = 0, sum_us = 0;
  for (const auto& s : h.joint_states) {
    const double error = static_cast<double>(s.utime - h.sim().ControllerToHostUs(s.device_utime));
    worst_us = std::max(worst_us, std::abs(error));
    sum_us += error;
  }
  std::printf(
      "drift %+.0f ppm: %zu joint states, error mean %.1f us, worst %.1f us, "
      "estimated drift %.1f ppm\n",
      drift_ppm, h.joint_states.size(), sum_us / static_cast<double>(h.joint_states.size()),
      worst_us, h.driver().clock().drift_ppm());
  EXPECT_LT(worst_us, 500.0);
}

TEST(IiwaFri, JointStateTimestampsWithinHalfAMillisecondUnder50PpmDrift) {
  ExpectTimestampsWithinHalfAMillisecond(50.0);
  ExpectTimestampsWithinHalfAMillisecond(-50.0);
}

TEST(IiwaFri, IiwaStatusDecodesWithDrakesDefinition) {
  sim::FriSimOptions o = FastSim();
  o.command_after_s = -1;
  FriHarness h(o);
  h.Start();
  ASSERT_TRUE(h.SpinUntil([&] { return h.iiwa_status_bytes.size() >= 20; }, 5.0));
  h.sim().RequestCommanding(true);
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.05);
  bool saw_monitoring = false, saw_commanding = false;
  ASSERT_EQ(h.iiwa_status_bytes.size(), h.joint_states.size());
  for (std::size_t k = 0; k < h.iiwa_status_bytes.size(); ++k) {
    const auto& bytes = h.iiwa_status_bytes[k];
    ASSERT_EQ(bytes.size(), 412u);  // Drake's size for 7 joints
    std::uint64_t fingerprint = 0;
    for (int i = 0; i < 8; ++i)
      fingerprint = (fingerprint << 8) | bytes[static_cast<std::size_t>(i)];
    ASSERT_EQ(fingerprint, 0xf16fb804284abca3ULL);
    auto status = DecodeLcm<drake::lcmt_iiwa_status>(bytes, "IIWA_STATUS");
    ASSERT_TRUE(status.ok()) << status.error().message;
    const auto& js = h.joint_states[k];
    EXPECT_EQ(status->utime, js.utime);
    EXPECT_EQ(status->num_joints, 7);
    EXPECT_EQ(status->joint_position_measured, js.positions);
    EXPECT_EQ(status->joint_velocity_estimated, js.velocities);
    EXPECT_EQ(status->joint_torque_measured, js.efforts);
    for (double t : status->joint_torque_external) EXPECT_EQ(t, 0.0);
    if (std::isnan(status->joint_position_ipo[0])) {
      saw_monitoring = true;
    } else {
      saw_commanding = true;
      EXPECT_EQ(status->joint_position_ipo, status->joint_position_commanded);
    }
  }
  EXPECT_TRUE(saw_monitoring);
  EXPECT_TRUE(saw_commanding);
}

TEST(IiwaFri, StopRequestBrakesATrajectory) {
  FriHarness h(FastSim());
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd from = LastMeasured(h);
  Eigen::VectorXd to = from;
  to[0] += 1.5;
  ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, Signed(PlanMove(from, to, "long"))).ok());
  h.SpinFor(0.6);
  ASSERT_GE(h.FindEvent(Status_t::EVENT_ACCEPTED, "long"), 0);
  selfcal::joint_trajectory_t stop;
  stop.utime = timing::RealtimeUs();
  stop.trajectory_id = "long";
  stop.num_joints = 0;
  stop.num_points = 0;
  stop.valid_until = 0;
  stop.tag_length = 0;
  ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, stop).ok());
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_STOPPED, "long", 1.0));
  h.SpinFor(0.8);
  EXPECT_EQ(h.driver().session().command_source(), Status_t::SOURCE_HOLD);
  EXPECT_EQ(h.FindEvent(Status_t::EVENT_COMPLETED, "long"), -1);
  // Stopped short of the goal, and no step above the limits.
  EXPECT_LT(h.sim().TruePosition()[0], to[0] - 0.2);
  EXPECT_EQ(h.sim().stats().velocity_violations, 0u);
}

// Drake's way of moving the arm: a synchronized profile streamed as IIWA_COMMAND at 100 Hz
// (half the FRI rate here). The driver interpolates the stream one period late: the setpoints
// follow the streamed path closely, within the limits, and end exactly at the last setpoint.
TEST(IiwaFri, A100HzCommandStreamIsFollowedSmoothly) {
  FriHarness h(FastSim(), FollowingIiwaCommand());
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd from = h.driver().session().commanded();
  Eigen::VectorXd to = from;
  to[0] += 0.5;
  to[2] -= 0.3;
  auto planned = trajectory::PointToPoint(from, to, trajectory::LimitsFromModel(IiwaModel(), 0.5));
  ASSERT_TRUE(planned.ok());
  drake::lcmt_iiwa_command command;
  command.num_joints = 7;
  command.num_torques = 0;
  h.sim().TakeSamples();
  const auto start = std::chrono::steady_clock::now();
  const std::int64_t start_host_us = timing::RealtimeUs();
  auto next_send = start;
  const double total = planned->duration() + 0.3;  // then keep the final position a while
  while (true) {
    const double t =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (t > total) break;
    if (std::chrono::steady_clock::now() >= next_send) {
      const Eigen::VectorXd q = planned->Evaluate(t).position;
      command.utime = timing::RealtimeUs();
      command.joint_position.assign(q.data(), q.data() + 7);
      ASSERT_TRUE(h.bus().Publish(channels::kIiwaCommand, command).ok());
      next_send += std::chrono::milliseconds(10);
    }
    ASSERT_TRUE(h.driver().SpinOnce(std::chrono::microseconds(500)).ok());
  }
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_STOPPED, "", 1.0));  // the stream ended: expiry
  h.SpinFor(0.2);
  const auto samples = h.sim().TakeSamples();
  // Path error of the setpoints: distance to the nearest point of the streamed profile.
  // Lag: how long after the stream's profile time the setpoint reaches that point (only where
  // the arm moves, so the nearest point is unique).
  double path_error = 0, max_lag = 0;
  for (const auto& s : samples) {
    double nearest = 1e9, nearest_t = 0;
    for (double t = 0; t <= planned->duration(); t += 0.0005) {
      const double e = (s.commanded - planned->Evaluate(t).position).cwiseAbs().maxCoeff();
      if (e < nearest) {
        nearest = e;
        nearest_t = t;
      }
    }
    path_error = std::max(path_error, nearest);
    const double t_sample =
        static_cast<double>(h.sim().ControllerToHostUs(s.controller_us) - start_host_us) * 1e-6;
    if (nearest_t > 0.05 && nearest_t < planned->duration() - 0.05) {
      max_lag = std::max(max_lag, t_sample - nearest_t);
    }
  }
  std::printf(
      "100 Hz stream: %zu cycles, setpoint path error %.2e rad, largest lag %.1f ms, "
      "final error %.2e rad\n",
      samples.size(), path_error, max_lag * 1e3,
      (samples.back().commanded - to).cwiseAbs().maxCoeff());
  // Stated bounds: setpoints within 4 mrad of the streamed path (per-joint acceleration limits
  // bend the path a little when a late setpoint makes the stream jerk; 0.4 to 2.1 mrad measured
  // on a loaded machine) and at most 50 ms behind it (one stream period of interpolation delay,
  // plus delivery and scheduling; the former limiter without the stream's velocity lagged 74 ms
  // and left the path by 8 mrad).
  EXPECT_LT(path_error, 4e-3);
  EXPECT_LT(max_lag, 0.05);
  EXPECT_LT((samples.back().commanded - to).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((h.sim().TruePosition() - to).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_EQ(h.sim().stats().velocity_violations, 0u);
  EXPECT_EQ(h.driver().session().limited_cycles(), 0);
}

}  // namespace
}  // namespace selfcal::testing
