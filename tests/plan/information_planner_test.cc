// Planning by information (core/plan/information_planner.h) on the small scenario
// (config/scenarios/small.yaml): a scene that cannot observe a parameter makes the planner name
// and mask it, and the planned scans predict an error no worse than as many of the paper-style
// plan's scans.
#include "core/plan/information_planner.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/sim/mesh.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/recording/recording.h"
#include "protocols/scenario/scenario_file.h"
#include "protocols/scenario/simulation_setup.h"

namespace selfcal::plan {
namespace {

struct Small {
  SimulationSetup setup;
  calib::CalibrationOptions engine;
};

Small LoadSmall() {
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  const std::string root = source != nullptr ? source : ".";
  auto scenario = ReadScenarioFile(root + "/config/scenarios/small.yaml");
  if (!scenario) ADD_FAILURE() << scenario.error().message;
  auto setup = PrepareSimulation(std::move(scenario).value());
  if (!setup) ADD_FAILURE() << setup.error().message;
  auto sensor = ReadSensorConfig(setup->scenario.sensor_path);
  if (!sensor) ADD_FAILURE() << sensor.error().message;
  calib::CalibrationOptions engine = recording::CalibrationOptionsFromSensor(*sensor);
  engine.threads = 2;
  return {std::move(setup).value(), engine};
}

// Only the floor (z = 0, 6 m x 6 m): a point-to-plane cost on one plane cannot see a scan slide
// along it or turn about its normal. The planner must name what that leaves undetermined, mask
// it, and still plan the rest.
TEST(InformationPlanner, ASinglePlaneNamesWhatItCannotObserve) {
  Small small = LoadSmall();
  sim::Scene floor;
  floor.name = "floor";
  floor.mesh = sim::MakeQuad({-3, -3, 0}, {6, 0, 0}, {0, 6, 0}, 12);
  PlannerOptions options;
  options.max_scans = 8;
  options.threads = 2;
  auto candidates = MakeCandidates(small.setup.nominal, small.setup.sensor, floor,
                                   small.setup.scenario.plan, small.engine, options);
  ASSERT_TRUE(candidates) << candidates.error().message;
  for (const auto& finding : candidates->unobservable)
    std::printf("unobservable: %s\n", finding.c_str());
  for (const auto& name : candidates->masked) std::printf("masked: %s\n", name.c_str());
  ASSERT_FALSE(candidates->unobservable.empty());
  for (const auto& finding : candidates->unobservable)
    EXPECT_NE(finding.find(": not observable from these scans"), std::string::npos) << finding;
  ASSERT_FALSE(candidates->masked.empty());
  // Sliding the whole arm along the floor: the first segment's x moves the arm sideways.
  EXPECT_NE(std::find(candidates->masked.begin(), candidates->masked.end(), "A1->A2.x"),
            candidates->masked.end());
  EXPECT_LT(candidates->selection_free.size(), candidates->information.free.size());
  const InformationPlan planned = ChooseScans(*candidates, options);
  EXPECT_EQ(planned.chosen.size(), 8u);
}

// The room corner observes every parameter; the planner's 7 scans predict an error no worse
// than the paper-style plan's first 7 (the same generator's views 0..6, the same prediction).
TEST(InformationPlanner, BeatsAsManyPaperScansOnTheSmallScenario) {
  Small small = LoadSmall();
  PlannerOptions options;
  options.max_scans = 7;
  options.threads = 2;
  auto candidates = MakeCandidates(small.setup.nominal, small.setup.sensor, small.setup.scene,
                                   small.setup.scenario.plan, small.engine, options);
  ASSERT_TRUE(candidates) << candidates.error().message;
  for (const auto& finding : candidates->unobservable)
    std::printf("unobservable: %s\n", finding.c_str());
  EXPECT_TRUE(candidates->unobservable.empty());
  EXPECT_EQ(candidates->selection_free.size(), candidates->information.free.size());
  const InformationPlan planned = ChooseScans(*candidates, options);
  ASSERT_EQ(planned.chosen.size(), 7u);
  const calib::PredictedError paper = PredictForViews(*candidates, {0, 1, 2, 3, 4, 5, 6}, options);
  std::printf("predicted sensor position RMS: planned %.4f mm, paper plan %.4f mm (7 scans)\n",
              planned.predicted.sensor.rms_position_m * 1e3, paper.sensor.rms_position_m * 1e3);
  EXPECT_LE(planned.predicted.sensor.rms_position_m, paper.sensor.rms_position_m);
  // The selection's own score is the prediction's RMS (trace(C G) = PredictPoseError's).
  EXPECT_NEAR(planned.predicted_rms_m.back(), planned.predicted.sensor.rms_position_m,
              1e-9 + 1e-6 * planned.predicted.sensor.rms_position_m);
  // Each added scan lowers the prediction.
  for (std::size_t s = 1; s < planned.predicted_rms_m.size(); ++s)
    EXPECT_LT(planned.predicted_rms_m[s], planned.predicted_rms_m[s - 1]);
  // The plan: the chosen views, then the generator's validation scans unchanged.
  ASSERT_EQ(planned.plan.scans.size(), 7u + candidates->validation.size());
  for (std::size_t s = 0; s < 7; ++s)
    EXPECT_EQ(planned.plan.scans[s].start,
              candidates->views[static_cast<std::size_t>(planned.chosen[s])].start);
  EXPECT_EQ(planned.plan.scans.back().purpose, sim::ScanPurpose::kValidation);
}

// The arm stretched straight up (every joint at 0) reaches about 1.3 m: a box around its
// elbow's height collides with a link, the same box beside the arm does not; the base's mount
// (base origin to the first joint) on the table top never counts.
TEST(InformationPlanner, LinksAgainstTheSceneObstacles) {
  const Small small = LoadSmall();
  const std::vector<double> up(small.setup.nominal.JointCount(), 0.0);
  sim::Scene scene;
  scene.workspace = Eigen::AlignedBox3d(Eigen::Vector3d(-2, -2, 0), Eigen::Vector3d(2, 2, 2));
  scene.obstacles = {Eigen::AlignedBox3d(Eigen::Vector3d(-2, -2, -1), Eigen::Vector3d(2, 2, 0))};
  EXPECT_TRUE(sim::LinksAreFree(small.setup.nominal, scene, up, 0.07));
  scene.obstacles.emplace_back(Eigen::Vector3d(-0.1, -0.1, 0.6), Eigen::Vector3d(0.1, 0.1, 0.7));
  EXPECT_FALSE(sim::LinksAreFree(small.setup.nominal, scene, up, 0.07));
  scene.obstacles.back() =
      Eigen::AlignedBox3d(Eigen::Vector3d(0.3, -0.1, 0.6), Eigen::Vector3d(0.5, 0.1, 0.7));
  EXPECT_TRUE(sim::LinksAreFree(small.setup.nominal, scene, up, 0.07));
  // A ceiling below the stretched arm's reach.
  scene.workspace = Eigen::AlignedBox3d(Eigen::Vector3d(-2, -2, 0), Eigen::Vector3d(2, 2, 0.9));
  EXPECT_FALSE(sim::LinksAreFree(small.setup.nominal, scene, up, 0.07));
}

TEST(InformationPlanner, RejectsBadOptionsAndSweeps) {
  Small small = LoadSmall();
  PlannerOptions options;
  options.max_scans = 1;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("max_scans = 1"), std::string::npos) << error;
  options.max_scans = 7;
  sim::PlanOptions sweeps = small.setup.scenario.plan;
  sweeps.kind = sim::PlanOptions::Kind::kLineSweeps;
  auto refused = MakeCandidates(small.setup.nominal, small.setup.sensor, small.setup.scene, sweeps,
                                small.engine, options);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("only stationary views"), std::string::npos);
}

}  // namespace
}  // namespace selfcal::plan
