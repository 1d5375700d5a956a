// The daemon in-process (tests/daemon/daemon_fixture.h): the state machine, refusals, aborts,
// in-motion checks, gate and rollback.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "core/model/joint_offsets.h"
#include "core/util/atomic_file.h"
#include "daemon/daemon.h"
#include "protocols/lcm_log/lcm_log.h"
#include "selfcal/calibration_result_t.hpp"
#include "selfcal/scan_marker_t.hpp"
#include "tests/daemon/daemon_fixture.h"
#include "tests/daemon/scripted_engine.h"
#include "tests/daemon/test_arm.h"

namespace selfcal::daemon {
namespace {

namespace fs = std::filesystem;
using Status_t = selfcal::calibration_status_t;
using Request_t = selfcal::calibration_request_t;

class DaemonServiceTest : public DaemonFixture {};

TEST_F(DaemonServiceTest, AcceptedSessionInstallsTheModelAndRollbackRestoresTheNominal) {
  Start("seconds=0.3,rms_before=0.010,rms_after=0.004,shift=0.003");
  const std::string nominal = CurrentModelText();
  const auto answer = Send(MakeRequest(Request_t::START, key_));
  EXPECT_EQ(answer.refusal.rfind("refused", 0), std::string::npos) << answer.refusal;
  ASSERT_TRUE(WaitResult(60)) << daemon_->message();
  const auto& result = results_.back();
  ASSERT_EQ(result.outcome, selfcal::calibration_result_t::ACCEPTED) << result.reason;
  EXPECT_DOUBLE_EQ(result.validation_rms_before, 0.010);
  EXPECT_DOUBLE_EQ(result.validation_rms_after, 0.004);
  ASSERT_EQ(result.num_parameters, 28);
  // The states went through the whole chain, in order, at 1 Hz or more.
  std::vector<State> seen;
  for (const auto& s : statuses_) {
    const State state = StateFromWire(s.state).value();
    if (seen.empty() || seen.back() != state) seen.push_back(state);
  }
  const std::vector<State> chain = {State::kChecking,    State::kMoving,     State::kRecording,
                                    State::kCalibrating, State::kValidating, State::kAccepted,
                                    State::kIdle};
  std::size_t k = 0;
  for (State s : seen) {
    if (k < chain.size() && s == chain[k]) ++k;
  }
  EXPECT_EQ(k, chain.size());
  for (std::size_t i = 1; i < statuses_.size(); ++i) {
    EXPECT_LE(statuses_[i].utime - statuses_[i - 1].utime, 1'000'000) << "status gap at " << i;
  }
  // The installed model is the engine's, the session is complete and its log has the markers.
  auto installed = ReadModelFile(Path("storage/models/current/model.yaml"));
  ASSERT_TRUE(installed) << installed.error().message;
  auto nominal_model = ParseModelFile(nominal, "nominal").value();
  EXPECT_NEAR(installed->model.tool.z, nominal_model.model.tool.z + 0.003, 1e-12);
  EXPECT_EQ(SessionStatus(result.session_id), "accepted");
  auto log =
      LcmLogReader::Open(Path("storage/sessions/" + result.session_id + "/recording.lcmlog"));
  ASSERT_TRUE(log) << log.error().message;
  int begins = 0, ends = 0, joints = 0, scans = 0, validation = 0;
  LogEvent event;
  while (log->Next(event)) {
    if (event.channel == config_.channels.scan_marker) {
      auto marker = DecodeLcm<selfcal::scan_marker_t>(event.data, "log").value();
      EXPECT_EQ(marker.session_id, result.session_id);
      (marker.event == selfcal::scan_marker_t::BEGIN ? begins : ends)++;
      if (marker.purpose == selfcal::scan_marker_t::VALIDATION &&
          marker.event == selfcal::scan_marker_t::BEGIN)
        ++validation;
    }
    if (event.channel == config_.channels.joint_state) ++joints;
    if (event.channel == config_.channels.sensor) ++scans;
  }
  EXPECT_EQ(begins, 3);
  EXPECT_EQ(ends, 3);
  EXPECT_EQ(validation, 1);
  EXPECT_GT(joints, 200);
  EXPECT_GT(scans, 40);
  EXPECT_GT(arm_->commands, 100u);

  const auto rollback = Send(MakeRequest(Request_t::ROLLBACK, key_));
  EXPECT_NE(rollback.message.find("rolled back"), std::string::npos) << rollback.message;
  EXPECT_EQ(CurrentModelText(), nominal);
  EXPECT_EQ(fs::read_symlink(Path("storage/models/previous")).string(), result.session_id);
}

TEST_F(DaemonServiceTest, RejectedCalibrationLeavesTheCurrentModelUntouched) {
  Start("seconds=0.2,rms_before=0.010,rms_after=0.0098");
  const std::string before = CurrentModelText();
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(WaitResult(60));
  EXPECT_EQ(results_.back().outcome, selfcal::calibration_result_t::REJECTED);
  EXPECT_NE(results_.back().reason.find("does not improve"), std::string::npos)
      << results_.back().reason;
  EXPECT_EQ(CurrentModelText(), before);
  EXPECT_EQ(SessionStatus(results_.back().session_id), "rejected");
  // An implausible jump is rejected too, however good the residual.
  daemon_.reset();
  Start("seconds=0.2,rms_before=0.010,rms_after=0.001,shift=0.2");
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(WaitResult(60));
  EXPECT_EQ(results_.back().outcome, selfcal::calibration_result_t::REJECTED);
  EXPECT_NE(results_.back().reason.find("beyond the plausible bound"), std::string::npos)
      << results_.back().reason;
  EXPECT_EQ(CurrentModelText(), before);
}

// A remaster plan (`mode: remaster`): the engine gets the installed model with RemasterMask free
// and nothing else, the gate judges against that mask, the installed model keeps the model file's
// mask, and the result message and the history carry the corrections per axis (the report's row:
// calib_remaster_test, the test arm's recording does not load as a report's scans). The
// scripted engine turns A4's zero by 0.5 deg (on the nominal iiwa, whose axes are at right angles,
// exactly A4->A5's beta) and nudges every parameter it is free to move.
class RemasterSessionTest : public DaemonFixture {
 protected:
  void SetUp() override {
    DaemonFixture::SetUp();
    std::string plan = kPlan;
    plan.insert(plan.find("scans:"), "mode: remaster\n");
    ASSERT_TRUE(WriteFileAtomically(Path("tiny.yaml"), plan));
  }
};

TEST_F(RemasterSessionTest, FreesOnlyTheZeroOffsetsAndTheMountAndCarriesThePerAxisCorrections) {
  Start("seconds=0.3,rms_before=0.010,rms_after=0.004,shift=0,offset_joint=4,offset_deg=0.5");
  const auto nominal = ParseModelFile(CurrentModelText(), "nominal").value().model;
  const std::vector<bool> remaster = RemasterMask(nominal).value();
  ASSERT_NE(remaster, nominal.mask);
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(WaitResult(60)) << daemon_->message();
  const auto result = results_.back();
  ASSERT_EQ(result.outcome, selfcal::calibration_result_t::ACCEPTED) << result.reason;
  // The message lists what the session calibrated: RemasterMask, nothing else.
  std::vector<std::string> freed;
  for (std::size_t i = 0; i < remaster.size(); ++i) {
    if (remaster[i]) freed.push_back(ParameterName(nominal, i));
  }
  EXPECT_EQ(result.parameter_names, freed);
  const std::string a4 = "A4 +0.5000 deg";
  EXPECT_NE(result.change.find("zero offsets to add to the measured position: A2 +0.0000 deg, A3 "
                               "+0.0000 deg, " +
                               a4 +
                               ", A5 +0.0000 deg, A6 +0.0000 deg; sensor "
                               "mount 0.000 mm, 0.0000 deg"),
            std::string::npos)
      << result.change;
  const auto installed = ReadModelFile(Path("storage/models/current/model.yaml")).value().model;
  EXPECT_EQ(installed.mask, nominal.mask) << "the installed model keeps the file's mask";
  const JointOffsetFit fit = FitJointOffsets(nominal, installed);
  EXPECT_NEAR(fit.offsets[3] * 180 / M_PI, 0.5, 1e-9);

  auto history = History::Open(Path("storage/history.sqlite"), true);
  ASSERT_TRUE(history) << history.error().message;
  const auto sessions = (*history)->Sessions(1).value();
  ASSERT_EQ(sessions.size(), 1u);
  EXPECT_EQ(sessions[0].change, result.change);
}

TEST_F(RemasterSessionTest, TheEngineMayMoveExactlyTheRemasterMask) {
  Start("seconds=0.3,rms_before=0.010,rms_after=0.004,shift=0,nudge=1e-5");
  const auto nominal = ParseModelFile(CurrentModelText(), "nominal").value().model;
  const std::vector<bool> remaster = RemasterMask(nominal).value();
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(WaitResult(60)) << daemon_->message();
  ASSERT_EQ(results_.back().outcome, selfcal::calibration_result_t::ACCEPTED)
      << results_.back().reason;
  const auto installed = ReadModelFile(Path("storage/models/current/model.yaml")).value().model;
  const std::vector<double> before = ToParameterVector(nominal);
  const std::vector<double> after = ToParameterVector(installed);
  for (std::size_t i = 0; i < before.size(); ++i) {
    EXPECT_EQ(after[i] != before[i], static_cast<bool>(remaster[i])) << ParameterName(nominal, i);
  }
}

TEST_F(DaemonServiceTest, RefusesUnsignedForgedStaleReplayedAndBusyRequests) {
  Start("seconds=3");
  auto unsigned_request = MakeRequest(Request_t::START, key_);
  unsigned_request.tag_length = 0;
  unsigned_request.tag.clear();
  EXPECT_NE(Send(unsigned_request).refusal.find("unsigned"), std::string::npos);
  auth::Key other = key_;
  other[0] ^= 1;
  EXPECT_NE(Send(MakeRequest(Request_t::START, other)).refusal.find("wrong signature"),
            std::string::npos);
  auto tampered = MakeRequest(Request_t::START, key_);
  tampered.requested_by = "someone else";
  EXPECT_NE(Send(tampered).refusal.find("wrong signature"), std::string::npos);
  EXPECT_NE(Send(MakeRequest(Request_t::START, key_, Now() - 60'000'000)).refusal.find("stale"),
            std::string::npos);
  EXPECT_EQ(daemon_->state(), State::kIdle) << "no refused request may start anything";
  const auto good = MakeRequest(Request_t::START, key_);
  EXPECT_EQ(Send(good).refusal.rfind("refused", 0), std::string::npos);
  EXPECT_NE(daemon_->state(), State::kIdle);
  EXPECT_NE(Send(good).refusal.find("replayed"), std::string::npos);
  EXPECT_NE(Send(MakeRequest(Request_t::START, key_)).refusal.find("busy"), std::string::npos);
  EXPECT_NE(Send(MakeRequest(Request_t::ROLLBACK, key_)).refusal.find("busy"), std::string::npos);
  // Each refusal is in the history with its reason.
  daemon_.reset();
  auto history = History::Open(Path("storage/history.sqlite"), true);
  ASSERT_TRUE(history);
  auto nonces = (*history)->NoncesSince(0);
  ASSERT_TRUE(nonces);
  EXPECT_EQ(nonces->size(), 3u)
      << "the good START, the busy START and the busy ROLLBACK used their nonces";
}

TEST_F(DaemonServiceTest, AbortStopsMotionAtOnce) {
  Start();
  const std::string before = CurrentModelText();
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(ReachState(State::kRecording, 20));
  const auto answer = Send(MakeRequest(Request_t::ABORT, key_));
  EXPECT_EQ(daemon_->state(), State::kIdle);
  ASSERT_FALSE(results_.empty());
  EXPECT_EQ(results_.back().outcome, selfcal::calibration_result_t::ABORTED);
  EXPECT_NE(results_.back().reason.find("daemon_service_test"), std::string::npos);
  // After the hold command, no more setpoints: the arm stands where it was.
  const std::size_t commands = arm_->commands;
  const auto position = arm_->position;
  RunFor(0.5);
  EXPECT_EQ(arm_->commands, commands);
  for (std::size_t j = 0; j < position.size(); ++j)
    EXPECT_NEAR(arm_->position[j], position[j], 0.02);
  const std::string id = results_.back().session_id;
  EXPECT_EQ(SessionStatus(id), "aborted");
  EXPECT_FALSE(fs::exists(Path("storage/sessions/" + id + "/recording.lcmlog")))
      << "never committed";
  EXPECT_EQ(CurrentModelText(), before);
}

TEST_F(DaemonServiceTest, AbortStopsTheComputationAtOnce) {
  Start("seconds=30");
  const std::string before = CurrentModelText();
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(ReachState(State::kCalibrating, 30));
  RunFor(0.5);
  const std::int64_t asked = Now();
  Send(MakeRequest(Request_t::ABORT, key_));
  EXPECT_EQ(results_.back().outcome, selfcal::calibration_result_t::ABORTED);
  // The worker stops within one engine step (1.5 s here): a new session is accepted soon after.
  bool accepted = false;
  while (!accepted && Now() - asked < 5'000'000) {
    const auto answer = Send(MakeRequest(Request_t::START, key_));
    accepted = answer.refusal.rfind("refused", 0) != 0;
    if (!accepted) RunFor(0.2);
  }
  EXPECT_TRUE(accepted);
  EXPECT_LT(Now() - asked, 5'000'000);
  EXPECT_EQ(CurrentModelText(), before);
}

TEST_F(DaemonServiceTest, InMotionChecksFailTheSession) {
  Start();
  struct Case {
    std::function<void()> break_it;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {[this] { arm_->joints_silent = true; }, "joint states went stale"},
      {[this] { arm_->sensor_silent = true; }, "sensor dropout"},
      {[this] { arm_->offset_joint_0 = 0.2; }, "deviates from the trajectory"},
  };
  for (const auto& c : cases) {
    Send(MakeRequest(Request_t::START, key_));
    ASSERT_TRUE(ReachState(State::kRecording, 20)) << c.expect;
    c.break_it();
    ASSERT_TRUE(WaitResult(5)) << c.expect;
    EXPECT_EQ(results_.back().outcome, selfcal::calibration_result_t::FAILED);
    EXPECT_NE(results_.back().reason.find(c.expect), std::string::npos) << results_.back().reason;
    EXPECT_EQ(SessionStatus(results_.back().session_id), "failed");
    arm_->joints_silent = arm_->sensor_silent = false;
    arm_->offset_joint_0 = 0;
    RunFor(0.3);
  }
}

TEST_F(DaemonServiceTest, PreMotionChecksRefuseASilentSensor) {
  Start();
  arm_->sensor_silent = true;
  RunFor(0.5);
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(WaitResult(5));
  EXPECT_EQ(results_.back().outcome, selfcal::calibration_result_t::FAILED);
  EXPECT_NE(results_.back().reason.find("sensor is silent"), std::string::npos)
      << results_.back().reason;
  EXPECT_EQ(arm_->commands, 0u) << "the arm never moved";
}

TEST_F(DaemonServiceTest, RefusesToStartWithAKeyOthersMayRead) {
  chmod(Path("daemon.key").c_str(), 0644);
  auto config = ReadDaemonConfig(Path("daemon.yaml"));
  ASSERT_TRUE(config);
  auto daemon =
      Daemon::Create(*config, std::shared_ptr<Bus>(OpenLcmBus("memq://").value()), nullptr, {});
  ASSERT_FALSE(daemon);
  EXPECT_NE(daemon.error().message.find("refusing to start"), std::string::npos)
      << daemon.error().message;
}

// The engine reports progress many times a second: the status goes out at its 2 Hz and on each
// change of message, not on every report (about 95 per second before).
TEST_F(DaemonServiceTest, CalibratingPublishesAtTheStatusRateAndOnChanges) {
  Start("seconds=4,rms_before=0.010,rms_after=0.004");
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(ReachState(State::kCalibrating, 30));
  const std::size_t from = statuses_.size();
  RunFor(3.0);
  std::size_t calibrating = 0;
  std::set<std::string> messages;
  for (std::size_t i = from; i < statuses_.size(); ++i) {
    if (StateFromWire(statuses_[i].state) != State::kCalibrating) continue;
    ++calibrating;
    messages.insert(statuses_[i].message);
  }
  EXPECT_GE(calibrating, 6u) << "2 Hz for 3 s";
  EXPECT_LE(calibrating, 6u + 1u + messages.size()) << messages.size() << " messages";
}

// A refusal is an answer in its own field: the status that carries it still shows the running
// session's state and message, so a client following the session cannot take it for progress.
TEST_F(DaemonServiceTest, ARefusalLeavesTheSessionsStateAndMessage) {
  Start("seconds=2,rms_before=0.010,rms_after=0.004");
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(ReachState(State::kRecording, 20));
  const auto busy = Send(MakeRequest(Request_t::START, key_));
  EXPECT_NE(busy.refusal.find("refused: busy"), std::string::npos) << busy.refusal;
  EXPECT_EQ(StateFromWire(busy.state), daemon_->state());
  EXPECT_EQ(busy.message, daemon_->message());
  EXPECT_FALSE(busy.session_id.empty());
}

// After a session, the idle status names it and its outcome: a client that missed the terminal
// status learns it; one whose session is not named knows the daemon restarted.
TEST_F(DaemonServiceTest, TheIdleStatusNamesTheLastSessionAndItsOutcome) {
  Start("seconds=0.3,rms_before=0.010,rms_after=0.004,shift=0.003");
  EXPECT_EQ(statuses_.back().last_session_id, "");
  EXPECT_EQ(statuses_.back().last_session_state, -1);
  const auto answer = Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(WaitResult(60)) << daemon_->message();
  RunFor(1.0);
  ASSERT_EQ(StateFromWire(statuses_.back().state), State::kIdle);
  EXPECT_EQ(statuses_.back().session_id, "");
  EXPECT_EQ(statuses_.back().last_session_id, answer.session_id);
  EXPECT_EQ(statuses_.back().last_session_state, Status_t::ACCEPTED);
}

}  // namespace
}  // namespace selfcal::daemon
