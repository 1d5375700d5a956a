// The scenario file's `effects:` section: read strictly, formatted back to the same effects,
// and with every effect off the recording is byte for byte the one without the section (the
// whole pipeline of `selfcal simulate`, in process); with an effect on it differs.
#include "protocols/scenario/effects_file.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/model/evaluation.h"
#include "core/sim/ray_caster.h"
#include "core/sim/scan_plan.h"
#include "protocols/scenario/scenario_file.h"
#include "protocols/scenario/sim_messages.h"
#include "protocols/scenario/simulation_setup.h"

namespace selfcal {
namespace {

std::string Source(const std::string& relative) {
  const char* root = std::getenv("SELFCAL_SOURCE_DIR");
  return std::string(root ? root : ".") + "/" + relative;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The test scenario's text with `extra` appended, parsed as if it were in its own folder.
Expected<Scenario> Parse(const std::string& scenario, const std::string& extra) {
  const std::string path = Source("tests/sim/data/" + scenario + ".yaml");
  return ParseScenario(ReadText(path) + extra, path, Source("tests/sim/data"));
}

// Every log event of the recording, encoded, in order: what `selfcal simulate` writes.
std::vector<LogEvent> Record(Scenario scenario) {
  auto setup = PrepareSimulation(std::move(scenario));
  EXPECT_TRUE(setup.ok()) << setup.error().message;
  auto caster = sim::RayCaster::Create(setup->scene);
  EXPECT_TRUE(caster.ok());
  auto plan = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, setup->scenario.plan);
  EXPECT_TRUE(plan.ok());
  MessageContext context;
  context.start_utime = setup->scenario.start_utime;
  for (const auto& joint : setup->nominal.joints) context.joint_names.push_back(joint.name);
  context.plan_name = setup->scenario.name;
  context.sensor = setup->sensor;
  const sim::Simulator simulator(setup->truth, setup->sensor, **caster, *plan,
                                 setup->scenario.recording);
  std::vector<LogEvent> events;
  for (int k = 0; k < simulator.SegmentCount(); ++k) {
    for (auto& event : SegmentEvents(simulator.Segment(k), context)) events.push_back(event);
  }
  return events;
}

bool SameBytes(const std::vector<LogEvent>& a, const std::vector<LogEvent>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].utime != b[i].utime || a[i].channel != b[i].channel || a[i].data != b[i].data) {
      return false;
    }
  }
  return true;
}

TEST(EffectsFile, AbsentOrEmptyMeansEveryEffectOff) {
  auto without = Parse("camera-corner", "");
  auto empty = Parse("camera-corner", "effects: {}\n");
  ASSERT_TRUE(without.ok()) << without.error().message;
  ASSERT_TRUE(empty.ok()) << empty.error().message;
  EXPECT_FALSE(without->recording.effects.AnyEnabled());
  EXPECT_FALSE(empty->recording.effects.AnyEnabled());
  EXPECT_EQ(FormatScenario(*without), FormatScenario(*empty));
  EXPECT_EQ(FormatScenario(*without).find("effects"), std::string::npos);
}

TEST(EffectsFile, OffReproducesTheRecordingByteForByte) {
  for (const char* name : {"camera-corner", "lidar-corner"}) {
    auto without = Parse(name, "");
    auto empty = Parse(name, "effects: {}\n");
    ASSERT_TRUE(without.ok() && empty.ok());
    const auto reference = Record(*without);
    ASSERT_GT(reference.size(), 100u);
    EXPECT_TRUE(SameBytes(reference, Record(*empty))) << name;
    // The same pipeline notices an effect: mixed pixels change the sensor messages.
    auto mixed = Parse(name, "effects: {mixed_pixels: {probability: 1.0}}\n");
    ASSERT_TRUE(mixed.ok()) << mixed.error().message;
    EXPECT_FALSE(SameBytes(reference, Record(*mixed))) << name;
  }
}

TEST(EffectsFile, ReadsEveryEffectAndFormatsItBack) {
  const std::string section = R"(effects:
  mixed_pixels: {probability: 0.3, min_jump: 0.03}
  range_bias: {offset: 0.001, per_metre: 0.001, incidence: 0.004, warmup_offset: 0.003, warmup_time_constant: 600}
  incidence_noise: {exponent: 1.5, max_factor: 3}
  grazing_dropout: {max_angle: 1.2}
  baseline_shadows: {baseline: 0.12}
  intrinsics: {depth_scale: 0.002, range_offset: -0.001, focal_scale: 0.004}
  joint_elasticity: {sensor_mass: 0.44}
  timing: {joint_lag: 0.003, clock_drift_ppm: 20}
  self_view: {radius: 0.065}
  walker: {scans: [1, 3], from: [2, -1, 0.8], to: [2, 1, 0.8]}
  moved_object: {after_scan: 2, size: [0.2, 0.3, 0.25], position: [1, 0.5, 0], shift: [0.1, 0, 0]}
  multipath: {amplitude: 0.004, radius: 0.08, samples: 12}
  dark_dropout: {threshold: 0.002}
  speckle: {correlation_length: 4}
  thermal_growth: {temperature_rise: 2.5}
  backlash: {angle: 0.0003}
)";
  auto scenario = Parse("camera-corner", section);
  ASSERT_TRUE(scenario.ok()) << scenario.error().message;
  const sim::FieldEffects& e = scenario->recording.effects;
  EXPECT_TRUE(e.mixed_pixels.enabled && e.range_bias.enabled && e.incidence_noise.enabled &&
              e.grazing_dropout.enabled && e.baseline_shadows.enabled && e.intrinsics.enabled &&
              e.joint_elasticity.enabled && e.timing.enabled && e.self_view.enabled &&
              e.walker.enabled && e.moved_object.enabled);
  EXPECT_DOUBLE_EQ(e.mixed_pixels.probability, 0.3);
  EXPECT_DOUBLE_EQ(e.range_bias.warmup_time_constant, 600);
  EXPECT_DOUBLE_EQ(e.incidence_noise.exponent, 1.5);
  EXPECT_DOUBLE_EQ(e.intrinsics.range_offset, -0.001);
  EXPECT_EQ(e.joint_elasticity.stiffness, IiwaElasticity().stiffness);  // defaults
  EXPECT_DOUBLE_EQ(e.joint_elasticity.sensor_mass, 0.44);
  EXPECT_DOUBLE_EQ(e.timing.clock_drift_ppm, 20);
  EXPECT_EQ(e.walker.scans, (std::vector<int>{1, 3}));
  EXPECT_DOUBLE_EQ(e.moved_object.size.y(), 0.3);
  EXPECT_TRUE(e.multipath.enabled && e.dark_dropout.enabled && e.speckle.enabled &&
              e.thermal_growth.enabled && e.backlash.enabled);
  EXPECT_EQ(e.multipath.samples, 12);
  EXPECT_DOUBLE_EQ(e.dark_dropout.threshold, 0.002);
  EXPECT_DOUBLE_EQ(e.speckle.correlation_length, 4);
  EXPECT_DOUBLE_EQ(e.thermal_growth.temperature_rise, 2.5);
  EXPECT_DOUBLE_EQ(e.thermal_growth.time_constant, 600);  // default
  EXPECT_DOUBLE_EQ(e.backlash.angle, 0.0003);
  // The resolved form reads back to the same effects.
  const std::string formatted = FormatScenario(*scenario);
  auto again = ParseScenario(formatted, "resolved", Source("tests/sim/data"));
  ASSERT_TRUE(again.ok()) << again.error().message << "\n" << formatted;
  EXPECT_EQ(FormatScenario(*again), formatted);
}

TEST(EffectsFile, RejectsUnknownKeysAndBadValuesNamingThem) {
  struct Case {
    const char* section;
    const char* key;
  };
  for (const Case& c : {Case{"effects: {flying_pixels: {}}\n", "flying_pixels"},
                        Case{"effects: {mixed_pixels: {probability: 1.5}}\n", "probability"},
                        Case{"effects: {mixed_pixels: {chance: 0.5}}\n", "chance"},
                        Case{"effects: {joint_elasticity: {stiffness: [1, 2]}}\n", "link_masses"},
                        Case{"effects: {walker: {from: [0, 0, 0]}}\n", "scans"},
                        Case{"effects: {timing: {joint_lag: 0.5}}\n", "joint_lag"},
                        Case{"effects: {multipath: {samples: 0}}\n", "samples"},
                        Case{"effects: {backlash: {angle: -1}}\n", "angle"}}) {
    auto scenario = Parse("camera-corner", c.section);
    ASSERT_FALSE(scenario.ok()) << c.section;
    EXPECT_NE(scenario.error().message.find(c.key), std::string::npos) << scenario.error().message;
    EXPECT_NE(scenario.error().message.find("camera-corner"), std::string::npos);
  }
}

TEST(EffectsFile, ElasticityMustMatchTheRobot) {
  auto scenario = Parse("camera-corner",
                        "effects: {joint_elasticity: {stiffness: [1, 2], link_masses: [1, 2]}}\n");
  ASSERT_TRUE(scenario.ok());
  auto setup = PrepareSimulation(std::move(*scenario));
  ASSERT_FALSE(setup.ok());
  EXPECT_NE(setup.error().message.find("joint_elasticity"), std::string::npos);
}

// The field twins: each reads, prepares and plans, turns effects on, and starts its nominal
// model about 60 mm RMS from the truth (twice today's scenarios).
class FieldScenario : public testing::TestWithParam<const char*> {};

TEST_P(FieldScenario, ReadsPreparesAndStartsSixtyMillimetresOff) {
  auto scenario =
      ReadScenarioFile(Source(std::string("config/scenarios/field/") + GetParam() + ".yaml"));
  ASSERT_TRUE(scenario.ok()) << scenario.error().message;
  EXPECT_EQ(scenario->name, std::string(GetParam()) + "-field");
  EXPECT_TRUE(scenario->recording.effects.AnyMeasurementEffect());
  EXPECT_TRUE(scenario->recording.effects.joint_elasticity.enabled);
  EXPECT_TRUE(scenario->recording.effects.timing.enabled);
  EXPECT_NE(scenario->recording.latency, 0);
  EXPECT_TRUE(scenario->recording.effects.thermal_growth.enabled);
  EXPECT_TRUE(scenario->recording.effects.backlash.enabled);
  EXPECT_FALSE(scenario->scene.albedo.empty());
  // The resolved form (scenario.yaml of a recording) reads back to the same scenario.
  const std::string formatted = FormatScenario(*scenario);
  auto again = ParseScenario(formatted, "resolved", Source("config/scenarios/field"));
  ASSERT_TRUE(again.ok()) << again.error().message << "\n" << formatted;
  EXPECT_EQ(FormatScenario(*again), formatted);
  EXPECT_EQ(again->scene.albedo, scenario->scene.albedo);
  scenario->plan.fit_scans = 7;
  auto setup = PrepareSimulation(std::move(*scenario));
  ASSERT_TRUE(setup.ok()) << setup.error().message;
  const PoseErrorStats error = SensorPoseError(setup->truth, setup->nominal, 1000, 777);
  EXPECT_GE(error.rms_position_m, 0.050);
  EXPECT_LE(error.rms_position_m, 0.070);
  auto plan = sim::MakeScanPlan(setup->nominal, setup->sensor, setup->scene, setup->scenario.plan);
  ASSERT_TRUE(plan.ok()) << plan.error().message;
}

INSTANTIATE_TEST_SUITE_P(Twins, FieldScenario,
                         testing::Values("kinect-bunny", "kinect-office", "photoneo-bunny",
                                         "wenglor-bunny", "hokuyo-office"));

}  // namespace
}  // namespace selfcal
