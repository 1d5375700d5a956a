// Signed trajectories: every field is covered by the tag, the tag is the trajectory's own (not a
// request's), and the verifier refuses unsigned, expired, over-long, early, replayed and
// over-capacity ones, also across a wall-clock step.
#include "protocols/trajectory/trajectory_signature.h"

#include <gtest/gtest.h>

#include <functional>

namespace selfcal {
namespace {

constexpr std::int64_t kNow = 1'800'000'000'000'000;
constexpr std::int64_t kMonotonic = 5'000'000;

auth::Key TestKey(std::uint8_t seed = 1) {
  auth::Key key{};
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(seed + 7 * i);
  return key;
}

selfcal::joint_trajectory_t Trajectory(const std::string& id, std::int64_t utime = kNow) {
  selfcal::joint_trajectory_t m{};
  m.utime = utime;
  m.trajectory_id = id;
  m.num_joints = 2;
  m.joint_names = {"A1", "A2"};
  m.num_points = 2;
  m.time_from_start = {0.0, 1.5};
  m.positions = {{0.1, 0.2}, {0.3, 0.4}};
  m.velocities = {{0.0, 0.0}, {0.0, 0.0}};
  m.tag_length = 0;
  return m;
}

selfcal::joint_trajectory_t Signed(selfcal::joint_trajectory_t m) {
  SignTrajectory(m, TestKey());
  return m;
}

TEST(TrajectorySignature, EveryFieldIsCovered) {
  const auto good = Signed(Trajectory("S1"));
  EXPECT_EQ(good.valid_until, kNow + kTrajectoryValidityUs);
  EXPECT_EQ(good.tag_length, 32);
  EXPECT_EQ(TrajectoryVerifier(TestKey(), 0).Check(good, kNow, kMonotonic), "");
  const std::vector<std::function<void(selfcal::joint_trajectory_t&)>> changes = {
      [](auto& m) { m.utime += 1; },
      [](auto& m) { m.valid_until += 1; },
      [](auto& m) { m.trajectory_id = "S2"; },
      [](auto& m) { m.joint_names[1] = "A3"; },
      [](auto& m) { m.time_from_start[1] = 1.25; },
      [](auto& m) { m.positions[1][0] = 0.31; },
      [](auto& m) { m.velocities[0][1] = 1e-300; },
      [](auto& m) { m.tag[5] ^= 0x10; },
      [](auto& m) {  // rows regrouped: the same numbers in other arrays
        m.positions = {{0.1}, {0.2, 0.3, 0.4}};
      },
      [](auto& m) { m.num_points = 0 + 1; },  // counts that disagree with the arrays
  };
  for (std::size_t i = 0; i < changes.size(); ++i) {
    auto changed = good;
    changes[i](changed);
    EXPECT_EQ(TrajectoryVerifier(TestKey(), 0).Check(changed, kNow, kMonotonic),
              "wrong signature (tag does not match the key)")
        << "change " << i;
  }
  EXPECT_TRUE(TrajectoryVerifier(TestKey(), 0).Authentic(good));
  EXPECT_FALSE(TrajectoryVerifier(TestKey(2), 0).Authentic(good));
  EXPECT_FALSE(TrajectoryVerifier(std::nullopt, 0).Authentic(good));
  EXPECT_EQ(TrajectoryVerifier(TestKey(2), 0).Check(good, kNow, kMonotonic),
            "wrong signature (tag does not match the key)");
  // Its own domain: the same bytes under the requests' domain give another tag.
  EXPECT_NE(
      auth::Tag(TestKey(), "selfcal.calibration_request_t/v2", CanonicalTrajectoryBytes(good)),
      good.tag);
}

TEST(TrajectorySignature, UnsignedOrWithoutAKeyIsRefused) {
  EXPECT_EQ(TrajectoryVerifier(TestKey(), 0).Check(Trajectory("S1"), kNow, kMonotonic),
            "unsigned trajectory (no tag)");
  EXPECT_EQ(TrajectoryVerifier(std::nullopt, 0).Check(Signed(Trajectory("S1")), kNow, kMonotonic),
            "no key configured (--key-file): every trajectory is refused");
}

TEST(TrajectorySignature, TimeBounds) {
  TrajectoryVerifier verifier(TestKey(), 0);
  const auto m = Signed(Trajectory("S1"));
  EXPECT_EQ(verifier.Check(m, m.valid_until + 1, kMonotonic),
            "expired (its valid_until has passed)");
  EXPECT_EQ(verifier.Check(m, kNow - kMaxTrajectoryValidityUs - 1, kMonotonic),
            "signed in the future (the sender's clock is ahead)");
  auto lasting = Trajectory("S2");
  SignTrajectory(lasting, TestKey(), kMaxTrajectoryValidityUs + 1);
  EXPECT_EQ(verifier.Check(lasting, kNow, kMonotonic), "validity outside (0, 30 s] after utime");
  auto none = Trajectory("S3");
  SignTrajectory(none, TestKey(), 0);
  EXPECT_EQ(verifier.Check(none, kNow, kMonotonic), "validity outside (0, 30 s] after utime");
  auto overflow = Trajectory("S4", std::numeric_limits<std::int64_t>::max() - 5);
  SignTrajectory(overflow, TestKey(), 1);
  EXPECT_NE(verifier.Check(overflow, kNow, kMonotonic), "");
  EXPECT_EQ(verifier.Check(m, m.valid_until, kMonotonic), "") << "valid up to valid_until";
  EXPECT_EQ(
      TrajectoryVerifier(TestKey(), kNow + 1).Check(Signed(Trajectory("S5")), kNow, kMonotonic),
      "signed before the driver started (a replay, or the sender's clock is behind)");
}

TEST(TrajectorySignature, AReplayIsRefusedAlsoAcrossAWallClockStep) {
  TrajectoryVerifier verifier(TestKey(), 0);
  const auto first = Signed(Trajectory("S1"));
  ASSERT_EQ(verifier.Check(first, kNow, kMonotonic), "");
  EXPECT_EQ(verifier.Check(first, kNow + 1, kMonotonic + 1),
            "replayed (this signed trajectory was received before)");
  // The wall clock steps 70 s ahead (1 s later by the monotonic clock): a trajectory signed then
  // is accepted, and `first`, expired by the wall clock, is not forgotten yet...
  ASSERT_EQ(verifier.Check(Signed(Trajectory("S2", kNow + 70'000'000)), kNow + 70'000'000,
                           kMonotonic + 1'000'000),
            "");
  // ...so when the wall clock steps back, `first` is still a replay.
  EXPECT_EQ(verifier.Check(first, kNow + 2'000'000, kMonotonic + 2'000'000),
            "replayed (this signed trajectory was received before)");
  // Forgotten only once expired by both clocks; by then the wall clock refuses it as expired.
  ASSERT_EQ(verifier.Check(Signed(Trajectory("S3", kNow + 61'000'000)), kNow + 61'000'000,
                           kMonotonic + 61'000'000),
            "");
  EXPECT_EQ(verifier.Check(first, kNow + 61'000'000, kMonotonic + 61'000'000),
            "expired (its valid_until has passed)");
}

TEST(TrajectorySignature, AFullReplayMemoryRefusesRatherThanForgets) {
  TrajectoryVerifier verifier(TestKey(), 0, 2);
  EXPECT_EQ(verifier.Check(Signed(Trajectory("S1")), kNow, kMonotonic), "");
  EXPECT_EQ(verifier.Check(Signed(Trajectory("S2")), kNow, kMonotonic), "");
  EXPECT_EQ(verifier.Check(Signed(Trajectory("S3")), kNow, kMonotonic),
            "too many signed trajectories within their validity; refused to stay replay-safe");
}

}  // namespace
}  // namespace selfcal
