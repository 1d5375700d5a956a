// calibration_result_t: the outcome's code and words, the model path only for an accepted
// session, and the calibrated parameters (and only those) before, after and with their std dev.
#include "daemon/result_message.h"

#include <gtest/gtest.h>

#include "protocols/model_file/model_file.h"

namespace selfcal::daemon {
namespace {

using Result_t = selfcal::calibration_result_t;

std::string SourceDir() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return dir ? dir : ".";
}

TEST(ResultMessageTest, OutcomesAndTheirWords) {
  const struct {
    State state;
    std::int8_t outcome;
    const char* word;
  } cases[] = {{State::kAccepted, Result_t::ACCEPTED, "accepted"},
               {State::kRejected, Result_t::REJECTED, "rejected"},
               {State::kAborted, Result_t::ABORTED, "aborted"},
               {State::kFailed, Result_t::FAILED, "failed"}};
  for (const auto& c : cases) {
    SessionOutcome ended;
    ended.outcome = c.state;
    ended.reason = "why";
    ended.utime = 42;
    ended.model_path = "/models/S/model.yaml";
    const Result_t result = MakeResultMessage("S", ended);
    EXPECT_EQ(result.outcome, c.outcome) << c.word;
    EXPECT_STREQ(OutcomeWord(c.state), c.word);
    EXPECT_EQ(result.session_id, "S");
    EXPECT_EQ(result.reason, "why");
    EXPECT_EQ(result.utime, 42);
    EXPECT_EQ(result.model_path, c.state == State::kAccepted ? "/models/S/model.yaml" : "");
    EXPECT_EQ(result.validation_rms_before, -1);
    EXPECT_EQ(result.num_parameters, 0);
  }
}

TEST(ResultMessageTest, CalibratedParametersBeforeAfterAndStdDev) {
  auto file = ReadModelFile(SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(file) << file.error().message;
  const RobotModel& before = file->model;
  CalibratedModel after;
  after.model = before;
  after.model.tool.z += 0.003;
  after.stddev.assign(before.ParameterCount(), 0.001);
  after.change = "sensor mount moved 3.0 mm / 0.00 deg (bumped?)";
  SessionRecord record;
  record.rms_before = 0.01;
  record.rms_after = 0.004;
  record.iterations = 7;
  record.runtime = 2.5;
  SessionOutcome ended;
  ended.outcome = State::kAccepted;
  ended.record = &record;
  ended.before = &before;
  ended.after = &after;
  const Result_t result = MakeResultMessage("S", ended);
  EXPECT_EQ(result.validation_rms_before, 0.01);
  EXPECT_EQ(result.validation_rms_after, 0.004);
  EXPECT_EQ(result.iterations, 7);
  EXPECT_EQ(result.runtime, 2.5);
  EXPECT_EQ(result.change, "sensor mount moved 3.0 mm / 0.00 deg (bumped?)");
  std::size_t calibrated = 0;
  for (bool m : before.mask) calibrated += m ? 1 : 0;
  ASSERT_EQ(static_cast<std::size_t>(result.num_parameters), calibrated);
  ASSERT_EQ(result.parameter_names.size(), calibrated);
  double moved = 0;
  for (std::size_t i = 0; i < calibrated; ++i) {
    moved += std::abs(result.parameters_after[i] - result.parameters_before[i]);
    EXPECT_EQ(result.parameter_stddev[i], 0.001);
  }
  EXPECT_NEAR(moved, 0.003, 1e-12) << "the tool's z moved, nothing else";
}

}  // namespace
}  // namespace selfcal::daemon
