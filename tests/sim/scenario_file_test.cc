// Scenario files: every committed scenario reads, prepares and plans within joint limits with a
// nominal 20-40 mm off its truth; the reader is strict and names file and key; the resolved
// form reads back to the same scenario. Cells (scene kind cell: a real cell's free space) plan
// scans whose sensor stays in that free space, and are never simulated.
#include "protocols/scenario/scenario_file.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "core/model/evaluation.h"
#include "core/model/kinematics.h"
#include "core/sim/ground_truth.h"
#include "core/sim/scan_plan.h"
#include "protocols/scenario/sensor_model_config.h"
#include "protocols/scenario/simulation_setup.h"

namespace selfcal {
namespace {

std::string Source(const std::string& relative) {
  const char* root = std::getenv("SELFCAL_SOURCE_DIR");
  return std::string(root ? root : ".") + "/" + relative;
}

class CommittedScenario : public testing::TestWithParam<const char*> {};

TEST_P(CommittedScenario, ReadsPreparesAndPlansWithinLimits) {
  const std::string path = Source(std::string("config/scenarios/") + GetParam() + ".yaml");
  auto scenario = ReadScenarioFile(path);
  ASSERT_TRUE(scenario.ok()) << scenario.error().message;
  EXPECT_EQ(scenario->name, GetParam());
  // Every scenario offers the paper's batches: its plan has 28 fit scans (or is the small one).
  EXPECT_EQ(scenario->plan.fit_scans, std::string(GetParam()) == "small" ? 14 : 28);
  EXPECT_EQ(scenario->plan.validation_scans, 7);
  scenario->plan.fit_scans = 7;  // the first batch; the rest is the same planner
  auto setup = PrepareSimulation(std::move(*scenario));
  ASSERT_TRUE(setup.ok()) << setup.error().message;
  const PoseErrorStats error = SensorPoseError(setup->truth, setup->nominal, 1000, 777);
  EXPECT_GE(error.rms_position_m, 0.020);
  EXPECT_LE(error.rms_position_m, 0.040);
  auto plan = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, setup->scenario.plan);
  ASSERT_TRUE(plan.ok()) << plan.error().message;
  ASSERT_EQ(plan->scans.size(), 14u);
  for (const auto& scan : plan->scans) {
    for (const auto* q : {&scan.start, &scan.end}) {
      ASSERT_EQ(q->size(), setup->nominal.JointCount());
      for (std::size_t j = 0; j < q->size(); ++j) {
        EXPECT_GE((*q)[j], setup->nominal.joints[j].lower);
        EXPECT_LE((*q)[j], setup->nominal.joints[j].upper);
      }
    }
  }
  // Round trip of the resolved form.
  const std::string resolved = FormatScenario(setup->scenario);
  auto again = ParseScenario(resolved, "resolved.yaml", "/");
  ASSERT_TRUE(again.ok()) << again.error().message << "\n" << resolved;
  EXPECT_EQ(FormatScenario(*again), resolved);
}

INSTANTIATE_TEST_SUITE_P(All, CommittedScenario,
                         testing::Values("small", "kinect-bunny", "kinect-teapot", "kinect-office",
                                         "kinect-lab", "photoneo-bunny", "photoneo-teapot",
                                         "wenglor-bunny", "wenglor-teapot", "hokuyo-office",
                                         "hokuyo-lab"),
                         [](const auto& info) {
                           std::string name = info.param;
                           for (char& c : name) c = c == '-' ? '_' : c;
                           return name;
                         });

const char* kMinimal =
    "name: t\nseed: 1\nrobot: r.yaml\nsensor: s.yaml\n"
    "sensor_mount: {x: 0, y: 0, z: 0.1, roll: 0, pitch: 0, yaw: 0}\n"
    "scene: {kind: corner}\n"
    "plan: {kind: stationary_views, scans: 7, view: {distance: [0.8, 1.0]}}\n";

TEST(ScenarioFile, MinimalScenarioGetsDefaultsAndResolvesPaths) {
  auto s = ParseScenario(kMinimal, "mem.yaml", "/base/dir");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(s->robot_path, "/base/dir/r.yaml");
  EXPECT_EQ(s->sensor_path, "/base/dir/s.yaml");
  EXPECT_EQ(s->plan.validation_scans, 7);
  EXPECT_EQ(s->plan.seed, 1u);
  EXPECT_EQ(s->recording.seed, 1u);
  EXPECT_DOUBLE_EQ(s->recording.joint_rate_hz, 200);
  EXPECT_FALSE(s->view_target_given);
  EXPECT_DOUBLE_EQ(s->plan.view.distance_min, 0.8);
  EXPECT_EQ(s->plan.link_radius, 0.0);  // the sensor's origin only
  EXPECT_EQ(FormatScenario(*s).find("link_radius"), std::string::npos);
}

// plan.link_radius: read, written back, and at most 0.5 m.
TEST(ScenarioFile, PlanLinkRadiusRoundTrips) {
  std::string text = kMinimal;
  text.replace(text.find("scans: 7,"), 9, "scans: 7, link_radius: 0.07,");
  auto s = ParseScenario(text, "mem.yaml", "/base/dir");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_DOUBLE_EQ(s->plan.link_radius, 0.07);
  auto again = ParseScenario(FormatScenario(*s), "again.yaml", "/");
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_DOUBLE_EQ(again->plan.link_radius, 0.07);
  text.replace(text.find("link_radius: 0.07"), 17, "link_radius: 0.7");
  const auto too_thick = ParseScenario(text, "mem.yaml", "/base/dir");
  ASSERT_FALSE(too_thick.ok());
  EXPECT_NE(too_thick.error().message.find("plan.link_radius"), std::string::npos)
      << too_thick.error().message;
}

// Names and paths are free text: YAML's comment, mapping and quote characters in them must survive
// the resolved form (a name "a #b" once came back as "a").
TEST(ScenarioFile, FreeTextSurvivesTheResolvedForm) {
  std::string text = kMinimal;
  text.replace(text.find("name: t"), 7, "name: \"a #b: 'c\\\" \"");
  text.replace(text.find("r.yaml"), 6, "\"my robot #2.yaml\"");
  auto s = ParseScenario(text, "mem.yaml", "/base");
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->name, "a #b: 'c\" ");
  const std::string resolved = FormatScenario(*s);
  auto again = ParseScenario(resolved, "resolved.yaml", "/");
  ASSERT_TRUE(again.ok()) << again.error().message << "\n" << resolved;
  EXPECT_EQ(again->name, s->name);
  EXPECT_EQ(again->robot_path, "/base/my robot #2.yaml");
  EXPECT_EQ(FormatScenario(*again), resolved);
}

void ExpectError(const std::string& text, const std::string& needle) {
  auto s = ParseScenario(text, "mem.yaml", "/");
  ASSERT_FALSE(s.ok()) << "accepted:\n" << text;
  EXPECT_NE(s.error().message.find(needle), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("mem.yaml"), std::string::npos) << s.error().message;
}

TEST(ScenarioFile, StrictErrorsNameFileAndKey) {
  const std::string base = kMinimal;
  ExpectError(base + "bogus: 1\n", "'bogus'");
  ExpectError("name: t\nseed: 1\n", "'robot'");
  ExpectError(base + "joint_states: {rate_hz: 5}\n", "joint_states.rate_hz");
  ExpectError(base + "joint_states: {rate_hz: 200, jitter: 1}\n", "joint_states.jitter");
  ExpectError(base + "sensor_latency: 0.5\n", "sensor_latency");
  ExpectError(base + "camera_output: jpeg\n", "camera_output");
  ExpectError(base + "timing: {settle_time: 0.01}\n", "timing.settle_time");
  std::string bad_plan = base;
  bad_plan.replace(bad_plan.find("stationary_views"), 16, "spiral");
  ExpectError(bad_plan, "plan.kind");
  std::string bad_range = base;
  bad_range.replace(bad_range.find("[0.8, 1.0]"), 10, "[1.0, 0.8]");
  ExpectError(bad_range, "plan.view.distance");
  // YAML's infinities would be written back as text no reader takes.
  std::string infinite_mount = base;
  infinite_mount.replace(infinite_mount.find("z: 0.1"), 6, "z: +.INF");
  ExpectError(infinite_mount, "sensor_mount.z");
  std::string infinite_range = base;
  infinite_range.replace(infinite_range.find("[0.8, 1.0]"), 10, "[0.8, .inf]");
  ExpectError(infinite_range, "plan.view.distance");
  std::string bad_seed = base;
  bad_seed.replace(bad_seed.find("seed: 1"), 7, "seed: x");
  ExpectError(bad_seed, "'seed'");
  EXPECT_FALSE(ReadScenarioFile("/nonexistent.yaml").ok());
}

TEST(ScenarioFile, PlanMustSuitTheSensor) {
  std::string text = kMinimal;
  text.replace(text.find("robot: r.yaml"), 13,
               "robot: " + Source("config/robots/kuka_lbr_iiwa_r840.yaml"));
  text.replace(text.find("sensor: s.yaml"), 14,
               "sensor: " + Source("config/sensors/hokuyo_utm30lx.yaml"));
  auto s = ParseScenario(text, "mem.yaml", "/");
  ASSERT_TRUE(s.ok()) << s.error().message;
  auto setup = PrepareSimulation(*s);
  ASSERT_FALSE(setup.ok());
  EXPECT_NE(setup.error().message.find("plan.kind"), std::string::npos) << setup.error().message;
  EXPECT_NE(setup.error().message.find("rotating_lidar"), std::string::npos)
      << setup.error().message;
}

// Found by fuzz_sensor_file: a camera one row high binned by 2 became a sensor of no pixels; the
// simulation said only "the sensor grid is empty". The scenario's key and the sensor's size are
// named now, and a binning the camera is large enough for still prepares.
TEST(ScenarioFile, ACameraBinningTheSensorIsTooSmallForNamesKeyAndSize) {
  std::string sensor_text;
  {
    std::ifstream in(Source("config/sensors/kinect_azure_nfov_binned.yaml"));
    sensor_text.assign(std::istreambuf_iterator<char>(in), {});
  }
  sensor_text.replace(sensor_text.find("{x: 320, y: 288}"), 16, "{x: 1080, y: 1}");
  const std::string sensor_path = testing::TempDir() + "one_row_camera.yaml";
  std::ofstream(sensor_path) << sensor_text;
  std::string text = kMinimal;
  text.replace(text.find("robot: r.yaml"), 13,
               "robot: " + Source("config/robots/kuka_lbr_iiwa_r840.yaml"));
  text.replace(text.find("sensor: s.yaml"), 14, "sensor: " + sensor_path);
  auto binned = ParseScenario(text + "camera_binning: 2\n", "mem.yaml", "/");
  ASSERT_TRUE(binned.ok()) << binned.error().message;
  const auto refused = PrepareSimulation(*binned);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("key 'camera_binning' 2 leaves no pixel of the 1080x1"),
            std::string::npos)
      << refused.error().message;
  auto unbinned = ParseScenario(text, "mem.yaml", "/");
  ASSERT_TRUE(unbinned.ok()) << unbinned.error().message;
  const auto prepared = PrepareSimulation(*unbinned);
  ASSERT_TRUE(prepared.ok()) << prepared.error().message;
  EXPECT_EQ(prepared->sensor.height, 1);
}

// The sensor origin of every scan's start and end lies in the free space, outside every obstacle.
void ExpectSensorInFreeSpace(const SimulationSetup& setup, const sim::ScanPlan& plan) {
  for (const auto& scan : plan.scans) {
    for (const auto* q : {&scan.start, &scan.end}) {
      const Eigen::Vector3d origin = ForwardKinematics(setup.nominal, *q).translation();
      EXPECT_TRUE(setup.scene.IsFree(origin, setup.scenario.plan.free_margin))
          << setup.scenario.name << ": sensor at " << origin.transpose();
    }
  }
}

class CommittedCell : public testing::TestWithParam<const char*> {};

TEST_P(CommittedCell, PlansTheInstalledScansInItsFreeSpaceAndIsNotSimulated) {
  const std::string path = Source(std::string("config/daemon/cells/iiwa_") + GetParam() + ".yaml");
  auto scenario = ReadScenarioFile(path);
  ASSERT_TRUE(scenario.ok()) << scenario.error().message;
  EXPECT_EQ(scenario->scene.kind, sim::SceneSpec::Kind::kCell);
  const auto simulated = PrepareSimulation(*scenario);
  ASSERT_FALSE(simulated.ok());
  EXPECT_NE(simulated.error().message.find("cannot be simulated"), std::string::npos)
      << simulated.error().message;
  auto setup = PrepareSimulation(std::move(*scenario), SetupUse::kPlanningOnly);
  ASSERT_TRUE(setup.ok()) << setup.error().message;
  EXPECT_FALSE(sim::HasSurfaces(setup->scene));
  auto plan = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, setup->scenario.plan);
  ASSERT_TRUE(plan.ok()) << plan.error().message;
  EXPECT_EQ(plan->scans.size(), 35u);
  ExpectSensorInFreeSpace(*setup, *plan);
  const std::string resolved = FormatScenario(setup->scenario);
  auto again = ParseScenario(resolved, "resolved.yaml", "/");
  ASSERT_TRUE(again.ok()) << again.error().message << "\n" << resolved;
  EXPECT_EQ(FormatScenario(*again), resolved);
}

INSTANTIATE_TEST_SUITE_P(All, CommittedCell,
                         testing::Values("hokuyo", "kinect", "photoneo", "wenglor"));

// kMinimal in a cell: free space, one obstacle, and the view target a cell needs.
std::string CellScenario() {
  std::string text = kMinimal;
  text.replace(text.find("{kind: corner}"), 14,
               "\n  kind: cell\n  free_space: {min: [-0.5, -1, 0.05], max: [1.3, 1, 1.5]}\n"
               "  obstacles:\n    - {min: [0.5, -0.1, 0], max: [0.7, 0.1, 0.2]}");
  text.replace(text.find("view: {"), 7, "view: {target: [0.6, 0, 0.1], ");
  return text;
}

TEST(ScenarioFile, ACellReadsItsBoxesStrictly) {
  const std::string cell = CellScenario();
  auto s = ParseScenario(cell, "mem.yaml", "/");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(s->scene.cell_free_space.min(), Eigen::Vector3d(-0.5, -1, 0.05));
  EXPECT_EQ(s->scene.cell_free_space.max(), Eigen::Vector3d(1.3, 1, 1.5));
  ASSERT_EQ(s->scene.cell_obstacles.size(), 1u);
  EXPECT_EQ(s->scene.cell_obstacles[0].max(), Eigen::Vector3d(0.7, 0.1, 0.2));
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = cell;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  ExpectError(replaced("max: [1.3, 1, 1.5]", "max: [1.3, -1, 1.5]"), "scene.free_space.max");
  ExpectError(replaced("max: [0.7, 0.1, 0.2]", "top: [0.7, 0.1, 0.2]"), "scene.obstacles[0]");
  ExpectError(replaced("  free_space", "  room"), "scene.free_space");
  ExpectError(replaced("target: [0.6, 0, 0.1], ", ""), "view.target");
}

TEST(ScenarioFile, TheSensorModelKeepsTheFileLayout) {
  for (const char* file :
       {"config/sensors/hokuyo_utm30lx.yaml", "config/sensors/wenglor_mlsl236.yaml",
        "config/sensors/kinect_azure_nfov_binned.yaml"}) {
    const auto config = ReadSensorConfig(Source(file));
    ASSERT_TRUE(config.ok()) << config.error().message;
    EXPECT_EQ(ToSensorModel(*config).kind, config->layout) << file;
  }
}

}  // namespace
}  // namespace selfcal
