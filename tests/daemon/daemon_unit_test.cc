// Unit tests of the daemon's parts: request authentication, key files, plans, the acceptance
// gate, the model store, session folders and the SQLite history.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/util/atomic_file.h"
#include "daemon/auth.h"
#include "daemon/clock.h"
#include "daemon/config.h"
#include "daemon/gate.h"
#include "daemon/history.h"
#include "daemon/model_store.h"
#include "daemon/plan.h"
#include "daemon/remaster.h"
#include "daemon/sessions.h"
#include "protocols/model_file/model_file.h"
#include "protocols/program/program.h"
#include "tests/yaml_leaf_paths.h"

namespace selfcal::daemon {
namespace {

namespace fs = std::filesystem;

std::string SourceDir() {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return dir ? dir : ".";
}

std::string TempDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("selfcal_daemon_unit_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

auth::Key TestKey(std::uint8_t seed) {
  auth::Key key{};
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(seed + i);
  return key;
}

selfcal::calibration_request_t SignedRequest(const auth::Key& key, std::int64_t utime,
                                             const std::string& nonce) {
  selfcal::calibration_request_t request;
  request.utime = utime;
  request.action = selfcal::calibration_request_t::START;
  request.robot_id = "r1";
  request.nonce = nonce;
  request.plan_name = "smoke";
  request.requested_by = "test";
  SignRequest(request, key);
  return request;
}

TEST(AuthTest, EveryFieldIsCoveredByTheTag) {
  const auth::Key key = TestKey(1);
  const auto request = SignedRequest(key, 1'700'000'000'000'000, "abc");
  RequestAuthenticator authenticator(key, "r1", 30);
  // Change each field after signing: the tag must no longer match.
  for (int field = 0; field < 6; ++field) {
    auto tampered = request;
    switch (field) {
      case 0:
        tampered.utime += 1;
        break;
      case 1:
        tampered.action = selfcal::calibration_request_t::ABORT;
        break;
      case 2:
        tampered.nonce = "abd";
        break;
      case 3:
        tampered.plan_name = "other";
        break;
      case 4:
        tampered.requested_by = "mallory";
        break;
      case 5:
        tampered.robot_id = "r2";
        break;
    }
    EXPECT_EQ(authenticator.Check(tampered, request.utime), Verdict::kBadSignature)
        << "field " << field;
  }
  // Moving bytes between adjacent strings changes the canonical encoding (length prefixes).
  auto shifted = request;
  shifted.nonce = "abcs";
  shifted.plan_name = "moke";
  EXPECT_NE(CanonicalRequestBytes(shifted), CanonicalRequestBytes(request));
  EXPECT_EQ(authenticator.Check(request, request.utime), Verdict::kAccepted);
}

TEST(AuthTest, RefusesUnsignedForgedStaleAndReplayed) {
  const auth::Key key = TestKey(1);
  RequestAuthenticator authenticator(key, "r1", 30);
  const std::int64_t now = 1'700'000'000'000'000;
  auto unsigned_request = SignedRequest(key, now, "n0");
  unsigned_request.tag_length = 0;
  unsigned_request.tag.clear();
  EXPECT_EQ(authenticator.Check(unsigned_request, now), Verdict::kUnsigned);
  EXPECT_EQ(authenticator.Check(SignedRequest(TestKey(2), now, "n1"), now), Verdict::kBadSignature);
  auto short_tag = SignedRequest(key, now, "n1");
  short_tag.tag.resize(16);
  short_tag.tag_length = 16;
  EXPECT_EQ(authenticator.Check(short_tag, now), Verdict::kBadSignature);
  EXPECT_EQ(authenticator.Check(SignedRequest(key, now - 31'000'000, "n2"), now), Verdict::kStale);
  EXPECT_EQ(authenticator.Check(SignedRequest(key, now + 31'000'000, "n3"), now), Verdict::kStale);
  const auto fresh = SignedRequest(key, now - 29'000'000, "n4");
  EXPECT_EQ(authenticator.Check(fresh, now), Verdict::kAccepted);
  EXPECT_EQ(authenticator.Check(fresh, now + 1'000'000), Verdict::kReplayed);
  // A stale request is refused as stale even with a new nonce; a remembered nonce survives a
  // restart.
  RequestAuthenticator restarted(key, "r1", 30);
  restarted.RememberNonce("n4", fresh.utime);
  EXPECT_EQ(restarted.Check(fresh, now), Verdict::kReplayed);
  EXPECT_EQ(authenticator.Check(SignedRequest(key, now, ""), now), Verdict::kMalformed);
}

// At capacity the authenticator forgets the nonce of the request signed first (not the one
// received first) and refuses everything signed at or before it; the others stay used.
TEST(AuthTest, AtCapacityForgetsTheOldestSignedNonceAndRefusesWhatWasSignedBeforeIt) {
  const auth::Key key = TestKey(1);
  RequestAuthenticator authenticator(key, "r1", 30, /*capacity=*/3);
  const std::int64_t now = 1'700'000'000'000'000;
  const auto a = SignedRequest(key, now + 3, "a");
  const auto b = SignedRequest(key, now + 1, "b");
  const auto c = SignedRequest(key, now + 2, "c");
  for (const auto& request : {a, b, c})
    EXPECT_EQ(authenticator.Check(request, now), Verdict::kAccepted);
  EXPECT_EQ(authenticator.Check(SignedRequest(key, now + 4, "d"), now), Verdict::kAccepted);
  EXPECT_EQ(authenticator.Check(b, now), Verdict::kTooOld);
  EXPECT_EQ(authenticator.Check(SignedRequest(key, now + 1, "e"), now), Verdict::kTooOld);
  EXPECT_EQ(authenticator.Check(a, now), Verdict::kReplayed);
  EXPECT_EQ(authenticator.Check(c, now), Verdict::kReplayed);
}

// Found by fuzz_calibration_request: the age of a request and the horizon of remembered nonces
// were differences that overflow at the ends of the int64 range (undefined behaviour); near the
// lower end the wrapped horizon forgot every nonce and a replay was accepted.
TEST(AuthTest, TimesAtTheEndsOfTheRangeNeitherOverflowNorOpenAReplay) {
  const auth::Key key = TestKey(1);
  RequestAuthenticator authenticator(key, "r1", 30);
  const std::int64_t now = 1'700'000'000'000'000;
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min();
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  EXPECT_EQ(authenticator.Check(SignedRequest(key, kMin, "old"), now), Verdict::kStale);
  EXPECT_EQ(authenticator.Check(SignedRequest(key, kMax, "new"), -now), Verdict::kStale);
  const std::int64_t early = kMin + 5'000'000;
  const auto first = SignedRequest(key, early, "early");
  EXPECT_EQ(authenticator.Check(first, early), Verdict::kAccepted);
  EXPECT_EQ(authenticator.Check(first, early), Verdict::kReplayed);
}

TEST(AuthTest, RefusesRequestsForAnotherRobotWithoutUsingTheirNonce) {
  const auth::Key key = TestKey(1);
  RequestAuthenticator r1(key, "r1", 30);
  RequestAuthenticator r2(key, "r2", 30);
  const std::int64_t now = 1'700'000'000'000'000;
  const auto request = SignedRequest(key, now, "n1");  // for r1
  EXPECT_EQ(r2.Check(request, now), Verdict::kOtherRobot);
  EXPECT_EQ(r1.Check(request, now), Verdict::kAccepted);
}

TEST(AuthTest, RefusesWeakKeys) {
  const std::string dir = TempDir("weak");
  const std::vector<std::string> weak = {std::string(64, '0'), std::string(64, 'f'),
                                         [] {
                                           std::string hex;
                                           for (int i = 0; i < 16; ++i) hex += "00ff";
                                           return hex;
                                         }(),
                                         [] {
                                           std::string hex;
                                           for (int i = 0; i < 8; ++i) hex += "01020304";
                                           return hex;
                                         }()};
  for (const auto& hex : weak) {
    ASSERT_TRUE(WriteFileAtomically(dir + "/weak.key", hex + "\n"));
    chmod((dir + "/weak.key").c_str(), 0600);
    auto key = auth::ReadKeyFile(dir + "/weak.key", true);
    ASSERT_FALSE(key) << hex;
    EXPECT_NE(key.error().message.find("weak"), std::string::npos) << key.error().message;
  }
  ASSERT_TRUE(auth::GenerateKeyFile(dir + "/random.key"));
  EXPECT_TRUE(auth::ReadKeyFile(dir + "/random.key", true));
}

TEST(AuthTest, KeyFilesArePrivateAndWellFormed) {
  const std::string dir = TempDir("key");
  const std::string path = dir + "/daemon.key";
  ASSERT_TRUE(auth::GenerateKeyFile(path));
  EXPECT_FALSE(auth::GenerateKeyFile(path)) << "must not overwrite";
  struct stat info {};
  ASSERT_EQ(stat(path.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  EXPECT_TRUE(auth::ReadKeyFile(path, true));
  chmod(path.c_str(), 0640);
  auto refused = auth::ReadKeyFile(path, true);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("0640"), std::string::npos) << refused.error().message;
  EXPECT_TRUE(auth::ReadKeyFile(path, false)) << "a client may read a group-readable copy";
  chmod(path.c_str(), 0600);
  ASSERT_TRUE(WriteFileAtomically(dir + "/bad.key", std::string(63, 'a') + "g\n"));
  chmod((dir + "/bad.key").c_str(), 0600);
  auto bad = auth::ReadKeyFile(dir + "/bad.key", true);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("byte 62"), std::string::npos) << bad.error().message;
  ASSERT_TRUE(WriteFileAtomically(dir + "/short.key", "abcd\n"));
  EXPECT_FALSE(auth::ReadKeyFile(dir + "/short.key", false));
}

TEST(ConfigTest, ReadsTheShippedConfigAndRejectsUnknownKeys) {
  auto config = ReadDaemonConfig(SourceDir() + "/config/daemon.yaml");
  ASSERT_TRUE(config) << config.error().message;
  EXPECT_EQ(config->default_plan, "smoke");
  EXPECT_EQ(config->robot_model, SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  EXPECT_EQ(config->key_file, SourceDir() + "/config/daemon.key");
  auto text = ReadFile(SourceDir() + "/config/daemon.yaml");
  ASSERT_TRUE(text);
  auto unknown = ParseDaemonConfig(*text + "bogus: 1\n", "/etc/x/daemon.yaml");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("bogus"), std::string::npos) << unknown.error().message;
  auto wrong_plan = ParseDaemonConfig(*text + "\n", "/etc/x/daemon.yaml");
  EXPECT_TRUE(wrong_plan);
  // The margin is off until a site measures its floor (docs/daemon.md, the acceptance gate).
  EXPECT_DOUBLE_EQ(config->acceptance.noise_floor, 0.0);
  EXPECT_DOUBLE_EQ(config->acceptance.min_improvement, 0.0);
  const std::string minimal =
      "robot_id: r1\nrobot_model: r.yaml\nsensor: s.yaml\nplans: {p: p.yaml}\ndefault_plan: p\n"
      "storage: {folder: s}\nkey_file: k\n";
  auto plain =
      ParseDaemonConfig(minimal + "acceptance: {min_improvement: 0.05}\n", "/etc/x/daemon.yaml");
  ASSERT_TRUE(plain) << plain.error().message;
  EXPECT_EQ(plain->acceptance.noise_floor, 0.0);  // omitted: the plain relative rule
  auto negative =
      ParseDaemonConfig(minimal + "acceptance: {noise_floor_m: -0.001}\n", "/etc/x/daemon.yaml");
  ASSERT_FALSE(negative);
  EXPECT_NE(negative.error().message.find("noise_floor_m"), std::string::npos)
      << negative.error().message;
  EXPECT_DOUBLE_EQ(config->acceptance.max_predicted_error, 0.005);
  EXPECT_DOUBLE_EQ(plain->acceptance.max_predicted_error, 0.005);  // omitted: the default
  auto no_bound =
      ParseDaemonConfig(minimal + "acceptance: {max_predicted_error_m: 0}\n", "/etc/x/daemon.yaml");
  ASSERT_FALSE(no_bound);
  EXPECT_NE(no_bound.error().message.find("max_predicted_error_m"), std::string::npos)
      << no_bound.error().message;
  EXPECT_EQ(plain->acceptance.max_held_out_offset, 0.0);  // omitted: off
  auto held_out = ParseDaemonConfig(minimal + "acceptance: {max_held_out_offset_m: 0.004}\n",
                                    "/etc/x/daemon.yaml");
  ASSERT_TRUE(held_out) << held_out.error().message;
  EXPECT_DOUBLE_EQ(held_out->acceptance.max_held_out_offset, 0.004);
  auto negative_held_out = ParseDaemonConfig(
      minimal + "acceptance: {max_held_out_offset_m: -0.001}\n", "/etc/x/daemon.yaml");
  ASSERT_FALSE(negative_held_out);
  EXPECT_NE(negative_held_out.error().message.find("max_held_out_offset_m"), std::string::npos)
      << negative_held_out.error().message;
}

// Every key the shipped daemon.yaml sets (it sets them all) is in the start-up echo, under its
// key path, with the effective value (relative paths resolved).
TEST(ConfigTest, TheStartUpEchoNamesEveryKeyOfTheFile) {
  auto config = ReadDaemonConfig(SourceDir() + "/config/daemon.yaml");
  ASSERT_TRUE(config) << config.error().message;
  program::Program program("selfcald-test", "test");
  DescribeSettings(program, *config);
  const std::string echo = program.Configuration();
  // The file lists every setting, so the echo holds exactly its keys.
  const auto keys = testing::LeafPaths(YAML::LoadFile(SourceDir() + "/config/daemon.yaml"));
  EXPECT_EQ(keys.size(), 39u);
  auto sorted = [](std::vector<std::string> v) {
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_EQ(sorted(testing::EchoedKeys(echo)), sorted(keys)) << echo;
  EXPECT_EQ(testing::EchoedValue(echo, "plans.smoke"),
            SourceDir() + "/config/daemon/plans/iiwa_smoke.yaml");
  EXPECT_EQ(testing::EchoedValue(echo, "storage.quota_mb"), "2048");
  EXPECT_EQ(testing::EchoedValue(echo, "checks.max_lag_s"), "0.1");
  EXPECT_EQ(testing::EchoedValue(echo, "channels.robot_status"), "SELFCAL_ROBOT_STATUS");
  // Values come from the struct when the echo is printed: an override after reading shows.
  config->key_file = "/run/credentials/daemon.key";
  EXPECT_EQ(testing::EchoedValue(program.Configuration(), "key_file"),
            "/run/credentials/daemon.key");
}

TEST(PlanTest, ShippedPlanIsWithinLimitsAndViolationsAreNamed) {
  auto model = ReadModelFile(SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(model) << model.error().message;
  auto plan = ReadScanPlan(SourceDir() + "/config/daemon/plans/iiwa_smoke.yaml");
  ASSERT_TRUE(plan) << plan.error().message;
  EXPECT_EQ(CheckPlan(*plan, model->model, 0.01), "");
  auto outside = *plan;
  outside.scans[1].to[3] = 2.2;
  EXPECT_NE(CheckPlan(outside, model->model, 0.01).find("joint A4 = 2.2 is outside"),
            std::string::npos)
      << CheckPlan(outside, model->model, 0.01);
  auto too_fast = *plan;
  too_fast.scans[0].speed = 3.0;
  EXPECT_NE(CheckPlan(too_fast, model->model, 0.01).find("velocity limit"), std::string::npos);
  auto no_validation = *plan;
  no_validation.scans.pop_back();
  EXPECT_NE(CheckPlan(no_validation, model->model, 0.01).find("no validation"), std::string::npos);
  auto wrong_count = *plan;
  wrong_count.scans[0].from.pop_back();
  EXPECT_NE(CheckPlan(wrong_count, model->model, 0.01).find("has 6 joints"), std::string::npos);
}

// A plan's position at time t: the trajectory the daemon sends to the arm's driver.
std::vector<double> At(const trajectory::JointTrajectory& motion, double t) {
  const Eigen::VectorXd q = motion.Evaluate(t).position;
  return {q.data(), q.data() + q.size()};
}

TEST(PlanTest, MotionsRespectLimitsAndEndAtTheTarget) {
  auto model = ReadModelFile(SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(model);
  const std::vector<double> from = {0, 0, 0, 0, 0, 0, 0};
  const std::vector<double> to = {1.0, -0.5, 0, 0.2, 0, 0, 2.0};
  ScanPlan plan;
  plan.name = "one";
  plan.scans.push_back({false, to, to, 0.1});  // a camera pose: the motion is the move to it
  auto planned = PlanScanMotion(plan, from, model->model, 0.5, 0);
  ASSERT_TRUE(planned) << planned.error().message;
  const auto& motion = planned->trajectory;
  ASSERT_GT(motion.duration(), 0);
  EXPECT_EQ(At(motion, 0), from);
  EXPECT_EQ(At(motion, motion.duration()), to);
  const double dt = 1e-3;
  std::vector<double> previous = At(motion, 0), previous_velocity(7, 0.0);
  for (double t = dt; t <= motion.duration(); t += dt) {
    const auto q = At(motion, t);
    for (std::size_t j = 0; j < 7; ++j) {
      const double velocity = (q[j] - previous[j]) / dt;
      EXPECT_LE(std::abs(velocity), 0.5 * model->model.joints[j].max_velocity * 1.001)
          << "joint " << j << " t " << t;
      EXPECT_LE(std::abs(velocity - previous_velocity[j]) / dt,
                0.5 * model->model.joints[j].max_acceleration * 1.01)
          << "joint " << j << " t " << t;
      previous_velocity[j] = velocity;
    }
    previous = q;
  }
}

// The demo's A1 sweep: half a turn at 1.2217 rad/s, above half of A1's 1.483 rad/s limit. The
// sweep must reach the plan's speed (it sets the LiDAR's line spacing), not the moves' fraction.
TEST(PlanTest, SweepsRunAtThePlannedSpeed) {
  auto model = ReadModelFile(SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(model);
  PlannedScan scan;
  scan.from = {-2.0, 0.5, 0, -1.2, 0, 0.8, 0};
  scan.to = scan.from;
  scan.to[0] += 3.141592653589793;
  scan.speed = 1.2217;
  auto planned = PlanSweep(scan, model->model, 0.3);
  ASSERT_TRUE(planned) << planned.error().message;
  const auto& sweep = *planned;
  double peak = 0;
  const double dt = 1e-3;
  for (double t = dt; t <= sweep.duration(); t += dt) {
    peak = std::max(peak, std::abs(At(sweep, t)[0] - At(sweep, t - dt)[0]) / dt);
  }
  EXPECT_NEAR(peak, scan.speed, 1e-3);
  EXPECT_EQ(At(sweep, sweep.duration()), scan.to);
}

RobotModel IiwaModel() {
  auto file = ReadModelFile(SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  EXPECT_TRUE(file) << file.error().message;
  return file ? file->model : RobotModel{};
}

ValidationEvidence Rms(double before, double after) { return {before, after, 0, 0}; }

TEST(GateTest, WithoutANoiseFloorThePlainRmsMustImproveByTheMargin) {
  const RobotModel before = IiwaModel();
  AcceptanceConfig config;
  config.min_improvement = 0.1;
  config.max_angle_change = 0.01;
  config.max_translation_change = 0.02;
  RobotModel after = before;
  after.tool.z += 0.01;
  EXPECT_TRUE(ApplyAcceptanceGate(config, before, after, Rms(0.010, 0.005)).accepted);
  EXPECT_TRUE(ApplyAcceptanceGate(config, before, after, Rms(0.010, 0.009)).accepted);
  const auto small = ApplyAcceptanceGate(config, before, after, Rms(0.010, 0.0091));
  EXPECT_FALSE(small.accepted);
  EXPECT_NE(small.reason.find("does not improve"), std::string::npos) << small.reason;
  EXPECT_FALSE(ApplyAcceptanceGate(config, before, after, Rms(0.010, NAN)).accepted);
  EXPECT_FALSE(ApplyAcceptanceGate(config, before, after, Rms(0.0, 0.0)).accepted);
}

TEST(GateTest, ModelErrorPartIsWhatTheFloorLeaves) {
  EXPECT_DOUBLE_EQ(ModelErrorPart(0.005, 0.0), 0.005);
  EXPECT_NEAR(ModelErrorPart(0.005, 0.003), 0.004, 1e-15);  // 3-4-5
  EXPECT_EQ(ModelErrorPart(0.002, 0.003), 0.0);             // below the floor: nothing left
}

// The Hokuyo case of docs/daemon.md: the plain RMS moves 6 %, the model part far more.
TEST(GateTest, AboveANoiseFloorAGoodModelPassesAndAMarginalOneDoesNot) {
  const RobotModel before = IiwaModel();
  RobotModel after = before;
  after.tool.x += 0.02;
  after.segments[3].beta += 0.003;
  AcceptanceConfig config;
  config.min_improvement = 0.3;
  config.noise_floor = 0.0075;
  const ValidationEvidence good{0.00831, 0.00782, 90000, 120000};
  const auto accepted = ApplyAcceptanceGate(config, before, after, good);
  EXPECT_TRUE(accepted.accepted) << accepted.reason;
  EXPECT_NE(accepted.reason.find("noise floor"), std::string::npos) << accepted.reason;
  // The same numbers fail a plain 30 % margin: the floor is what makes them meaningful.
  AcceptanceConfig plain = config;
  plain.noise_floor = 0;
  EXPECT_FALSE(ApplyAcceptanceGate(plain, before, after, good).accepted);
  // Part above the floor 3.58 -> 3.44 mm (4 %): not a real improvement.
  const auto marginal =
      ApplyAcceptanceGate(config, before, after, {0.00831, 0.00825, 90000, 91000});
  EXPECT_FALSE(marginal.accepted);
  EXPECT_NE(marginal.reason.find("does not improve"), std::string::npos) << marginal.reason;
  // Down to the floor or below it: everything explainable is explained.
  EXPECT_TRUE(
      ApplyAcceptanceGate(config, before, after, {0.00831, 0.0074, 90000, 130000}).accepted);
}

TEST(GateTest, RejectsAWorseModelWhateverTheFloor) {
  const RobotModel before = IiwaModel();
  RobotModel after = before;
  after.tool.z += 0.001;
  for (const double floor : {0.0, 0.0075, 0.0082}) {
    AcceptanceConfig config;
    config.min_improvement = 0.3;
    config.noise_floor = floor;
    const auto worse = ApplyAcceptanceGate(config, before, after, {0.00831, 0.00840, 90000, 90000});
    EXPECT_FALSE(worse.accepted) << "floor " << floor;
    EXPECT_FALSE(ApplyAcceptanceGate(config, before, after, Rms(0.00831, 0.00831)).accepted)
        << "floor " << floor;
  }
}

// A current model at the floor has nothing left to improve: with the optional margin set, an
// equally good or better new model is installed, a worse one is not.
TEST(GateTest, ACurrentModelAtTheFloorNeedsOnlyBeMatched) {
  const RobotModel before = IiwaModel();
  AcceptanceConfig config;
  config.noise_floor = 0.008;
  config.min_improvement = 0.05;
  const auto better = ApplyAcceptanceGate(config, before, before, {0.0079, 0.0070, 90000, 91000});
  EXPECT_TRUE(better.accepted) << better.reason;
  // 3 x 7.9 mm / sqrt(90000) = 0.079 mm of tolerance.
  const auto same = ApplyAcceptanceGate(config, before, before, {0.0079, 0.00795, 90000, 90000});
  EXPECT_TRUE(same.accepted) << same.reason;
  const auto worse = ApplyAcceptanceGate(config, before, before, {0.0079, 0.0080, 90000, 90000});
  EXPECT_FALSE(worse.accepted);
  EXPECT_NE(worse.reason.find("worse than the current model beyond the tolerance of 0.079 mm"),
            std::string::npos)
      << worse.reason;
}

// What recalibrating from the true model of the small scenario gave: validation RMS 5.25438 ->
// 5.25605 mm (+0.03 %), 297838 -> 297786 matches. Noise of the comparison, not a worse model.
TEST(GateTest, RecalibratingACorrectModelIsAcceptedWithinTheTolerance) {
  const RobotModel before = IiwaModel();
  RobotModel after = before;
  after.tool.x += 0.0005;
  const AcceptanceConfig defaults;
  EXPECT_NEAR(ValidationTolerance({0.00525438, 0.00525605, 297838, 297786}),
              3 * 0.00525438 / std::sqrt(297786.0), 1e-15);
  const auto again =
      ApplyAcceptanceGate(defaults, before, after, {0.00525438, 0.00525605, 297838, 297786});
  EXPECT_TRUE(again.accepted) << again.reason;
  EXPECT_NE(again.reason.find("tolerance 0.0288"), std::string::npos) << again.reason;
  // A rise of 2 % over 20,000 matches is beyond 3 x 4 mm / sqrt(20000) = 0.085 mm.
  const auto risen = ApplyAcceptanceGate(defaults, before, after, {0.004, 0.00408, 20000, 20000});
  EXPECT_TRUE(risen.accepted) << risen.reason;
  const auto worse = ApplyAcceptanceGate(defaults, before, after, {0.004, 0.0041, 20000, 20000});
  EXPECT_FALSE(worse.accepted);
  EXPECT_NE(worse.reason.find("4 mm -> 4.1 mm: worse than the current model"), std::string::npos)
      << worse.reason;
  // Without match counts there is no tolerance: not worse means not higher.
  EXPECT_FALSE(ApplyAcceptanceGate(defaults, before, after, Rms(0.004, 0.0040001)).accepted);
  // A few matches fewer is chance (3 sqrt(N)); a third fewer is not.
  EXPECT_TRUE(ApplyAcceptanceGate(defaults, before, after, {0.004, 0.004, 20000, 19700}).accepted);
  EXPECT_FALSE(ApplyAcceptanceGate(defaults, before, after, {0.004, 0.004, 20000, 19500}).accepted);
}

// An engine result as ToCalibratedModel() makes it: converged, validated, certain enough.
CalibratedModel GoodResult(const RobotModel& current) {
  CalibratedModel result;
  result.model = current;
  result.model.tool.z += 0.002;
  result.usable = true;
  result.message = "converged: |delta k| small";
  result.validation_rms_before = 0.009;
  result.validation_rms_after = 0.005;
  result.validation_matches_before = 150000;
  result.validation_matches_after = 290000;
  result.predicted_error = 0.0012;
  result.predicted_worst_error = 0.0016;
  return result;
}

TEST(GateTest, JudgeCalibrationNamesTheRuleThatFailedWithItsNumbers) {
  const RobotModel current = IiwaModel();
  const AcceptanceConfig defaults;  // bound 5 mm
  CalibratedModel good = GoodResult(current);
  const auto accepted = JudgeCalibration(defaults, current, good);
  EXPECT_TRUE(accepted.accepted) << accepted.reason;
  EXPECT_NE(accepted.reason.find("predicted sensor position error 1.2 mm RMS, worst 1.6 mm"),
            std::string::npos)
      << accepted.reason;

  CalibratedModel unsure = GoodResult(current);
  unsure.predicted_error = 0.0061;
  unsure.predicted_worst_error = 0.0074;
  const auto too_unsure = JudgeCalibration(defaults, current, unsure);
  EXPECT_FALSE(too_unsure.accepted);
  EXPECT_NE(too_unsure.reason.find("predicted sensor position error 6.1 mm RMS over the workspace "
                                   "(worst 7.4 mm) exceeds the bound of 5 mm"),
            std::string::npos)
      << too_unsure.reason;
  AcceptanceConfig lenient;
  lenient.max_predicted_error = 0.008;
  EXPECT_TRUE(JudgeCalibration(lenient, current, unsure).accepted);
  // What the calibration holds (the sensor's intrinsics) is named as part of the prediction.
  unsure.predicted_held_error = 0.0052;
  const auto held = JudgeCalibration(defaults, current, unsure);
  EXPECT_FALSE(held.accepted);
  EXPECT_NE(held.reason.find("(worst 7.4 mm) (5.2 mm of it from what the calibration holds at "
                             "assumed values) exceeds the bound of 5 mm"),
            std::string::npos)
      << held.reason;
  EXPECT_NE(JudgeCalibration(lenient, current, unsure)
                .reason.find("worst 7.4 mm (5.2 mm of it from what the calibration holds"),
            std::string::npos);

  CalibratedModel unknown = GoodResult(current);
  unknown.predicted_error = -1;
  const auto no_prediction = JudgeCalibration(lenient, current, unknown);
  EXPECT_FALSE(no_prediction.accepted);
  EXPECT_NE(no_prediction.reason.find("no predicted error"), std::string::npos)
      << no_prediction.reason;

  CalibratedModel blind = GoodResult(current);
  blind.unobservable = {"A1->A2.x: not observable from these scans"};
  const auto unobservable = JudgeCalibration(defaults, current, blind);
  EXPECT_FALSE(unobservable.accepted);
  EXPECT_EQ(unobservable.reason, "unobservable: A1->A2.x: not observable from these scans");

  CalibratedModel stopped = GoodResult(current);
  stopped.usable = false;
  stopped.message = "max_iterations: i_max = 50 reached";
  EXPECT_EQ(JudgeCalibration(defaults, current, stopped).reason,
            "the engine's result is not usable: max_iterations: i_max = 50 reached");
}

TEST(GateTest, TheHeldOutScansAreHeldToTheirBoundOnlyWhenOneIsSet) {
  const RobotModel current = IiwaModel();
  CalibratedModel drifting = GoodResult(current);
  drifting.held_out_offset = 0.0041;
  drifting.held_out_worst_offset = 0.0063;
  const AcceptanceConfig defaults;  // max_held_out_offset 0: not checked
  const auto unchecked = JudgeCalibration(defaults, current, drifting);
  EXPECT_TRUE(unchecked.accepted) << unchecked.reason;
  // Said beside the prediction even when not checked.
  EXPECT_NE(unchecked.reason.find("(bound 5 mm); held-out scans moved 4.1 mm RMS"),
            std::string::npos)
      << unchecked.reason;
  EXPECT_EQ(unchecked.reason.find("bound 0 mm"), std::string::npos) << unchecked.reason;

  AcceptanceConfig bounded;
  bounded.max_held_out_offset = 0.003;
  const auto refused = JudgeCalibration(bounded, current, drifting);
  EXPECT_FALSE(refused.accepted);
  EXPECT_NE(refused.reason.find("the held-out scans, registered onto the fit scans, move their "
                                "sensor origins 4.1 mm RMS (worst 6.3 mm), beyond the bound of "
                                "3 mm (acceptance.max_held_out_offset_m)"),
            std::string::npos)
      << refused.reason;

  CalibratedModel steady = GoodResult(current);
  steady.held_out_offset = 0.0014;
  steady.held_out_worst_offset = 0.0019;
  const auto accepted = JudgeCalibration(bounded, current, steady);
  EXPECT_TRUE(accepted.accepted) << accepted.reason;
  EXPECT_NE(accepted.reason.find("held-out scans moved 1.4 mm RMS (bound 3 mm)"), std::string::npos)
      << accepted.reason;

  CalibratedModel unregistered = GoodResult(current);  // held_out_offset -1
  const auto unknown = JudgeCalibration(bounded, current, unregistered);
  EXPECT_FALSE(unknown.accepted);
  EXPECT_NE(unknown.reason.find("no held-out scan could be registered"), std::string::npos)
      << unknown.reason;
}

TEST(GateTest, WithoutValidationScansOnlyAnExplicitSkipJudgesOnTheOtherRules) {
  const RobotModel current = IiwaModel();
  const AcceptanceConfig defaults;
  CalibratedModel result = GoodResult(current);
  result.validation_rms_before = result.validation_rms_after = -1;
  result.validation_matches_before = result.validation_matches_after = 0;
  const auto refused = JudgeCalibration(defaults, current, result);
  EXPECT_FALSE(refused.accepted);
  EXPECT_EQ(refused.reason, "validation failed: the recording has no validation scans");
  const auto skipped = JudgeCalibration(defaults, current, result, ValidationRule::kSkipped);
  EXPECT_TRUE(skipped.accepted) << skipped.reason;
  EXPECT_NE(skipped.reason.find("no validation scans (--no-validation)"), std::string::npos)
      << skipped.reason;
  // The other rules still hold.
  result.model.tool.z += 0.2;
  const auto jump = JudgeCalibration(defaults, current, result, ValidationRule::kSkipped);
  EXPECT_FALSE(jump.accepted);
  EXPECT_NE(jump.reason.find("beyond the plausible bound"), std::string::npos) << jump.reason;
}

// The RMS counts only matches within d_max: losing the worst matches lowers it too.
TEST(GateTest, RejectsALowerRmsBoughtWithFewerMatches) {
  const RobotModel before = IiwaModel();
  AcceptanceConfig config;
  config.noise_floor = 0.0075;
  config.min_improvement = 0.3;
  const auto decision =
      ApplyAcceptanceGate(config, before, before, {0.00831, 0.00760, 90000, 60000});
  EXPECT_FALSE(decision.accepted);
  EXPECT_NE(decision.reason.find("fewer validation points"), std::string::npos) << decision.reason;
}

TEST(GateTest, RejectsImplausibleParameterJumpsEvenWithAPerfectResidual) {
  const RobotModel before = IiwaModel();
  AcceptanceConfig config;
  config.min_improvement = 0.1;
  config.noise_floor = 0.0075;
  config.max_angle_change = 0.01;
  config.max_translation_change = 0.02;
  const ValidationEvidence perfect{0.010, 0.0075, 1000, 2000};
  RobotModel far = before;
  far.tool.z += 0.03;
  const auto moved = ApplyAcceptanceGate(config, before, far, perfect);
  EXPECT_FALSE(moved.accepted);
  EXPECT_NE(moved.reason.find("A7->tool moves by 0.03"), std::string::npos) << moved.reason;
  RobotModel angle = before;
  angle.segments[2].beta += 0.02;
  const auto turned = ApplyAcceptanceGate(config, before, angle, perfect);
  EXPECT_FALSE(turned.accepted);
  EXPECT_NE(turned.reason.find("beyond the plausible bound"), std::string::npos) << turned.reason;
  RobotModel base = before;
  base.base.z += 0.001;  // never calibrated
  EXPECT_FALSE(ApplyAcceptanceGate(config, before, base, perfect).accepted);
  RobotModel inside = before;
  inside.tool.z += 0.019;
  inside.segments[2].beta -= 0.009;
  EXPECT_TRUE(ApplyAcceptanceGate(config, before, inside, perfect).accepted);
}

// The model a result is re-judged against (selfcal report): a remastering's result (its
// `remaster:` section) against the remastering's mask, as selfcald judged it; any other against
// the model as it is; a calibration: section that is not YAML is an error that says where.
TEST(GateTest, AResultIsJudgedAgainstTheMaskItsEngineStartedFrom) {
  const RobotModel installed = IiwaModel();
  const auto remastering =
      JudgedAgainst(installed, "termination: converged\nremaster:\n  samples: 200\n");
  ASSERT_TRUE(remastering) << remastering.error().message;
  EXPECT_EQ(remastering->mask, RemasterMask(installed).value());
  EXPECT_NE(remastering->mask, installed.mask);
  const auto full = JudgedAgainst(installed, "termination: converged\n");
  ASSERT_TRUE(full) << full.error().message;
  EXPECT_EQ(full->mask, installed.mask);
  const auto broken = JudgedAgainst(installed, "termination: converged\nremaster: [1, 2\n");
  ASSERT_FALSE(broken);
  EXPECT_NE(broken.error().message.find("line "), std::string::npos) << broken.error().message;
}

// A remastering after a motor swap (tools/demo --remaster, seed 19: A4 0.5 deg off, recovered
// within 0.007 deg) moves the validation RMS 8.19698 -> 8.18328 mm: the site's 40 % margin above
// an 8.1 mm floor refuses it, the remastering's rules accept it and still refuse a worse model.
TEST(GateTest, ARemasteringIsJudgedWithoutTheImprovementMargin) {
  const RobotModel before = IiwaModel();
  RobotModel after = before;  // what the engine changed is not what this rule looks at
  after.segments[3].beta += 0.5 * M_PI / 180;
  AcceptanceConfig site;
  site.min_improvement = 0.4;
  site.noise_floor = 0.0081;
  const ValidationEvidence swap{0.00819698, 0.00818328, 90000, 90100};
  const auto full = ApplyAcceptanceGate(site, before, after, swap);
  EXPECT_FALSE(full.accepted);
  EXPECT_NE(full.reason.find("does not improve"), std::string::npos) << full.reason;
  const AcceptanceConfig remaster = RemasterAcceptance(site);
  EXPECT_EQ(remaster.min_improvement, 0);
  EXPECT_EQ(remaster.noise_floor, site.noise_floor);
  EXPECT_EQ(remaster.max_predicted_error, site.max_predicted_error);
  const auto accepted = ApplyAcceptanceGate(remaster, before, after, swap);
  EXPECT_TRUE(accepted.accepted) << accepted.reason;
  EXPECT_FALSE(
      ApplyAcceptanceGate(remaster, before, after, {0.00819698, 0.0083, 90000, 90000}).accepted);
}

// What a demo session's engine returned: base.z (never calibrated) one ulp off after k / s * s.
TEST(GateTest, RoundOffOfUncalibratedParametersIsUndoneAndRealChangesAreNot) {
  const RobotModel before = IiwaModel();
  ASSERT_FALSE(before.mask[5]);  // base.z
  const ValidationEvidence good{0.010, 0.004, 1000, 2000};
  AcceptanceConfig config;
  RobotModel ulp = before;
  ulp.base.z = std::nextafter(ulp.base.z, 1.0);
  ulp.tool.x += 0.001;                                                    // calibrated: kept
  EXPECT_FALSE(ApplyAcceptanceGate(config, before, ulp, good).accepted);  // the exact check
  EXPECT_EQ(RestoreRoundOff(before, ulp), 1);
  EXPECT_EQ(ulp.base.z, before.base.z);
  EXPECT_EQ(ulp.tool.x, before.tool.x + 0.001);
  EXPECT_TRUE(ApplyAcceptanceGate(config, before, ulp, good).accepted);
  RobotModel moved = before;
  moved.base.z += 1e-9;
  EXPECT_EQ(RestoreRoundOff(before, moved), 0);
  const auto refused = ApplyAcceptanceGate(config, before, moved, good);
  EXPECT_FALSE(refused.accepted);
  EXPECT_NE(refused.reason.find("base.z is not calibrated but changed"), std::string::npos)
      << refused.reason;
}

// A sensor mounted at right angles (tool beta = -90 deg, the demo's Hokuyo): RotX(a) RotY(-90 deg)
// RotZ(g) = RotX(a - g) RotY(-90 deg), so alpha and gamma moving together change nothing. The
// bound is on what the link does, so such a model passes and a real turn of the same size fails.
TEST(GateTest, BoundsApplyToEachLinksTransformNotToDegenerateParameters) {
  RobotModel before = IiwaModel();
  before.tool.beta = -1.5707963267948966;
  before.tool.x = 0.216;
  AcceptanceConfig config;  // bounds 0.05 rad, 0.05 m
  const ValidationEvidence good{0.010, 0.004, 1000, 2000};
  RobotModel split = before;
  split.tool.alpha += 0.0715;
  split.tool.gamma += 0.0715;
  const auto same = ApplyAcceptanceGate(config, before, split, good);
  EXPECT_TRUE(same.accepted) << same.reason;
  RobotModel turned = before;
  turned.tool.alpha += 0.0715;
  const auto real = ApplyAcceptanceGate(config, before, turned, good);
  EXPECT_FALSE(real.accepted);
  EXPECT_NE(real.reason.find("A7->tool turns by 0.0715"), std::string::npos) << real.reason;
}

TEST(ClockTest, MillisPrintsAgesInFixedPointMilliseconds) {
  EXPECT_EQ(Millis(12'500), "12.5 ms");
  EXPECT_EQ(Millis(1'000'400), "1000.4 ms") << "not 1e+03 ms";
  EXPECT_EQ(Millis(0), "0.0 ms");
}

TEST(ModelStoreTest, InstallKeepsThePreviousAndRollbackRestoresIt) {
  const std::string dir = TempDir("models");
  const std::string nominal = SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml";
  int urdf_calls = 0;
  auto store =
      ModelStore::Open(dir, nominal, [&](const RobotModel& model) -> Expected<std::string> {
        ++urdf_calls;
        return "<robot name=\"" + model.name + "\"/>";
      });
  ASSERT_TRUE(store) << store.error().message;
  EXPECT_EQ(store->CurrentId(), kNominalModelId);
  EXPECT_EQ(ReadFile(store->CurrentPath()).value(), ReadFile(nominal).value());
  EXPECT_FALSE(store->Rollback()) << "nothing to roll back to";
  RobotModel changed = store->Current()->model;
  changed.tool.z += 0.004;
  ASSERT_TRUE(store->Install("s1", changed, "{session: s1}"));
  EXPECT_EQ(store->CurrentId(), "s1");
  EXPECT_EQ(store->PreviousId(), kNominalModelId);
  EXPECT_DOUBLE_EQ(store->Current()->model.tool.z, changed.tool.z);
  EXPECT_TRUE(fs::exists(dir + "/models/s1/model.urdf"));
  EXPECT_EQ(urdf_calls, 2);
  // Reopening finds the installed model.
  auto reopened = ModelStore::Open(dir, nominal, {});
  ASSERT_TRUE(reopened);
  EXPECT_EQ(reopened->CurrentId(), "s1");
  ASSERT_TRUE(reopened->Rollback());
  EXPECT_EQ(reopened->CurrentId(), kNominalModelId);
  EXPECT_EQ(reopened->PreviousId(), "s1");
  EXPECT_EQ(ReadFile(reopened->CurrentPath()).value(), ReadFile(nominal).value());
  EXPECT_FALSE(reopened->Install("../evil", changed, ""));
  // A failing URDF export installs nothing.
  auto failing = ModelStore::Open(
      dir, nominal, [](const RobotModel&) -> Expected<std::string> { return Error{"no"}; });
  ASSERT_TRUE(failing);
  EXPECT_FALSE(failing->Install("s2", changed, ""));
  EXPECT_EQ(failing->CurrentId(), kNominalModelId);
  EXPECT_FALSE(fs::exists(dir + "/models/s2")) << "a failed install leaves its folder";
}

TEST(ModelStoreTest, DiscardUninstalledRemovesOnlyAFolderNoLinkPointsAt) {
  const std::string dir = TempDir("models-discard");
  const std::string nominal = SourceDir() + "/config/robots/kuka_lbr_iiwa_r840.yaml";
  auto store = ModelStore::Open(dir, nominal, {});
  ASSERT_TRUE(store) << store.error().message;
  RobotModel changed = store->Current()->model;
  changed.tool.z += 0.004;
  ASSERT_TRUE(store->Install("s1", changed, "{session: s1}"));
  // What a kill -9 during the next install leaves: the URDF and a temporary model.yaml.
  const std::string torn = dir + "/models/s2";
  fs::create_directories(torn);
  ASSERT_TRUE(WriteFileAtomically(torn + "/model.urdf", "<robot/>"));
  ASSERT_TRUE(WriteFileAtomically(torn + "/model.yaml.tmp.4242", "joints: ["));
  ASSERT_TRUE(store->DiscardUninstalled("s2"));
  EXPECT_FALSE(fs::exists(torn));
  // Current and previous stay, whatever the caller asks.
  ASSERT_TRUE(store->DiscardUninstalled("s1"));
  ASSERT_TRUE(store->DiscardUninstalled(kNominalModelId));
  EXPECT_TRUE(fs::exists(store->ModelPath("s1")));
  EXPECT_TRUE(fs::exists(store->ModelPath(kNominalModelId)));
  EXPECT_TRUE(store->DiscardUninstalled("never-written"));
  EXPECT_FALSE(store->DiscardUninstalled("../evil"));
}

TEST(SessionStoreTest, MarksInterruptedSessionsAndEnforcesTheQuotaOldestFirst) {
  const std::string dir = TempDir("sessions");
  SessionStore store(dir);
  for (int i = 0; i < 4; ++i) {
    SessionMeta meta;
    meta.id = "2026010" + std::to_string(i);
    meta.status = i == 3 ? "recording" : "rejected";
    if (i == 1) meta.status = "accepted";
    ASSERT_TRUE(store.Create(meta));
    ASSERT_TRUE(WriteFileAtomically(store.RecordingPath(meta.id), std::string(1000, 'x')));
  }
  auto marked = store.MarkInterrupted(42);
  ASSERT_TRUE(marked);
  ASSERT_EQ(marked->size(), 1u);
  EXPECT_EQ(store.Read("20260103")->status, "incomplete");
  EXPECT_EQ(store.Read("20260101")->status, "accepted");
  // About 4 x 1.1 kB; a quota of 2.5 kB removes the two oldest that are not kept.
  auto removed = store.EnforceQuota(2500, {"20260101"});
  ASSERT_TRUE(removed);
  EXPECT_EQ(*removed, (std::vector<std::string>{"20260100", "20260102"}));
  EXPECT_TRUE(fs::exists(store.SessionFolder("20260101")));
  EXPECT_TRUE(fs::exists(store.SessionFolder("20260103")));
  // The history counts in the quota: with 1 kB of it, the next oldest goes too.
  auto more = store.EnforceQuota(2500, {"20260101"}, 1000);
  ASSERT_TRUE(more);
  EXPECT_EQ(*more, (std::vector<std::string>{"20260103"}));
}

TEST(HistoryTest, KeepsTheNewestRequestsAndRemembersTheForgottenNonces) {
  const std::string dir = TempDir("history_bound");
  auto history = History::Open(dir + "/h.sqlite", false, 5);
  ASSERT_TRUE(history) << history.error().message;
  EXPECT_EQ((*history)->ForgottenNoncesUpTo().value(), std::numeric_limits<std::int64_t>::min());
  for (int i = 1; i <= 12; ++i) {
    std::string nonce = "n";  // not "n" + to_string: GCC 12's false -Wrestrict (bug 105329)
    nonce += std::to_string(i);
    ASSERT_TRUE((*history)->LogRequest(i, 100 + i, nonce, 1, "t", "accepted",
                                       /*nonce_used=*/i != 7));
  }
  EXPECT_EQ((*history)->RequestRows().value(), 5);
  auto kept = (*history)->NoncesSince(0).value();
  ASSERT_EQ(kept.size(), 5u);
  EXPECT_EQ(kept.front().first, "n8");
  // Rows 1..7 went; the newest used nonce among them is row 6's (row 7's was not used).
  EXPECT_EQ((*history)->ForgottenNoncesUpTo().value(), 106);
  EXPECT_GT((*history)->FileBytes(), 0u);
}

TEST(HistoryTest, RecordsSessionsAndRequests) {
  const std::string dir = TempDir("history");
  auto history = History::Open(dir + "/h.sqlite", false);
  ASSERT_TRUE(history) << history.error().message;
  SessionRecord record;
  record.id = "s1";
  record.started_utime = 10;
  record.state = "recording";
  ASSERT_TRUE((*history)->UpsertSession(record));
  record.state = "accepted";
  record.rms_before = 0.01;
  record.rms_after = 0.005;
  record.change = "sensor mount moved 2.1 mm / 0.30 deg (bumped?)";
  ASSERT_TRUE((*history)->UpsertSession(record));
  record.change.clear();
  record.id = "s2";
  record.started_utime = 20;
  record.state = "failed";
  ASSERT_TRUE((*history)->UpsertSession(record));
  ASSERT_TRUE((*history)->LogRequest(100, 99, "n1", 1, "me", "accepted", true));
  ASSERT_TRUE((*history)->LogRequest(100, 50, "n2", 1, "me", "refused: stale", false));
  auto read_only = History::Open(dir + "/h.sqlite", true);
  ASSERT_TRUE(read_only);
  auto sessions = (*read_only)->Sessions(10);
  ASSERT_TRUE(sessions);
  ASSERT_EQ(sessions->size(), 2u);
  EXPECT_EQ((*sessions)[0].id, "s2");
  EXPECT_EQ((*sessions)[1].state, "accepted");
  EXPECT_DOUBLE_EQ((*sessions)[1].rms_after, 0.005);
  EXPECT_EQ((*sessions)[1].change, "sensor mount moved 2.1 mm / 0.30 deg (bumped?)");
  EXPECT_EQ((*sessions)[0].change, "");
  auto nonces = (*history)->NoncesSince(0);
  ASSERT_TRUE(nonces);
  ASSERT_EQ(nonces->size(), 1u);
  EXPECT_EQ((*nonces)[0].first, "n1");
}

// A history an older daemon wrote (no `change` column): read as it is, then extended on the
// first writable open, its rows kept.
TEST(HistoryTest, AnOlderHistoryGainsTheChangeColumn) {
  const std::string dir = TempDir("history_old");
  const std::string path = dir + "/h.sqlite";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  const int created = sqlite3_exec(
      db,
      "CREATE TABLE sessions (id TEXT PRIMARY KEY, started_utime INTEGER, ended_utime INTEGER,"
      " plan TEXT, requested_by TEXT, nonce TEXT, state TEXT, reason TEXT, rms_before REAL,"
      " rms_after REAL, iterations INTEGER, runtime REAL, model_id TEXT);"
      " INSERT INTO sessions (id, started_utime, state) VALUES ('old', 5, 'accepted');",
      nullptr, nullptr, nullptr);
  sqlite3_close(db);
  ASSERT_EQ(created, SQLITE_OK);
  auto read_only = History::Open(path, true);
  ASSERT_TRUE(read_only) << read_only.error().message;
  auto before = (*read_only)->Sessions(10);
  ASSERT_TRUE(before) << before.error().message;
  ASSERT_EQ(before->size(), 1u);
  EXPECT_EQ((*before)[0].change, "");
  auto writable = History::Open(path, false);
  ASSERT_TRUE(writable) << writable.error().message;
  SessionRecord record;
  record.id = "new";
  record.started_utime = 6;
  record.state = "rejected";
  record.change = "no significant change";
  ASSERT_TRUE((*writable)->UpsertSession(record));
  auto after = (*writable)->Sessions(10);
  ASSERT_TRUE(after);
  ASSERT_EQ(after->size(), 2u);
  EXPECT_EQ((*after)[0].change, "no significant change");
  EXPECT_EQ((*after)[1].id, "old");
}

}  // namespace
}  // namespace selfcal::daemon
