// The motion executor against a perfect arm on memq://: one trajectory goes out, scan boundaries
// come back in order at the planned times, and stale inputs, a deviation or the driver's refusal
// fail the motion and stop the arm.
#include "daemon/motion_executor.h"

#include <gtest/gtest.h>

#include <vector>

#include "protocols/model_file/model_file.h"
#include "protocols/trajectory/trajectory_signature.h"
#include "selfcal/joint_trajectory_t.hpp"

namespace selfcal::daemon {
namespace {

using Kind = MotionEvent::Kind;
using DriverStatus_t = selfcal::robot_driver_status_t;

std::string SourceDir() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return dir ? dir : ".";
}

class MotionExecutorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto file = ReadModelFile(SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
    ASSERT_TRUE(file) << file.error().message;
    model_ = file->model;
    for (const auto& joint : model_.joints) names_.push_back(joint.name);
    bus_ = std::shared_ptr<Bus>(OpenLcmBus("memq://").value());
    bus_->Subscribe("TRAJECTORY", [this](const BusMessage& m) {
      sent_.push_back(DecodeLcm<selfcal::joint_trajectory_t>(m.data, m.channel).value());
    });
    ScanPlan plan;
    plan.name = "two";
    const std::vector<double> a = {0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0};
    std::vector<double> b = a, c = a;
    b[0] = 0.2;
    c[0] = 0.2;
    c[6] = 0.2;
    plan.scans = {{false, a, b, 0.5}, {true, b, c, 0.5}};
    auto motion = PlanScanMotion(plan, a, model_, 1.0, 0.1);
    ASSERT_TRUE(motion) << motion.error().message;
    motion_ = *motion;
    checks_.joint_state_max_age = 0.1;
    checks_.sensor_max_age = 0.3;
    checks_.max_deviation = 0.05;
    checks_.max_lag = 0.1;
  }

  // The inputs of an arm that is exactly where the trajectory says, measured at `now`.
  MotionInputs PerfectArm(std::int64_t now) {
    const double t = static_cast<double>(now - start_) * 1e-6;
    const Eigen::VectorXd q = motion_.trajectory.Evaluate(t).position;
    joints_.assign(q.data(), q.data() + q.size());
    return {now, &joints_, now};
  }
  void Receive() { ASSERT_TRUE(ServiceBus(*bus_, true, std::chrono::milliseconds(0))); }

  RobotModel model_;
  std::vector<std::string> names_;
  std::shared_ptr<Bus> bus_;
  std::vector<selfcal::joint_trajectory_t> sent_;
  ScanMotion motion_;
  CheckConfig checks_;
  std::vector<double> joints_;
  const std::int64_t start_ = 1'800'000'000'000'000;
  const auth::Key key_ = {3, 1, 4, 1, 5, 9, 2, 6, 5, 3, 5, 8, 9, 7, 9, 3,
                          2, 3, 8, 4, 6, 2, 6, 4, 3, 3, 8, 3, 2, 7, 9, 5};
};

TEST_F(MotionExecutorTest, PublishesOneTrajectoryAndReportsScanBoundariesInOrder) {
  MotionExecutor executor(bus_, "TRAJECTORY", checks_, key_);
  ASSERT_TRUE(executor.Start(motion_, names_, "S1", start_, start_));
  Receive();
  ASSERT_EQ(sent_.size(), 1u);
  EXPECT_EQ(sent_[0].trajectory_id, "S1");
  EXPECT_EQ(sent_[0].joint_names, names_);
  EXPECT_EQ(static_cast<std::size_t>(sent_[0].num_points), motion_.trajectory.knots().size());
  // Signed with the daemon's key, as the driver requires.
  TrajectoryVerifier verifier(key_, start_);
  EXPECT_EQ(verifier.Check(sent_[0], start_ + 1000, 0), "");
  EXPECT_NE(TrajectoryVerifier(auth::Key{}, start_).Check(sent_[0], start_ + 1000, 0), "");
  std::vector<Kind> kinds;
  std::vector<double> times;
  const auto end = start_ + static_cast<std::int64_t>((motion_.trajectory.duration() + 0.1) * 1e6);
  for (std::int64_t now = start_; now <= end && executor.active(); now += 5000) {
    EXPECT_GE(executor.next_deadline(), start_);
    for (const auto& event : executor.Tick(now, now, PerfectArm(now))) {
      kinds.push_back(event.kind);
      times.push_back(static_cast<double>(now - start_) * 1e-6);
      EXPECT_NE(event.kind, Kind::kFailed) << event.reason;
    }
  }
  const std::vector<Kind> expected = {Kind::kScanBegin, Kind::kScanEnd, Kind::kMoveToScan,
                                      Kind::kScanBegin, Kind::kScanEnd, Kind::kCompleted};
  ASSERT_EQ(kinds, expected);
  EXPECT_NEAR(times[0], motion_.scans[0].begin, 0.005);
  EXPECT_NEAR(times[1], motion_.scans[0].end, 0.005);
  EXPECT_NEAR(times[3], motion_.scans[1].begin, 0.005);
  EXPECT_NEAR(times[5], motion_.trajectory.duration(), 0.005);
  EXPECT_FALSE(executor.active());
  EXPECT_EQ(executor.next_deadline(), 0);
  Receive();
  EXPECT_EQ(sent_.size(), 1u) << "a completed motion sends no stop";
}

TEST_F(MotionExecutorTest, TheDriversRefusalOfOurTrajectoryFailsTheMotionAndStopsTheArm) {
  MotionExecutor executor(bus_, "TRAJECTORY", checks_, key_);
  ASSERT_TRUE(executor.Start(motion_, names_, "S1", start_, start_));
  DriverStatus_t status{};
  status.event = DriverStatus_t::EVENT_REFUSED;
  status.trajectory_id = "someone else's";
  status.message = "not ours";
  executor.OnDriverStatus(status);
  EXPECT_TRUE(executor.Tick(start_ + 5000, start_ + 5000, PerfectArm(start_ + 5000)).empty());
  status.trajectory_id = "S1";
  status.message = "session is MONITORING_WAIT, not COMMANDING_ACTIVE";
  executor.OnDriverStatus(status);
  const auto events = executor.Tick(start_ + 10000, start_ + 10000, PerfectArm(start_ + 10000));
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, Kind::kFailed);
  EXPECT_EQ(events[0].reason,
            "the arm's driver refused the trajectory: session is MONITORING_WAIT, not "
            "COMMANDING_ACTIVE");
  EXPECT_FALSE(executor.active());
  Receive();
  ASSERT_EQ(sent_.size(), 2u);
  EXPECT_EQ(sent_[1].num_points, 0) << "the stop is an empty trajectory";
  EXPECT_EQ(TrajectoryVerifier(key_, start_).Check(sent_[1], start_, 0), "") << "signed too";
  EXPECT_EQ(sent_[1].trajectory_id, "S1");
}

TEST_F(MotionExecutorTest, StaleJointsSilentSensorAndDeviationFailTheMotion) {
  const std::int64_t t = start_ + 500'000;
  struct Case {
    std::function<MotionInputs()> inputs;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {[&] {
         return MotionInputs{t - 200'000, &joints_, t};
       },
       "joint states went stale"},
      {[&] {
         return MotionInputs{t, &joints_, t - 400'000};
       },
       "sensor dropout"},
      {[&] {
         auto inputs = PerfectArm(t);
         joints_[0] += 0.2;
         return inputs;
       },
       "joint A1 deviates from the trajectory by"},
  };
  for (const auto& c : cases) {
    MotionExecutor executor(bus_, "TRAJECTORY", checks_, key_);
    ASSERT_TRUE(executor.Start(motion_, names_, "S1", start_, start_));
    PerfectArm(t);
    const auto events = executor.Tick(t, t, c.inputs());
    ASSERT_FALSE(events.empty()) << c.expect;
    EXPECT_EQ(events.back().kind, Kind::kFailed);
    EXPECT_NE(events.back().reason.find(c.expect), std::string::npos) << events.back().reason;
    EXPECT_FALSE(executor.active());
  }
}

}  // namespace
}  // namespace selfcal::daemon
