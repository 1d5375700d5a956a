// Planning by information (core/plan/information_planner.h) on the small scenario
// (config/scenarios/small.yaml): a scene that cannot observe a parameter makes the planner name
// and mask it, and the planned scans predict an error no worse than as many of the paper-style
// plan's scans.
#include "core/plan/information_planner.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/model/kinematics.h"
#include "core/sim/mesh.h"
#include "core/sim/site_map.h"
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

// A scenario of config/scenarios, its files read as `selfcal plan` reads them.
Small LoadScenario(const std::string& name) {
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  const std::string root = source != nullptr ? source : ".";
  auto scenario = ReadScenarioFile(root + "/config/scenarios/" + name);
  if (!scenario) ADD_FAILURE() << scenario.error().message;
  auto setup = PrepareSimulation(std::move(scenario).value());
  if (!setup) ADD_FAILURE() << setup.error().message;
  auto sensor = ReadSensorConfig(setup->scenario.sensor_path);
  if (!sensor) ADD_FAILURE() << sensor.error().message;
  calib::CalibrationOptions engine = recording::CalibrationOptionsFromSensor(*sensor);
  engine.threads = 2;
  return {std::move(setup).value(), engine};
}

Small LoadSmall() { return LoadScenario("small.yaml"); }

// The planner's options for 7 scans on 2 threads, and its candidates on `scene`.
PlannerOptions SevenScans() {
  PlannerOptions options;
  options.max_scans = 7;
  options.threads = 2;
  return options;
}

Expected<CandidateSet> CandidatesOn(const Small& small, const sim::Scene& scene,
                                    const PlannerOptions& options) {
  return MakeCandidates(small.setup.nominal, small.setup.sensor, scene, small.setup.scenario.plan,
                        small.engine, options);
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
  EXPECT_LT(candidates->selection_free.size(), candidates->information.EstimatedCount());
  const InformationPlan planned = ChooseScans(*candidates, options);
  EXPECT_EQ(planned.chosen.size(), 8u);
}

// The planner's 7 scans of the room corner, and what the 7 of the paper-style plan predict (the
// same generator's views 0..6, the same prediction).
struct SevenPlanned {
  std::optional<CandidateSet> candidates;
  InformationPlan planned;
  calib::PredictedError paper;
};

SevenPlanned PlanSeven(const Small& small) {
  const PlannerOptions options = SevenScans();
  SevenPlanned out;
  auto candidates = CandidatesOn(small, small.setup.scene, options);
  if (!candidates) {
    ADD_FAILURE() << candidates.error().message;
    return out;
  }
  out.candidates = std::move(candidates).value();
  out.planned = ChooseScans(*out.candidates, options);
  out.paper = PredictForViews(*out.candidates, {0, 1, 2, 3, 4, 5, 6}, options);
  std::printf(
      "predicted sensor position RMS: planned %.4f mm (%.4f mm of it held), paper plan "
      "%.4f mm (7 scans)\n",
      out.planned.predicted.sensor.rms_position_m * 1e3,
      out.planned.predicted_held.sensor.rms_position_m * 1e3,
      out.paper.sensor.rms_position_m * 1e3);
  return out;
}

// With the intrinsics exact the prediction is the scans' alone: each added scan lowers it.
TEST(InformationPlanner, BeatsAsManyPaperScansOnTheSmallScenario) {
  Small small = LoadSmall();
  small.engine.intrinsic_scale_sd = small.engine.intrinsic_offset_sd_m =
      small.engine.intrinsic_focal_sd = 0;
  const SevenPlanned seven = PlanSeven(small);
  ASSERT_TRUE(seven.candidates);
  const CandidateSet* candidates = &*seven.candidates;
  const InformationPlan& planned = seven.planned;
  for (const auto& finding : candidates->unobservable)
    std::printf("unobservable: %s\n", finding.c_str());
  EXPECT_TRUE(candidates->unobservable.empty());
  EXPECT_EQ(candidates->information.held, 0u);
  EXPECT_EQ(candidates->selection_free.size(), candidates->information.free.size());
  ASSERT_EQ(planned.chosen.size(), 7u);
  EXPECT_LE(planned.predicted.sensor.rms_position_m, seven.paper.sensor.rms_position_m);
  EXPECT_EQ(planned.predicted_held.sensor.rms_position_m, 0.0);
  // The selection's own score is the prediction's RMS (trace(C G) = PredictPoseError's).
  EXPECT_NEAR(planned.predicted_rms_m.back(), planned.predicted.sensor.rms_position_m,
              1e-9 + 1e-6 * planned.predicted.sensor.rms_position_m);
  for (std::size_t s = 1; s < planned.predicted_rms_m.size(); ++s)
    EXPECT_LT(planned.predicted_rms_m[s], planned.predicted_rms_m[s - 1]);
  // The plan: the chosen views, then the generator's validation scans unchanged.
  ASSERT_EQ(planned.plan.scans.size(), 7u + candidates->validation.size());
  for (std::size_t s = 0; s < 7; ++s)
    EXPECT_EQ(planned.plan.scans[s].start,
              candidates->views[static_cast<std::size_t>(planned.chosen[s])].start);
  EXPECT_EQ(planned.plan.scans.back().purpose, sim::ScanPurpose::kValidation);
}

// With the sensor file's intrinsics uncertainty (held by a calibration that does not free them),
// the prediction adds what it moves the estimate by, as the calibration's own does; the selection
// still ranks by the scans' part, so the same scans are chosen.
TEST(InformationPlanner, CountsWhatTheCalibrationHolds) {
  const Small small = LoadSmall();
  ASSERT_GT(small.engine.intrinsic_scale_sd, 0.0);
  const SevenPlanned seven = PlanSeven(small);
  ASSERT_TRUE(seven.candidates);
  EXPECT_EQ(seven.candidates->information.held, 3u);  // a camera's scale, offset, focal length
  const InformationPlan& planned = seven.planned;
  ASSERT_EQ(planned.chosen.size(), 7u);
  const double held = planned.predicted_held.sensor.rms_position_m;
  EXPECT_GT(held, 0.0);
  EXPECT_LT(held, planned.predicted.sensor.rms_position_m);
  EXPECT_NEAR(planned.predicted_rms_m.back(), planned.predicted.sensor.rms_position_m,
              1e-9 + 1e-6 * planned.predicted.sensor.rms_position_m);
  // Held exactly (the test above), the same candidates predict less.
  Small exact = small;
  exact.engine.intrinsic_scale_sd = exact.engine.intrinsic_offset_sd_m =
      exact.engine.intrinsic_focal_sd = 0;
  const SevenPlanned without = PlanSeven(exact);
  ASSERT_TRUE(without.candidates);
  EXPECT_EQ(without.planned.chosen, planned.chosen);
  EXPECT_LT(without.paper.sensor.rms_position_m, seven.paper.sensor.rms_position_m);
  EXPECT_LT(without.planned.predicted.sensor.rms_position_m,
            planned.predicted.sensor.rms_position_m);
}

// The scene's surfaces as points, `per_m2` per square metre on every triangle: what a fused
// cloud of earlier scans holds where they saw the scene.
std::vector<Eigen::Vector3f> SampleSurfaces(const sim::TriangleMesh& mesh, double per_m2) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3f> points;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d ab = mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>() - a;
    const Eigen::Vector3d ac = mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>() - a;
    const double expected = 0.5 * ab.cross(ac).norm() * per_m2;
    const int count = static_cast<int>(expected + unit(random));
    for (int i = 0; i < count; ++i) {
      double s = unit(random), r = unit(random);
      if (s + r > 1) s = 1 - s, r = 1 - r;
      points.push_back((a + s * ab + r * ac).cast<float>());
    }
  }
  return points;
}

// Planning on a real site sees the scene only as the points of earlier scans. Its map (squares
// on the points, core/sim/site_map.h) must give the same candidate views, predict for a plan
// what the scene itself predicts, and so choose a plan as good on the scene as the scene's own.
TEST(InformationPlanner, AMapOfTheScenesPointsPlansAsTheSceneDoes) {
  Small small = LoadSmall();
  const PlannerOptions options = SevenScans();
  auto on_scene = CandidatesOn(small, small.setup.scene, options);
  ASSERT_TRUE(on_scene) << on_scene.error().message;
  sim::Scene mapped = small.setup.scene;
  const sim::SiteMap map =
      sim::BuildSiteMap(SampleSurfaces(small.setup.scene.mesh, 20000), sim::SiteMapOptions{});
  std::printf("map: %zu points, %zu squares, %zu occupied voxels\n", map.points, map.splats,
              map.occupied.size());
  sim::UseSiteMap(map, mapped);
  auto on_map = CandidatesOn(small, mapped, options);
  ASSERT_TRUE(on_map) << on_map.error().message;
  ASSERT_EQ(on_map->views.size(), on_scene->views.size());
  for (std::size_t v = 0; v < on_map->views.size(); ++v)
    ASSERT_EQ(on_map->views[v].start, on_scene->views[v].start) << "view " << v;
  EXPECT_EQ(on_map->sighted, on_scene->sighted);

  const InformationPlan planned_on_map = ChooseScans(*on_map, options);
  const InformationPlan planned_on_scene = ChooseScans(*on_scene, options);
  const double map_says = planned_on_map.predicted.sensor.rms_position_m;
  const double scene_says =
      PredictForViews(*on_scene, planned_on_map.chosen, options).sensor.rms_position_m;
  const double scene_plan = planned_on_scene.predicted.sensor.rms_position_m;
  std::printf(
      "predicted sensor position RMS: the map's plan %.4f mm on the map, %.4f mm on the scene; "
      "the scene's own plan %.4f mm\n",
      map_says * 1e3, scene_says * 1e3, scene_plan * 1e3);
  EXPECT_NEAR(map_says, scene_says, 0.1 * scene_says);
  EXPECT_LE(scene_says, 1.1 * scene_plan);
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

// The arm laid forward (A2 at 90 deg) sweeps a circle of about 0.8 m about A1: a box at
// 45 deg on that circle stands in the straight move from A1 = 0 to A1 = 90 deg, not in the moves
// through the arm raised at A1 = 45 deg. The nearest scan after the first is the one behind the
// box, so the order must take the detour; without a way round it says where it is stuck.
TEST(InformationPlanner, ScansAreOrderedForMovesThatKeepTheLinksClear) {
  const Small small = LoadSmall();
  const RobotModel& arm = small.setup.nominal;
  auto at = [&arm](double a1_deg, double a2_deg) {
    std::vector<double> q(arm.JointCount(), 0.0);
    q[0] = a1_deg * M_PI / 180;
    q[1] = a2_deg * M_PI / 180;
    return q;
  };
  sim::Scene scene;
  scene.workspace = Eigen::AlignedBox3d(Eigen::Vector3d(-3, -3, -1), Eigen::Vector3d(3, 3, 3));
  // The sensor of the laid arm at 45 deg: the box stands where its tip passes.
  const Eigen::Vector3d box_centre = ForwardKinematics(arm, at(45, 90)).translation();
  scene.obstacles.emplace_back(box_centre - Eigen::Vector3d::Constant(0.05),
                               box_centre + Eigen::Vector3d::Constant(0.05));
  EXPECT_FALSE(sim::MoveIsFree(arm, scene, at(0, 90), at(90, 90), 0.07));
  EXPECT_TRUE(sim::MoveIsFree(arm, scene, at(0, 90), at(45, -5), 0.07));
  EXPECT_TRUE(sim::MoveIsFree(arm, scene, at(45, -5), at(90, 90), 0.07));

  auto scan = [](std::vector<double> q, sim::ScanPurpose purpose) {
    sim::PlannedScan s;
    s.purpose = purpose;
    s.start = s.end = std::move(q);
    return s;
  };
  sim::ScanPlan plan;
  plan.scans = {scan(at(0, 90), sim::ScanPurpose::kFit), scan(at(90, 90), sim::ScanPurpose::kFit),
                scan(at(45, -5), sim::ScanPurpose::kFit),
                scan(at(135, 90), sim::ScanPurpose::kValidation)};
  auto ordered = sim::OrderForFreeMoves(arm, scene, plan, 0.07);
  ASSERT_TRUE(ordered) << ordered.error().message;
  ASSERT_EQ(ordered->scans.size(), 4u);
  EXPECT_EQ(ordered->scans[0].start, at(0, 90));
  EXPECT_EQ(ordered->scans[1].start, at(45, -5));  // the detour, though A1 = 90 is nearer
  EXPECT_EQ(ordered->scans[2].start, at(90, 90));
  EXPECT_EQ(ordered->scans[3].purpose, sim::ScanPurpose::kValidation);
  for (std::size_t k = 1; k < 4; ++k) {
    EXPECT_TRUE(
        sim::MoveIsFree(arm, scene, ordered->scans[k - 1].end, ordered->scans[k].start, 0.07))
        << k;
  }
  EXPECT_LE(sim::JointTravel(*ordered), 2 * M_PI);

  plan.scans.erase(plan.scans.begin() + 2);  // no detour left
  const auto stuck = sim::OrderForFreeMoves(arm, scene, plan, 0.07);
  ASSERT_FALSE(stuck);
  EXPECT_NE(stuck.error().message.find("no collision-free move from scan 1"), std::string::npos)
      << stuck.error().message;
}

// The paper-style generator with plan.link_radius (the installed cells set 0.07 m): every scan
// and every move between scans keeps the links clear; without it, on the same cell, some do not.
TEST(ScanPlanGenerator, WithALinkRadiusEveryScanAndMoveKeepsTheLinksClear) {
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  auto scenario = ReadScenarioFile(std::string(source != nullptr ? source : ".") +
                                   "/config/daemon/cells/iiwa_kinect.yaml");
  ASSERT_TRUE(scenario) << scenario.error().message;
  auto setup = PrepareSimulation(std::move(*scenario), SetupUse::kPlanningOnly);
  ASSERT_TRUE(setup) << setup.error().message;
  const double radius = setup->scenario.plan.link_radius;
  ASSERT_EQ(radius, 0.07);
  auto blocked = [&](const sim::ScanPlan& plan) {
    std::size_t count = sim::BlockedMoves(setup->nominal, setup->scene, plan, radius).size();
    for (const auto& scan : plan.scans)
      count += sim::MoveIsFree(setup->nominal, setup->scene, scan.start, scan.end, radius) ? 0 : 1;
    return count;
  };
  auto plan = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, setup->scenario.plan);
  ASSERT_TRUE(plan) << plan.error().message;
  EXPECT_EQ(plan->scans.size(), 35u);
  EXPECT_EQ(blocked(*plan), 0u);
  sim::PlanOptions origin_only = setup->scenario.plan;
  origin_only.link_radius = 0;
  auto unchecked = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, origin_only);
  ASSERT_TRUE(unchecked) << unchecked.error().message;
  EXPECT_GT(blocked(*unchecked), 0u);
}

TEST(InformationPlanner, RejectsBadOptions) {
  PlannerOptions options;
  options.max_scans = 1;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("max_scans = 1"), std::string::npos) << error;
}

// Sweeps: each candidate a sweep whose poses (one per line) are the arm's joints at their
// measurement time, thinned for planning. The plan beats as many
// of the paper-style plan's sweeps, and the thinning changes the prediction little (J^T J is
// scaled back by the measurements left out, and the match distance grows with the spacing).
void PlansSweeps(const std::string& scenario) {
  Small sweeps = LoadScenario(scenario);
  // The scans' part of the prediction, which the selection ranks by (the held part: below).
  sweeps.engine.intrinsic_scale_sd = sweeps.engine.intrinsic_offset_sd_m =
      sweeps.engine.intrinsic_focal_sd = 0;
  PlannerOptions options;
  options.max_scans = 4;
  options.candidates = 12;
  options.threads = 2;
  auto candidates = MakeCandidates(sweeps.setup.nominal, sweeps.setup.sensor, sweeps.setup.scene,
                                   sweeps.setup.scenario.plan, sweeps.engine, options);
  ASSERT_TRUE(candidates) << candidates.error().message;
  ASSERT_GE(candidates->sighted.size(), 6u);
  EXPECT_TRUE(candidates->unobservable.empty());
  const InformationPlan planned = ChooseScans(*candidates, options);
  ASSERT_EQ(planned.chosen.size(), 4u);
  for (std::size_t s = 0; s < 4; ++s) {
    const auto& view = candidates->views[static_cast<std::size_t>(planned.chosen[s])];
    EXPECT_EQ(planned.plan.scans[s].start, view.start);
    EXPECT_EQ(planned.plan.scans[s].end, view.end);
    EXPECT_NE(view.start, view.end);
  }
  const calib::PredictedError paper = PredictForViews(*candidates, {0, 1, 2, 3}, options);
  PlannerOptions finer = options;
  finer.planning_cells = 8 * options.planning_cells;
  auto fine = MakeCandidates(sweeps.setup.nominal, sweeps.setup.sensor, sweeps.setup.scene,
                             sweeps.setup.scenario.plan, sweeps.engine, finer);
  ASSERT_TRUE(fine) << fine.error().message;
  auto kept = [](const CandidateSet& set) { return set.thinning.along * set.thinning.lines; };
  EXPECT_GT(kept(*candidates), kept(*fine));
  const calib::PredictedError paper_fine = PredictForViews(*fine, {0, 1, 2, 3}, finer);
  std::printf(
      "%s, 4 sweeps: predicted sensor position RMS planned %.4f mm, paper plan %.4f mm "
      "(thinned %d x %d), %.4f mm (thinned %d x %d)\n",
      scenario.c_str(), planned.predicted.sensor.rms_position_m * 1e3,
      paper.sensor.rms_position_m * 1e3, candidates->thinning.along, candidates->thinning.lines,
      paper_fine.sensor.rms_position_m * 1e3, fine->thinning.along, fine->thinning.lines);
  EXPECT_LE(planned.predicted.sensor.rms_position_m, paper.sensor.rms_position_m);
  EXPECT_NEAR(paper.sensor.rms_position_m / paper_fine.sensor.rms_position_m, 1.0, 0.2);
  // What the engine matched is what the planning simulated: one pose per line.
  auto simulated = SimulateViews(sweeps.setup.nominal, sweeps.setup.sensor, sweeps.setup.scene,
                                 {candidates->views.front()}, options.planning_cells, 0.0, {});
  ASSERT_TRUE(simulated) << simulated.error().message;
  ASSERT_EQ(simulated->datasets.size(), 1u);
  const calib::Dataset& dataset = simulated->datasets.front();
  EXPECT_EQ(dataset.layout, calib::PoseLayout::kOnePerColumn);
  EXPECT_EQ(dataset.pose_joints.size(), dataset.PoseCount() * dataset.joint_count);
  EXPECT_LE(dataset.PointCount(), static_cast<std::size_t>(options.planning_cells));
}

TEST(InformationPlanner, PlansLidarSweeps) { PlansSweeps("hokuyo-demo.yaml"); }

TEST(InformationPlanner, PlansLineScannerSweeps) { PlansSweeps("wenglor-bunny.yaml"); }

}  // namespace
}  // namespace selfcal::plan
