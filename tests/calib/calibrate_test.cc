// End-to-end on synthetic in-memory data: a depth camera in a room, a perturbed robot.
#include "core/calib/calibrate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <tuple>

#include "core/calib/covariance.h"
#include "tests/calib/synthetic.h"

namespace selfcal::calib {
namespace {

using testing::SyntheticCamera;

struct Recording {
  RobotModel nominal, truth;
  std::vector<Dataset> datasets;
};

Recording MakeRecording(std::size_t fit, std::size_t validation, double noise_m,
                        const SyntheticCamera& camera = SyntheticCamera{}) {
  Recording recording;
  recording.nominal = testing::LoadIiwa();
  recording.truth = testing::PerturbedModel(recording.nominal, 3);
  const testing::Scene scene = testing::RoomScene();
  const auto configurations = testing::WorkspaceConfigurations(fit + validation, 11);
  for (std::size_t i = 0; i < configurations.size(); ++i) {
    Dataset dataset =
        testing::DepthScan(scene, recording.truth, configurations[i], camera, static_cast<int>(i),
                           noise_m, static_cast<unsigned>(i + 1));
    dataset.validation = i >= fit;
    recording.datasets.push_back(std::move(dataset));
  }
  return recording;
}

CalibrationOptions KinectLikeOptions(SolverKind solver) {
  CalibrationOptions options;  // Table I, Kinect: n = m = 2, g_min 0.75, d_max 20 mm, f_min 0.8
  options.solver = solver;
  options.threads = 2;
  return options;
}

TEST(Calibrate, RecoversTheSensorPoseFromNoiselessDepthImages) {
  const Recording recording = MakeRecording(16, 4, 0.0);
  const PoseErrorStats nominal =
      SensorPoseError(recording.truth, recording.nominal, testing::EvaluationConfigurations());
  const CalibrationResult result =
      Calibrate(recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast));
  ASSERT_TRUE(result.usable) << result.message;
  const PoseErrorStats calibrated =
      SensorPoseError(recording.truth, result.model, testing::EvaluationConfigurations());
  std::printf("nominal %.3f mm %.4f deg -> calibrated %.4f mm %.5f deg, %zu iterations, %s\n",
              nominal.rms_position_m * 1e3, nominal.rms_orientation_rad * 180 / M_PI,
              calibrated.rms_position_m * 1e3, calibrated.rms_orientation_rad * 180 / M_PI,
              result.iterations.size(), result.message.c_str());
  EXPECT_LT(calibrated.rms_position_m, 0.5e-3);
  EXPECT_LT(calibrated.rms_orientation_rad, 0.03 * M_PI / 180);
  EXPECT_LT(calibrated.rms_position_m, nominal.rms_position_m / 10);
  EXPECT_TRUE(result.validation.available);
  EXPECT_LT(result.validation.rms_after_m, result.validation.rms_before_m);
  EXPECT_EQ(result.parameters.size(), 28u);
  // A room with spheres and boxes observes every calibrated parameter.
  EXPECT_TRUE(result.unobservable.empty()) << result.unobservable.front();
  EXPECT_GT(result.predicted.sensor.rms_position_m, 0);
}

// Coarse to fine (deviation 24): the loop starts at a query stride of 4, so its first iteration
// matches about 1/16 of the points, and ends at every point, converged there as the plain loop.
TEST(Calibrate, CoarseToFineEndsConvergedAtEveryPoint) {
  const Recording recording = MakeRecording(12, 3, 0.0005);
  CalibrationOptions options = KinectLikeOptions(SolverKind::kFast);
  const CalibrationResult plain = Calibrate(recording.datasets, recording.nominal, options);
  options.coarse_stride = 4;
  const CalibrationResult coarse = Calibrate(recording.datasets, recording.nominal, options);
  ASSERT_TRUE(plain.converged) << plain.message;
  ASSERT_TRUE(coarse.converged) << coarse.message;
  const auto matches = [](const CalibrationResult& result, std::size_t i) {
    return static_cast<double>(result.iterations[i].valid_matches);
  };
  const double plain_error =
      SensorPoseError(recording.truth, plain.model, testing::EvaluationConfigurations())
          .rms_position_m;
  const double coarse_error =
      SensorPoseError(recording.truth, coarse.model, testing::EvaluationConfigurations())
          .rms_position_m;
  std::printf(
      "plain: %zu iterations, %.0f -> %.0f matches, %.4f mm; coarse to fine: %zu iterations, "
      "%.0f -> %.0f matches, %.4f mm\n",
      plain.iterations.size(), matches(plain, 0), matches(plain, plain.iterations.size() - 1),
      plain_error * 1e3, coarse.iterations.size(), matches(coarse, 0),
      matches(coarse, coarse.iterations.size() - 1), coarse_error * 1e3);
  EXPECT_LT(matches(coarse, 0), matches(plain, 0) / 8);
  EXPECT_NEAR(matches(coarse, coarse.iterations.size() - 1),
              matches(plain, plain.iterations.size() - 1),
              0.01 * matches(plain, plain.iterations.size() - 1));
  EXPECT_LT(coarse_error, 1.5 * plain_error + 0.05e-3);
  // The levels' stride is not left behind: the validation after matches every point.
  EXPECT_NEAR(static_cast<double>(coarse.validation.matches_after),
              static_cast<double>(plain.validation.matches_after),
              0.01 * static_cast<double>(plain.validation.matches_after));
}

// Only the floor: a point-to-plane residual on one plane cannot see a scan slide along it or
// turn about its normal (A1->A2.x moves the whole arm sideways in the J1 frame, which turns about
// the floor's normal). The range noise makes the normals rough, which gives the normal equations
// spurious information, but the scans disagree along those directions: the engine must name them,
// and predict an error no site would accept.
TEST(Calibrate, ASinglePlaneNamesWhatItCannotObserve) {
  RobotModel nominal = testing::LoadIiwa();
  const RobotModel truth = testing::PerturbedModel(nominal, 3);
  testing::Scene floor;
  floor.planes = {{{0, 0, 1}, -0.4}};
  const auto configurations = testing::WorkspaceConfigurations(8, 11);
  std::vector<Dataset> datasets;
  for (std::size_t i = 0; i < configurations.size(); ++i) {
    datasets.push_back(testing::DepthScan(floor, truth, configurations[i], SyntheticCamera{},
                                          static_cast<int>(i), 0.001,
                                          static_cast<unsigned>(i + 1)));
  }
  CalibrationOptions options = KinectLikeOptions(SolverKind::kFast);
  options.i_max = 3;
  const CalibrationResult result = Calibrate(datasets, nominal, options);
  ASSERT_FALSE(result.iterations.empty()) << result.message;
  for (const auto& entry : result.unobservable) std::printf("unobservable: %s\n", entry.c_str());
  std::printf("predicted sensor position error %.1f mm RMS\n",
              result.predicted.sensor.rms_position_m * 1e3);
  ASSERT_FALSE(result.unobservable.empty());
  for (const auto& entry : result.unobservable) {
    EXPECT_NE(entry.find(": not observable from these scans"), std::string::npos) << entry;
  }
  EXPECT_GT(result.predicted.sensor.rms_position_m, kUnobservableMotion);
}

TEST(Calibrate, FastAndReferenceModesAgree) {
  // Small: the reference mode differentiates the full chain per match with 36-wide jets. One ICP
  // iteration compares the modes on identical matches; the fast mode's own convergence is
  // covered above. (The small simulated scenario is compared in small_scenario_test.cc.)
  SyntheticCamera camera;
  camera.width = 40;
  camera.height = 32;
  camera.intrinsics.fx = 26;
  camera.intrinsics.fy = 28;
  camera.intrinsics.cx = 19.5;
  camera.intrinsics.cy = 15.5;
  const Recording recording = MakeRecording(7, 1, 0.0, camera);
  CalibrationOptions fast_options = KinectLikeOptions(SolverKind::kFast);
  fast_options.i_max = 1;
  fast_options.lm_max_iterations = 8;
  CalibrationOptions reference_options = fast_options;
  reference_options.search = SearchStrategy::kReference;
  reference_options.solver = SolverKind::kReference;
  const CalibrationResult fast = Calibrate(recording.datasets, recording.nominal, fast_options);
  const CalibrationResult reference =
      Calibrate(recording.datasets, recording.nominal, reference_options);
  ASSERT_EQ(fast.iterations.size(), 1u) << fast.message;
  ASSERT_EQ(reference.iterations.size(), 1u) << reference.message;
  const PoseErrorStats fast_error =
      SensorPoseError(recording.truth, fast.model, testing::EvaluationConfigurations());
  const PoseErrorStats reference_error =
      SensorPoseError(recording.truth, reference.model, testing::EvaluationConfigurations());
  const PoseErrorStats difference =
      SensorPoseError(reference.model, fast.model, testing::EvaluationConfigurations());
  std::printf(
      "fast %.4f mm %.5f deg (%zu it, %.2f s), reference %.4f mm %.5f deg (%zu it, %.2f s), "
      "difference %.5f mm %.6f deg\n",
      fast_error.rms_position_m * 1e3, fast_error.rms_orientation_rad * 180 / M_PI,
      fast.iterations.size(), fast.runtime_s, reference_error.rms_position_m * 1e3,
      reference_error.rms_orientation_rad * 180 / M_PI, reference.iterations.size(),
      reference.runtime_s, difference.rms_position_m * 1e3,
      difference.rms_orientation_rad * 180 / M_PI);
  // Same matches, same cost, same minimum: the two modes differ by far less than their error.
  EXPECT_LT(difference.rms_position_m, 0.05e-3);
  EXPECT_LT(difference.rms_orientation_rad, 0.002 * M_PI / 180);
  EXPECT_EQ(fast.iterations.front().valid_matches, reference.iterations.front().valid_matches);
  EXPECT_NEAR(fast.iterations.front().rms_after_m, reference.iterations.front().rms_after_m, 1e-7);
  // Seven 40 x 32 images do not observe all 28 parameters: this test compares the modes, not the
  // accuracy (RecoversTheSensorPoseFromNoiselessDepthImages does).
}

TEST(Calibrate, EverySearchStrategyRunsWithEverySolver) {
  // The two choices are independent: both searches find the same matches, and on the same
  // matches both solvers take the same step.
  SyntheticCamera camera;
  camera.width = 40;
  camera.height = 32;
  camera.intrinsics.fx = 26;
  camera.intrinsics.fy = 28;
  camera.intrinsics.cx = 19.5;
  camera.intrinsics.cy = 15.5;
  const Recording recording = MakeRecording(5, 0, 0.0, camera);
  std::vector<CalibrationResult> results;
  for (SearchStrategy search : {SearchStrategy::kFast, SearchStrategy::kReference}) {
    for (SolverKind solver : {SolverKind::kFast, SolverKind::kReference}) {
      CalibrationOptions options = KinectLikeOptions(solver);
      options.search = search;
      options.i_max = 1;
      options.lm_max_iterations = 2;
      results.push_back(Calibrate(recording.datasets, recording.nominal, options));
      const CalibrationResult& result = results.back();
      ASSERT_EQ(result.iterations.size(), 1u)
          << SearchName(search) << "/" << SolverName(solver) << ": " << result.message;
      EXPECT_EQ(result.search, search);
      EXPECT_EQ(result.solver, solver);
    }
  }
  for (const CalibrationResult& result : results) {
    EXPECT_EQ(result.iterations[0].valid_matches, results[0].iterations[0].valid_matches);
    EXPECT_NEAR(result.iterations[0].rms_after_m, results[0].iterations[0].rms_after_m, 1e-7);
  }
  EXPECT_GT(results[0].iterations[0].delta, 1e-3);  // a real step
}

TEST(Calibrate, OptionsOutOfRangeAreInvalidInputThatNamesThem) {
  const Recording recording = MakeRecording(2, 0, 0.0);
  CalibrationOptions options = KinectLikeOptions(SolverKind::kFast);
  options.d_max = 0;
  const CalibrationResult result = Calibrate(recording.datasets, recording.nominal, options);
  EXPECT_EQ(result.termination, Termination::kInvalidInput);
  EXPECT_EQ(result.message, "options: d_max = 0 m, must be positive and finite");
  EXPECT_FALSE(result.usable);
  EXPECT_TRUE(result.iterations.empty());
}

TEST(Calibrate, ResultsAreIdenticalForAnyThreadCount) {
  const Recording recording = MakeRecording(6, 1, 0.002);
  CalibrationOptions options = KinectLikeOptions(SolverKind::kFast);
  options.threads = 1;
  const CalibrationResult one = Calibrate(recording.datasets, recording.nominal, options);
  options.threads = 3;
  const CalibrationResult three = Calibrate(recording.datasets, recording.nominal, options);
  ASSERT_EQ(one.iterations.size(), three.iterations.size());
  EXPECT_EQ(ToParameterVector(one.model), ToParameterVector(three.model));  // bit for bit
  for (std::size_t i = 0; i < one.iterations.size(); ++i) {
    EXPECT_EQ(one.iterations[i].valid_matches, three.iterations[i].valid_matches);
  }
}

TEST(Calibrate, CancelledIsAResultNotACrash) {
  const Recording recording = MakeRecording(3, 0, 0.0);
  std::atomic<bool> cancel{true};
  int calls = 0;
  const CalibrationResult result = Calibrate(
      recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast),
      [&](const CalibrationProgress&) { ++calls; }, &cancel);
  EXPECT_EQ(result.termination, Termination::kCancelled);
  EXPECT_FALSE(result.usable);
  EXPECT_EQ(ToParameterVector(result.model), ToParameterVector(recording.nominal));
}

TEST(Calibrate, CancelDuringTheSolveStopsThatIteration) {
  const Recording recording = MakeRecording(3, 0, 0.0);
  std::atomic<bool> cancel{false};
  int solving_reports = 0;
  const CalibrationResult result = Calibrate(
      recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast),
      [&](const CalibrationProgress& p) {
        if (p.stage == CalibrationStage::kSolving) {
          ++solving_reports;
          cancel = true;  // as an abort arriving while the solver runs
        }
      },
      &cancel);
  EXPECT_EQ(solving_reports, 1);
  EXPECT_EQ(result.termination, Termination::kCancelled);
  EXPECT_FALSE(result.usable);
  EXPECT_NE(result.message.find("during iteration 1"), std::string::npos) << result.message;
}

TEST(Calibrate, ReportsProgress) {
  const Recording recording = MakeRecording(3, 1, 0.0);
  std::vector<CalibrationStage> stages;
  const CalibrationResult result =
      Calibrate(recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast),
                [&](const CalibrationProgress& p) { stages.push_back(p.stage); });
  EXPECT_NE(std::find(stages.begin(), stages.end(), CalibrationStage::kValidation), stages.end());
  EXPECT_NE(std::find(stages.begin(), stages.end(), CalibrationStage::kSolving), stages.end());
}

TEST(Calibrate, BadDatasetsNameTheScan) {
  Recording recording = MakeRecording(3, 0, 0.0);
  recording.datasets[1].pose_joints[2] = std::numeric_limits<double>::quiet_NaN();
  CalibrationResult result =
      Calibrate(recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast));
  EXPECT_EQ(result.termination, Termination::kInvalidInput);
  EXPECT_NE(result.message.find("scan 1"), std::string::npos) << result.message;

  recording = MakeRecording(3, 0, 0.0);
  recording.datasets[2].joint_count = 6;
  result = Calibrate(recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast));
  EXPECT_EQ(result.termination, Termination::kInvalidInput);
  EXPECT_NE(result.message.find("scan 2: 6 joints"), std::string::npos) << result.message;

  recording = MakeRecording(3, 0, 0.0);
  std::fill(recording.datasets[0].z.begin(), recording.datasets[0].z.end(),
            std::numeric_limits<float>::quiet_NaN());
  result = Calibrate(recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast));
  EXPECT_EQ(result.termination, Termination::kInvalidInput);
  EXPECT_NE(result.message.find("scan 0: no valid points"), std::string::npos) << result.message;
}

TEST(Calibrate, ScansWithoutOverlapAreNamed) {
  Recording recording = MakeRecording(3, 0, 0.0);
  // Move scan 2's points far away: it overlaps nothing.
  for (float& z : recording.datasets[2].z) z += 100.0f;
  const CalibrationResult result =
      Calibrate(recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast));
  if (result.termination == Termination::kTooFewMatches) {
    EXPECT_NE(result.message.find("scans without any overlap: 2"), std::string::npos)
        << result.message;
  }
  // Two scans that see nothing in common at all.
  recording.datasets.pop_back();
  for (float& z : recording.datasets[1].z) z += 100.0f;
  const CalibrationResult none =
      Calibrate(recording.datasets, recording.nominal, KinectLikeOptions(SolverKind::kFast));
  EXPECT_EQ(none.termination, Termination::kTooFewMatches);
  EXPECT_FALSE(none.usable);
  EXPECT_NE(none.message.find("scans without any overlap: 0 1"), std::string::npos) << none.message;
}

// LiDAR sweeps (a pose per point): the fast mode's knots against the reference's full chain.
std::vector<Dataset> LidarSweeps(const RobotModel& truth, std::size_t count, std::size_t rays,
                                 double seconds) {
  const testing::Scene scene = testing::RoomScene();
  testing::LidarSweepOptions options;
  options.rays = rays;
  options.seconds = seconds;
  const auto configurations = testing::WorkspaceConfigurations(count, 23);
  std::vector<Dataset> sweeps;
  for (std::size_t i = 0; i < count; ++i) {
    std::vector<double> to = configurations[i];
    to[6] += (i % 2 == 0 ? 1.2 : -1.2) * seconds;  // A7 at 1.2 rad/s, as the demo's sweeps
    to[5] += 0.2 * seconds;
    sweeps.push_back(testing::LidarSweep(scene, truth, configurations[i], to, static_cast<int>(i),
                                         options, static_cast<unsigned>(i + 1)));
  }
  return sweeps;
}

// The fast mode blends the poses between knots (pose_knots.h), which moves a point by < 1 um: the
// one approximation of the fast path, so the step differs a little at the default knots and not
// at all (1e-6 of the step) with a knot at every pose.
TEST(Calibrate, LidarFastAndReferenceModesTakeTheSameStep) {
  const RobotModel nominal = testing::LoadIiwa();
  const RobotModel truth = testing::PerturbedModel(nominal, 6);
  const std::vector<Dataset> sweeps = LidarSweeps(truth, 4, 541, 1.0);
  CalibrationOptions fast_options = testing::HokuyoOptions(SolverKind::kFast);
  fast_options.i_max = 1;
  fast_options.lm_max_iterations = 1;
  CalibrationOptions reference_options = fast_options;
  reference_options.search = SearchStrategy::kReference;
  reference_options.solver = SolverKind::kReference;
  CalibrationOptions every_pose_options = fast_options;
  every_pose_options.knot_max_joint_step = 1e-7;  // rad; consecutive points differ by ~3e-5
  const CalibrationResult reference = Calibrate(sweeps, nominal, reference_options);
  ASSERT_EQ(reference.iterations.size(), 1u) << reference.message;
  const double moved =
      SensorPoseError(nominal, reference.model, testing::EvaluationConfigurations()).rms_position_m;
  EXPECT_GT(moved, 1e-3);
  ASSERT_GT(reference.iterations[0].valid_matches, 1000u);
  for (const auto& [name, options, relative] :
       {std::tuple{"default knots", fast_options, 1e-3},
        std::tuple{"a knot at every pose", every_pose_options, 1e-6}}) {
    const CalibrationResult fast = Calibrate(sweeps, nominal, options);
    ASSERT_EQ(fast.iterations.size(), 1u) << fast.message;
    const PoseErrorStats difference =
        SensorPoseError(reference.model, fast.model, testing::EvaluationConfigurations());
    std::printf(
        "%s: %zu vs %zu matches; one step moves the sensor %.4f mm, the modes differ by %.3g of "
        "it (%.3g deg)\n",
        name, fast.iterations[0].valid_matches, reference.iterations[0].valid_matches, moved * 1e3,
        difference.rms_position_m / moved, difference.rms_orientation_rad * 180 / M_PI);
    // Projection through knots moves points by < 1 um, so a match or two may differ.
    EXPECT_NEAR(static_cast<double>(fast.iterations[0].valid_matches),
                static_cast<double>(reference.iterations[0].valid_matches),
                relative * static_cast<double>(reference.iterations[0].valid_matches))
        << name;
    EXPECT_LT(difference.rms_position_m, relative * moved) << name;
  }
}

TEST(Calibrate, RecoversTheSensorPoseFromLidarSweeps) {
  const RobotModel nominal = testing::LoadIiwa();
  const RobotModel truth = testing::PerturbedModel(nominal, 6);
  const std::vector<Dataset> sweeps = LidarSweeps(truth, 12, 541, 1.0);
  const PoseErrorStats nominal_error =
      SensorPoseError(truth, nominal, testing::EvaluationConfigurations());
  const CalibrationResult result =
      Calibrate(sweeps, nominal, testing::HokuyoOptions(SolverKind::kFast));
  const PoseErrorStats calibrated =
      SensorPoseError(truth, result.model, testing::EvaluationConfigurations());
  std::printf(
      "nominal %.3f mm %.4f deg -> calibrated %.4f mm %.5f deg, %zu iterations, %.1f s, %s\n",
      nominal_error.rms_position_m * 1e3, nominal_error.rms_orientation_rad * 180 / M_PI,
      calibrated.rms_position_m * 1e3, calibrated.rms_orientation_rad * 180 / M_PI,
      result.iterations.size(), result.runtime_s, result.message.c_str());
  ASSERT_TRUE(result.usable) << result.message;
  // Twelve short sweeps of half the Hokuyo's rays are sparse (0.5 deg between rays, 1.7 deg
  // between lines): this checks the LiDAR path end to end; hokuyo-office measures its accuracy
  // (docs/accuracy.md).
  EXPECT_LT(calibrated.rms_position_m, nominal_error.rms_position_m / 10);
  EXPECT_LT(calibrated.rms_position_m, 2e-3);
}

// Scans the caller gives up (Calibrate(std::vector<Dataset>&&)) have their points corrected in
// place instead of in a copy: with the range offset free, the same result as from scans passed
// by reference, bit for bit.
TEST(Calibrate, ScansGivenUpCalibrateAsScansPassedByReference) {
  const RobotModel nominal = testing::LoadIiwa();
  const RobotModel truth = testing::PerturbedModel(nominal, 6);
  const std::vector<Dataset> sweeps = LidarSweeps(truth, 4, 541, 1.0);
  CalibrationOptions options = testing::HokuyoOptions(SolverKind::kFast);
  ASSERT_EQ(options.ChooseIntrinsics("offset"), "");
  options.i_max = 3;
  const CalibrationResult by_reference = Calibrate(sweeps, nominal, options);
  std::vector<Dataset> copy = sweeps;
  const CalibrationResult given_up = Calibrate(std::move(copy), nominal, options);
  ASSERT_EQ(by_reference.iterations.size(), 3u) << by_reference.message;
  ASSERT_EQ(given_up.iterations.size(), 3u) << given_up.message;
  EXPECT_EQ(ToParameterVector(given_up.model), ToParameterVector(by_reference.model));
  ASSERT_EQ(given_up.parameters.size(), by_reference.parameters.size());
  bool offset_moved = false;
  for (std::size_t p = 0; p < given_up.parameters.size(); ++p) {
    const ParameterReport& a = given_up.parameters[p];
    EXPECT_EQ(a.calibrated, by_reference.parameters[p].calibrated) << a.name;
    if (a.name == "sensor.range_offset") offset_moved = a.calibrated != 0;
  }
  EXPECT_TRUE(offset_moved);  // the points were corrected, not left as measured
}

}  // namespace
}  // namespace selfcal::calib
