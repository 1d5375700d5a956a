// Motion only from the key's holder: selfcal-iiwa against the FRI simulator over UDP on
// 127.0.0.1 executes a joint_trajectory_t only when it is signed with its key, within its
// validity and not seen before; Drake's IIWA_COMMAND only with follow_iiwa_command. What it
// refuses must leave the simulator's commanded positions where they were.
#include <gtest/gtest.h>

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

// A move of A1 by `delta` from where the driver commands the arm now, unsigned.
selfcal::joint_trajectory_t Move(FriHarness& h, double delta, const std::string& id,
                                 std::int64_t utime = timing::RealtimeUs()) {
  const Eigen::VectorXd from = h.driver().session().commanded();
  Eigen::VectorXd to = from;
  to[0] += delta;
  auto planned = trajectory::PointToPoint(from, to, trajectory::LimitsFromModel(IiwaModel()));
  EXPECT_TRUE(planned.ok());
  return ToMessage(*planned, {"A1", "A2", "A3", "A4", "A5", "A6", "A7"}, id, utime);
}

// A stop request (no points) without a tag.
selfcal::joint_trajectory_t UnsignedStop(const std::string& id) {
  selfcal::joint_trajectory_t stop{};
  stop.utime = timing::RealtimeUs();
  stop.trajectory_id = id;
  return stop;
}

// Publishes `message` and spins until the driver refused it; returns the refusal's reason.
std::string ExpectRefused(FriHarness& h, const selfcal::joint_trajectory_t& message) {
  const std::size_t from = h.statuses.size();
  EXPECT_TRUE(h.bus().Publish(channels::kJointTrajectory, message).ok());
  if (!h.WaitForEvent(Status_t::EVENT_REFUSED, message.trajectory_id, 1.0, from)) {
    ADD_FAILURE() << message.trajectory_id << " was not refused";
    return {};
  }
  EXPECT_EQ(h.FindEvent(Status_t::EVENT_ACCEPTED, message.trajectory_id, from), -1);
  return h
      .statuses[static_cast<std::size_t>(
          h.FindEvent(Status_t::EVENT_REFUSED, message.trajectory_id, from))]
      .message;
}

// The largest change of the simulator's commanded positions over `samples` from `start`.
double LargestCommandedChange(const std::vector<sim::FriSimSample>& samples,
                              const Eigen::VectorXd& start) {
  double change = 0;
  for (const auto& s : samples)
    change = std::max(change, (s.commanded - start).cwiseAbs().maxCoeff());
  return change;
}

TEST(IiwaAuth, UnsignedAndWronglySignedStreamsMoveNothing) {
  FriHarness h(FastSim());
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd start = h.sim().TruePosition();
  h.sim().TakeSamples();
  auth::Key wrong = TestKey();
  wrong[0] ^= 1;
  // For 1 s, every 20 ms: an unsigned trajectory, one signed with another key, one whose
  // positions were changed after signing, and a Drake command 0.1 rad away.
  drake::lcmt_iiwa_command command;
  command.num_joints = 7;
  command.num_torques = 0;
  for (int i = 0; i < 50; ++i) {
    const std::string n = std::to_string(i);
    ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, Move(h, 0.3, "unsigned-" + n)).ok());
    auto forged = Move(h, 0.3, "forged-" + n);
    SignTrajectory(forged, wrong);
    ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, forged).ok());
    auto tampered = Move(h, 0.01, "tampered-" + n);
    SignTrajectory(tampered, TestKey());
    for (auto& row : tampered.positions) row[0] += 0.29 * (row[0] - start[0]) / 0.01;
    ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, tampered).ok());
    command.utime = timing::RealtimeUs();
    command.joint_position.assign(start.data(), start.data() + 7);
    command.joint_position[0] += 0.1 * (i + 1) / 50.0;
    ASSERT_TRUE(h.bus().Publish(channels::kIiwaCommand, command).ok());
    h.SpinFor(0.02);
  }
  h.SpinFor(0.2);
  const auto samples = h.sim().TakeSamples();
  ASSERT_GT(samples.size(), 400u);
  EXPECT_LT(LargestCommandedChange(samples, start), 1e-9);
  EXPECT_LT((h.sim().TruePosition() - start).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(h.FindEvent(Status_t::EVENT_ACCEPTED), -1);
  EXPECT_EQ(h.driver().session().command_source(), Status_t::SOURCE_HOLD);
  // Refused with their reasons on the status message (the same reason at most once a second, so
  // the tampered ones, also "wrong signature", are not each reported).
  auto reason_of = [&](const std::string& id) {
    const int i = h.FindEvent(Status_t::EVENT_REFUSED, id);
    return i < 0 ? std::string("(none)") : h.statuses[static_cast<std::size_t>(i)].message;
  };
  EXPECT_NE(reason_of("unsigned-0").find("unsigned"), std::string::npos) << reason_of("unsigned-0");
  EXPECT_NE(reason_of("forged-0").find("wrong signature"), std::string::npos);
  EXPECT_NE(reason_of("IIWA_COMMAND").find("--follow-iiwa-command"), std::string::npos)
      << reason_of("IIWA_COMMAND");
}

TEST(IiwaAuth, ASignedTrajectoryMovesTheArmOnceAndNotWhenReplayedOrExpired) {
  FriHarness h(FastSim());
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd start = h.sim().TruePosition();
  auto move = Move(h, 0.2, "signed");
  SignTrajectory(move, TestKey());
  ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, move).ok());
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_ACCEPTED, "signed", 1.0))
      << (h.statuses.empty() ? "" : h.statuses.back().message);
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_COMPLETED, "signed", 5.0));
  h.SpinFor(0.2);
  const Eigen::VectorXd moved = h.sim().TruePosition();
  EXPECT_NEAR(moved[0] - start[0], 0.2, 1e-3);

  // Back to the start with a second signed trajectory; then the first one again (a capture
  // replayed): it starts where the arm now is, within its validity, so only the replay check
  // can refuse it.
  auto back = Move(h, -0.2, "back");
  SignTrajectory(back, TestKey());
  ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, back).ok());
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_COMPLETED, "back", 5.0));
  h.SpinFor(0.2);
  h.sim().TakeSamples();
  EXPECT_NE(ExpectRefused(h, move).find("replayed"), std::string::npos);
  // Expired: signed 15 s ago with the daemon's 10 s validity.
  auto old = Move(h, 0.2, "expired", timing::RealtimeUs() - 15'000'000);
  SignTrajectory(old, TestKey());
  EXPECT_NE(ExpectRefused(h, old).find("expired"), std::string::npos);
  // A validity longer than the driver accepts.
  auto lasting = Move(h, 0.2, "lasting");
  SignTrajectory(lasting, TestKey(), kMaxTrajectoryValidityUs + 1);
  EXPECT_NE(ExpectRefused(h, lasting).find("validity"), std::string::npos);
  // Signed before the driver started: it could have been captured before a restart.
  auto before = Move(h, 0.2, "before-start", timing::RealtimeUs() - 8'000'000);
  SignTrajectory(before, TestKey());
  EXPECT_NE(ExpectRefused(h, before).find("before the driver started"), std::string::npos);
  h.SpinFor(0.2);
  EXPECT_LT(LargestCommandedChange(h.sim().TakeSamples(), start), 1e-3)
      << "after 'back' the arm stays at the start";
  EXPECT_LT((h.sim().TruePosition() - start).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(IiwaAuth, WithoutAKeyEveryTrajectoryIsRefusedAndAStopIsHonoured) {
  FriHarness h(FastSim(), {}, std::nullopt);
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd start = h.sim().TruePosition();
  h.sim().TakeSamples();
  auto move = Move(h, 0.2, "signed-but-no-key");
  SignTrajectory(move, TestKey());
  EXPECT_NE(ExpectRefused(h, move).find("no key configured"), std::string::npos);
  // An unsigned stop is honoured: stopping never depends on a key.
  ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, UnsignedStop("stop")).ok());
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_STOPPED, "stop", 1.0));
  h.SpinFor(0.1);
  EXPECT_LT(LargestCommandedChange(h.sim().TakeSamples(), start), 1e-9);
}

// An unsigned stop brakes a signed trajectory that is running.
TEST(IiwaAuth, AnUnsignedStopBrakesASignedTrajectory) {
  FriHarness h(FastSim());
  h.Start();
  ASSERT_TRUE(h.WaitForState(SessionState::kCommandingActive, 5.0));
  h.SpinFor(0.1);
  const Eigen::VectorXd start = h.sim().TruePosition();
  auto move = Move(h, 1.5, "long");
  SignTrajectory(move, TestKey());
  ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, move).ok());
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_ACCEPTED, "long", 1.0));
  h.SpinFor(0.5);
  ASSERT_TRUE(h.bus().Publish(channels::kJointTrajectory, UnsignedStop("long")).ok());
  ASSERT_TRUE(h.WaitForEvent(Status_t::EVENT_STOPPED, "long", 1.0));
  h.SpinFor(0.8);
  EXPECT_EQ(h.driver().session().command_source(), Status_t::SOURCE_HOLD);
  EXPECT_EQ(h.FindEvent(Status_t::EVENT_COMPLETED, "long"), -1);
  EXPECT_GT(h.sim().TruePosition()[0], start[0] + 0.01) << "it moved before the stop";
  EXPECT_LT(h.sim().TruePosition()[0], start[0] + 1.5 - 0.2) << "and stopped short of the goal";
}

}  // namespace
}  // namespace selfcal::testing
