// Synchronized motions within the iiwa's limits, constant-velocity sweeps, scan programs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/trajectory/motion.h"
#include "core/trajectory/scan_program.h"
#include "protocols/model_file/model_file.h"

namespace selfcal::trajectory {
namespace {

JointLimits IiwaLimits() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  auto file =
      ReadModelFile(std::string(dir ? dir : ".") + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  EXPECT_TRUE(file.ok()) << file.error().message;
  return LimitsFromModel(file->model);
}

Eigen::VectorXd Q(std::initializer_list<double> values) {
  Eigen::VectorXd q(static_cast<Eigen::Index>(values.size()));
  Eigen::Index i = 0;
  for (double v : values) q[i++] = v;
  return q;
}

// Samples every 1 ms and checks limits numerically, independently of CheckLimits; returns the
// largest ratio of |velocity| / limit and |acceleration| / limit seen.
struct Ratios {
  double velocity = 0, acceleration = 0, jerk = 0;
};
Ratios SampleRatios(const JointTrajectory& t, const JointLimits& limits) {
  Ratios r;
  const double dt = 1e-3;
  Eigen::VectorXd previous_acceleration = t.Evaluate(0).acceleration;
  for (double time = dt; time < t.duration(); time += dt) {
    const Sample s = t.Evaluate(time);
    for (Eigen::Index i = 0; i < s.position.size(); ++i) {
      EXPECT_GE(s.position[i], limits.lower[i] - 1e-9);
      EXPECT_LE(s.position[i], limits.upper[i] + 1e-9);
      r.velocity = std::max(r.velocity, std::abs(s.velocity[i]) / limits.max_velocity[i]);
      r.acceleration =
          std::max(r.acceleration, std::abs(s.acceleration[i]) / limits.max_acceleration[i]);
      r.jerk = std::max(
          r.jerk, std::abs(s.acceleration[i] - previous_acceleration[i]) / dt / limits.max_jerk[i]);
    }
    previous_acceleration = s.acceleration;
  }
  return r;
}

TEST(Trajectory, PointToPointIsSynchronizedWithinLimitsAndUsesThem) {
  const JointLimits limits = IiwaLimits();
  const Eigen::VectorXd from = Q({0, 0.5, 0, -1.2, 0, 0.8, 0});
  const Eigen::VectorXd to = Q({1.5, -0.4, 0.3, -0.6, 1.0, -0.5, 2.0});
  auto t = PointToPoint(from, to, limits);
  ASSERT_TRUE(t.ok()) << t.error().message;
  EXPECT_TRUE((t->Evaluate(0).position - from).isZero(0));
  EXPECT_TRUE((t->Evaluate(t->duration()).position - to).norm() < 1e-12);
  EXPECT_TRUE(t->Evaluate(t->duration()).velocity.isZero(1e-12));
  ASSERT_TRUE(CheckLimits(*t, limits).ok()) << CheckLimits(*t, limits).error().message;
  const Ratios r = SampleRatios(*t, limits);
  EXPECT_LE(r.velocity, 1 + 1e-9);
  EXPECT_LE(r.acceleration, 1 + 1e-9);
  EXPECT_LE(r.jerk, 1 + 1e-6);
  // Time-optimal for the slowest joint: it reaches its velocity limit on this long move.
  EXPECT_GT(r.velocity, 0.999);
  // Synchronized: every sample lies on the straight line from -> to.
  const Eigen::VectorXd direction = (to - from).normalized();
  for (double time = 0; time < t->duration(); time += 0.01) {
    const Eigen::VectorXd d = t->Evaluate(time).position - from;
    EXPECT_LT((d - d.dot(direction) * direction).norm(), 1e-9) << time;
  }
}

TEST(Trajectory, ShortMoveNeverReachesCruiseAndTrapezoidWithoutJerkLimit) {
  JointLimits limits = IiwaLimits();
  const Eigen::VectorXd from = Q({0, 0, 0, 0, 0, 0, 0});
  const Eigen::VectorXd to = Q({0.05, 0, 0, 0, 0, 0, 0});
  auto s_curve = PointToPoint(from, to, limits);
  ASSERT_TRUE(s_curve.ok());
  EXPECT_LT(SampleRatios(*s_curve, limits).velocity, 0.5);
  limits.max_jerk.resize(0);
  auto trapezoid = PointToPoint(from, to, limits);
  ASSERT_TRUE(trapezoid.ok());
  // Without a jerk limit the move is faster (bang-bang: 2 sqrt(d / a)).
  EXPECT_NEAR(trapezoid->duration(), 2 * std::sqrt(0.05 / 5.0), 1e-9);
  EXPECT_GT(s_curve->duration(), trapezoid->duration());
  EXPECT_TRUE(CheckLimits(*trapezoid, limits).ok());
}

TEST(Trajectory, ConstantVelocitySweepHoldsTheSpeedExactlyOverTheSegment) {
  const JointLimits limits = IiwaLimits();
  const Eigen::VectorXd posture = Q({0, 0.3, 0, -1.0, 0, 0.5, 0});
  const ScanStep step = OneAxisSweep(posture, 6, -1.0, 1.0, 0.5, 0);
  auto sweep = ConstantVelocitySweep(step.from, step.target, 0.5, limits);
  ASSERT_TRUE(sweep.ok()) << sweep.error().message;
  EXPECT_NEAR(sweep->trajectory.Evaluate(sweep->constant_begin).position[6], -1.0, 1e-9);
  EXPECT_NEAR(sweep->trajectory.Evaluate(sweep->constant_end).position[6], 1.0, 1e-9);
  EXPECT_NEAR(sweep->constant_end - sweep->constant_begin, 2.0 / 0.5, 1e-9);
  for (double t = sweep->constant_begin; t <= sweep->constant_end; t += 0.01) {
    const Sample s = sweep->trajectory.Evaluate(t);
    EXPECT_NEAR(s.velocity[6], 0.5, 1e-9) << t;
    EXPECT_NEAR(s.velocity[0], 0.0, 1e-12);
  }
  EXPECT_TRUE(CheckLimits(sweep->trajectory, limits).ok());
}

TEST(Trajectory, InfeasibleSweepsAreErrorsThatSayWhy) {
  const JointLimits limits = IiwaLimits();
  const Eigen::VectorXd posture = Q({0, 0.3, 0, -1.0, 0, 0.5, 0});
  // A7's limit is 2.356 rad/s.
  auto too_fast = ConstantVelocitySweep(posture, Q({0, 0.3, 0, -1.0, 0, 0.5, 1}), 3.0, limits);
  ASSERT_FALSE(too_fast.ok());
  EXPECT_NE(too_fast.error().message.find("above its limit 2.356"), std::string::npos)
      << too_fast.error().message;
  // The run-up before -3.0 leaves A7's range of +-3.054 rad.
  auto run_up = ConstantVelocitySweep(Q({0, 0.3, 0, -1.0, 0, 0.5, -3.0}),
                                      Q({0, 0.3, 0, -1.0, 0, 0.5, 0}), 1.0, limits);
  ASSERT_FALSE(run_up.ok());
  EXPECT_NE(run_up.error().message.find("run-up"), std::string::npos) << run_up.error().message;
  auto outside = PointToPoint(posture, Q({0, 3.0, 0, 0, 0, 0, 0}), limits);
  ASSERT_FALSE(outside.ok());
  EXPECT_NE(outside.error().message.find("joint 1"), std::string::npos);
}

TEST(Trajectory, CheckLimitsFindsViolationsBetweenKnots) {
  const JointLimits limits = IiwaLimits();
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(7);
  // Knot positions inside the limits, but the cubic between them overshoots A2's 2.094 rad.
  Eigen::VectorXd q1 = zero, v0 = zero, v1 = zero;
  q1[1] = 2.0;
  v0[1] = 1.4;
  v1[1] = -1.4;
  auto overshoot = JointTrajectory::FromKnots({{0, zero, v0}, {2.0, q1, v1}});
  ASSERT_TRUE(overshoot.ok());
  const auto status = CheckLimits(*overshoot, limits, {"A1", "A2"});
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find("A2"), std::string::npos) << status.error().message;
  EXPECT_NE(status.error().message.find("position"), std::string::npos) << status.error().message;
  // Too fast: 1 rad in 0.1 s.
  Eigen::VectorXd q = zero;
  q[0] = 1.0;
  auto fast = JointTrajectory::FromKnots({{0, zero, zero}, {0.1, q, zero}});
  ASSERT_TRUE(fast.ok());
  ASSERT_FALSE(CheckLimits(*fast, limits).ok());
  EXPECT_NE(CheckLimits(*fast, limits).error().message.find("velocity"), std::string::npos);
  // Bad knots.
  EXPECT_FALSE(JointTrajectory::FromKnots({}).ok());
  EXPECT_FALSE(JointTrajectory::FromKnots({{0, zero, zero}, {0, zero, zero}}).ok());
  EXPECT_FALSE(JointTrajectory::FromKnots({{0.5, zero, zero}}).ok());
  Eigen::VectorXd nan = zero;
  nan[3] = std::nan("");
  EXPECT_FALSE(JointTrajectory::FromKnots({{0, zero, zero}, {1, nan, zero}}).ok());
}

// Found by the driver's limit check: a phase of round-off length made a knot interval of 1e-17 s
// whose Hermite acceleration was 1e17. Many random moves, every one within the limits.
TEST(Trajectory, RandomMovesAlwaysPassTheLimitCheck) {
  const JointLimits limits = IiwaLimits();
  std::mt19937 random(42);
  for (int trial = 0; trial < 500; ++trial) {
    Eigen::VectorXd from(7), to(7);
    for (Eigen::Index i = 0; i < 7; ++i) {
      std::uniform_real_distribution<double> u(limits.lower[i], limits.upper[i]);
      from[i] = u(random);
      // Half of the moves are short (a few hundredths of a radian), where ramps are triangular.
      to[i] = trial % 2 ? u(random)
                        : std::clamp(from[i] + 0.05 * (u(random) / limits.upper[i]),
                                     limits.lower[i], limits.upper[i]);
    }
    auto t = PointToPoint(from, to, limits);
    ASSERT_TRUE(t.ok()) << t.error().message;
    const auto status = CheckLimits(*t, limits);
    ASSERT_TRUE(status.ok()) << "trial " << trial << ": " << status.error().message;
    ASSERT_LT((t->back().position - to).norm(), 1e-9);
    for (std::size_t k = 1; k < t->knots().size(); ++k) {
      ASSERT_GT(t->knots()[k].time - t->knots()[k - 1].time, 1e-7) << "trial " << trial;
    }
  }
}

TEST(Trajectory, ScanProgramOfSweepsAndCameraPoses) {
  const JointLimits limits = IiwaLimits();
  const Eigen::VectorXd home = Q({0, 0, 0, -1.2, 0, 0.8, 0});
  ScanProgram program;
  program.name = "mixed";
  program.steps.push_back(OneAxisSweep(Q({0.5, 0.3, 0, -1.0, 0, 0.5, 0}), 6, -1.5, 1.5, 0.8, 0));
  program.steps.push_back(
      LineSweep(Q({-0.5, 0.2, 0, -1.1, 0, 0.6, 0}), Q({0.5, 0.4, 0.2, -0.9, 0.1, 0.4, 0}), 0.3, 1));
  program.steps.push_back(CameraPose(Q({0.2, 0.1, 0, -1.4, 0, 1.0, 0}), 0.5, 0.2, 2));
  ScanStep transfer;
  transfer.target = home;
  program.steps.push_back(transfer);
  auto planned = PlanScanProgram(program, home, limits);
  ASSERT_TRUE(planned.ok()) << planned.error().message;
  const JointTrajectory& t = planned->trajectory;
  EXPECT_TRUE(CheckLimits(t, limits).ok()) << CheckLimits(t, limits).error().message;
  const Ratios r = SampleRatios(t, limits);
  EXPECT_LE(r.velocity, 1 + 1e-9);
  EXPECT_LE(r.acceleration, 1 + 1e-9);
  EXPECT_LE(r.jerk, 1 + 1e-6);
  ASSERT_EQ(planned->windows.size(), 3u);
  // Sweep 0: A7 at 0.8 rad/s over [-1.5, 1.5].
  const ScanWindow& w0 = planned->windows[0];
  EXPECT_NEAR(w0.end - w0.begin, 3.0 / 0.8, 1e-6);
  EXPECT_NEAR(t.Evaluate(w0.begin).position[6], -1.5, 1e-9);
  EXPECT_NEAR(t.Evaluate((w0.begin + w0.end) / 2).velocity[6], 0.8, 1e-9);
  // Sweep 1: the fastest joint (A1, 1 rad) at 0.3 rad/s.
  const ScanWindow& w1 = planned->windows[1];
  EXPECT_NEAR(w1.end - w1.begin, 1.0 / 0.3, 1e-6);
  EXPECT_NEAR(t.Evaluate((w1.begin + w1.end) / 2).velocity[0], 0.3, 1e-9);
  // Camera pose: standing still during its window, after the settle time.
  const ScanWindow& w2 = planned->windows[2];
  EXPECT_NEAR(w2.end - w2.begin, 0.2, 1e-9);
  EXPECT_TRUE(t.Evaluate(w2.begin - 0.5 + 1e-6).velocity.isZero(1e-9));
  EXPECT_TRUE(t.Evaluate((w2.begin + w2.end) / 2).velocity.isZero(0));
  EXPECT_LT((t.Evaluate(w2.begin).position - program.steps[2].target).norm(), 1e-9);
  // Ends at home, at rest.
  EXPECT_LT((t.back().position - home).norm(), 1e-9);
  // Position is continuous everywhere (no jumps at the joins).
  Eigen::VectorXd previous = t.Evaluate(0).position;
  for (double time = 1e-3; time < t.duration(); time += 1e-3) {
    const Eigen::VectorXd q = t.Evaluate(time).position;
    EXPECT_LT((q - previous).cwiseAbs().maxCoeff(), 2.4e-3) << time;
    previous = q;
  }
  // A step that cannot be planned names itself.
  program.steps[1].speed = 50;
  auto bad = PlanScanProgram(program, home, limits);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("step 1"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace selfcal::trajectory
