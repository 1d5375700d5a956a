#include "protocols/model_file/sensor_config.h"

#include <gtest/gtest.h>

#include <array>
#include <vector>

namespace selfcal {
namespace {

std::string SensorPath(const std::string& name) {
  const char* dir = std::getenv("SELFCAL_SOURCE_DIR");
  return std::string(dir ? dir : ".") + "/config/sensors/" + name + ".yaml";
}

// A small, valid depth camera file for the tests to change one key of.
constexpr const char* kCamera = R"(name: cam
layout: depth_camera
resolution: {x: 4, y: 3}
view_range: {closest: 0.5, farthest: 1.0}
noise: {sigma_abs: 0.001, sigma_rel: 0}
preprocessing: {n: 2, m: 2, g_min: 0.8}
match_validation: {d_max: 0.02, f_min: 0.8}
stop: {epsilon: 1.0e-4, i_max: 50}
geometry: {fx: 10, fy: 10, cx: 2, cy: 1.5, frame_rate_hz: 30}
)";

TEST(SensorConfig, ShippedSensorsCarryTableI) {
  const auto hokuyo = ReadSensorConfig(SensorPath("hokuyo_utm30lx"));
  ASSERT_TRUE(hokuyo.ok()) << hokuyo.error().message;
  EXPECT_EQ(hokuyo->layout, SensorLayout::kRotatingLidar);
  EXPECT_EQ(hokuyo->filter_n, 2);
  EXPECT_EQ(hokuyo->filter_m, 4);
  EXPECT_DOUBLE_EQ(hokuyo->g_min, 0.60);
  EXPECT_DOUBLE_EQ(hokuyo->f_min, 0.75);
  EXPECT_DOUBLE_EQ(hokuyo->sigma_abs, 0.018);
  EXPECT_EQ(hokuyo->lidar.steps, 1081);

  const auto wenglor = ReadSensorConfig(SensorPath("wenglor_mlsl236"));
  ASSERT_TRUE(wenglor.ok()) << wenglor.error().message;
  EXPECT_EQ(wenglor->filter_n, 3);
  EXPECT_EQ(wenglor->filter_m, 2);
  EXPECT_DOUBLE_EQ(wenglor->sigma_abs, 0.0002);

  const auto kinect = ReadSensorConfig(SensorPath("kinect_azure_nfov_binned"));
  ASSERT_TRUE(kinect.ok()) << kinect.error().message;
  EXPECT_EQ(kinect->resolution_x, 320);
  EXPECT_EQ(kinect->resolution_y, 288);
  EXPECT_DOUBLE_EQ(kinect->sigma_rel, 0.0021);
  EXPECT_DOUBLE_EQ(kinect->g_min, 0.75);

  const auto photoneo = ReadSensorConfig(SensorPath("photoneo_motioncam3d"));
  ASSERT_TRUE(photoneo.ok()) << photoneo.error().message;
  EXPECT_EQ(photoneo->resolution_x, 1120);
  EXPECT_EQ(photoneo->query_stride, 2);  // deviation 11; every other sensor queries every point
  EXPECT_EQ(kinect->query_stride, 1);
  EXPECT_DOUBLE_EQ(photoneo->range_closest, 0.497);
  for (const auto* s : {&*hokuyo, &*wenglor, &*kinect, &*photoneo}) {
    EXPECT_DOUBLE_EQ(s->d_max, 0.020) << s->name;
    EXPECT_DOUBLE_EQ(s->epsilon, 1e-4) << s->name;
    EXPECT_EQ(s->i_max, 50) << s->name;
  }
}

TEST(SensorConfig, StrictAboutKeys) {
  const std::string good = kCamera;
  ASSERT_TRUE(ParseSensorConfig(good, "cam.yaml").ok());
  auto with = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    return text.replace(text.find(from), from.size(), to);
  };
  const auto unknown = ParseSensorConfig(with("i_max: 50", "i_max: 50, j_max: 3"), "cam.yaml");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("stop.j_max"), std::string::npos);
  const auto missing = ParseSensorConfig(with("fx: 10, ", ""), "cam.yaml");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("geometry.fx"), std::string::npos);
  const auto layout = ParseSensorConfig(with("depth_camera", "sonar"), "cam.yaml");
  ASSERT_FALSE(layout.ok());
  EXPECT_NE(layout.error().message.find("sonar"), std::string::npos);
  const auto range = ParseSensorConfig(with("farthest: 1.0", "farthest: 0.1"), "cam.yaml");
  ASSERT_FALSE(range.ok());
  EXPECT_NE(range.error().message.find("view_range.farthest"), std::string::npos);
  // query_stride (1: every point, as the paper) and coarse_stride (1: off, the paper's loop;
  // deviation 24) are optional and at least 1.
  const auto plain = ParseSensorConfig(good, "cam.yaml");
  EXPECT_EQ(plain->query_stride, 1);
  EXPECT_EQ(plain->coarse_stride, 1);
  for (const std::string key : {"query_stride", "coarse_stride"}) {
    const auto strided =
        ParseSensorConfig(with("f_min: 0.8}", "f_min: 0.8, " + key + ": 4}"), "cam.yaml");
    ASSERT_TRUE(strided.ok()) << strided.error().message;
    EXPECT_EQ(key == "query_stride" ? strided->query_stride : strided->coarse_stride, 4);
    const auto zero =
        ParseSensorConfig(with("f_min: 0.8}", "f_min: 0.8, " + key + ": 0}"), "cam.yaml");
    ASSERT_FALSE(zero.ok());
    EXPECT_NE(zero.error().message.find("match_validation." + key), std::string::npos);
  }
  // flying_pixel_angle is optional (0: off, as the paper; deviation 19).
  EXPECT_EQ(ParseSensorConfig(good, "cam.yaml")->flying_pixel_angle_deg, 0.0);
  const auto flying =
      ParseSensorConfig(with("g_min: 0.8", "g_min: 0.8, flying_pixel_angle: 10"), "cam.yaml");
  ASSERT_TRUE(flying.ok()) << flying.error().message;
  EXPECT_EQ(flying->flying_pixel_angle_deg, 10.0);
  // Found by fuzz_sensor_file: values the engine refuses (g_min 1.6; the engine's limits now
  // check it here) and noise terms that are NaN or infinite (they passed "< 0") were read without
  // a word. Each names its key.
  for (const auto& [from, to, key] : std::vector<std::array<std::string, 3>>{
           {"g_min: 0.8", "g_min: 1.6", "preprocessing.g_min"},
           {"g_min: 0.8", "g_min: .nan", "preprocessing.g_min"},
           {"f_min: 0.8", "f_min: -1.5", "match_validation.f_min"},
           {"sigma_abs: 0.001", "sigma_abs: .nan", "noise.sigma_abs"},
           {"sigma_rel: 0", "sigma_rel: .inf", "noise.sigma_rel"},
           {"g_min: 0.8", "g_min: 0.8, flying_pixel_angle: 90", "preprocessing.flying_pixel_angle"},
           {"g_min: 0.8", "g_min: 0.8, flying_pixel_angle: -1", "preprocessing.flying_pixel_angle"},
           {"g_min: 0.8", "g_min: 0.8, flying_pixel_angle: .nan",
            "preprocessing.flying_pixel_angle"}}) {
    const auto bad = ParseSensorConfig(with(from, to), "cam.yaml");
    ASSERT_FALSE(bad.ok()) << to;
    EXPECT_NE(bad.error().message.find(key), std::string::npos) << bad.error().message;
  }
}

// The optional latency section (docs/engine.md, deviation 16): the engine's start value, and
// whether it estimates it; absent = 0 s and the layout's choice.
TEST(SensorConfig, LatencyIsOptionalAndChecked) {
  const std::string good = kCamera;
  const auto plain = ParseSensorConfig(good, "cam.yaml");
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain->latency_s, 0.0);
  EXPECT_FALSE(plain->estimate_latency.has_value());
  const auto given =
      ParseSensorConfig(good + "latency: {seconds: 0.012, estimate: false}\n", "cam.yaml");
  ASSERT_TRUE(given.ok()) << given.error().message;
  EXPECT_DOUBLE_EQ(given->latency_s, 0.012);
  ASSERT_TRUE(given->estimate_latency.has_value());
  EXPECT_FALSE(*given->estimate_latency);
  const auto only_estimate = ParseSensorConfig(good + "latency: {estimate: true}\n", "cam.yaml");
  ASSERT_TRUE(only_estimate.ok()) << only_estimate.error().message;
  EXPECT_EQ(only_estimate->latency_s, 0.0);
  EXPECT_TRUE(only_estimate->estimate_latency.value_or(false));
  for (const auto& [section, expected] : std::vector<std::array<std::string, 2>>{
           {"latency: {seconds: 12}", "key 'latency.seconds' must be within +-1 s"},
           {"latency: {seconds: .nan}", "latency.seconds"},
           {"latency: {estimate: maybe}", "latency.estimate"},
           {"latency: {seconds: 0.01, offset: 2}", "latency.offset"}}) {
    const auto bad = ParseSensorConfig(good + section + "\n", "cam.yaml");
    ASSERT_FALSE(bad.ok()) << section;
    EXPECT_NE(bad.error().message.find(expected), std::string::npos) << bad.error().message;
  }
}

TEST(SensorConfig, IntrinsicsUncertaintyIsOptionalAndChecked) {
  const std::string good = kCamera;
  const auto plain = ParseSensorConfig(good, "cam.yaml");
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain->intrinsics_uncertainty.scale, 0.0);
  EXPECT_EQ(plain->intrinsics_uncertainty.offset_m, 0.0);
  EXPECT_EQ(plain->intrinsics_uncertainty.focal, 0.0);
  const auto given = ParseSensorConfig(
      good + "intrinsics_uncertainty: {scale: 0.002, offset: 0.003}\n", "cam.yaml");
  ASSERT_TRUE(given.ok()) << given.error().message;
  EXPECT_DOUBLE_EQ(given->intrinsics_uncertainty.scale, 0.002);
  EXPECT_DOUBLE_EQ(given->intrinsics_uncertainty.offset_m, 0.003);
  EXPECT_EQ(given->intrinsics_uncertainty.focal, 0.0);
  for (const auto& [section, expected] : std::vector<std::array<std::string, 2>>{
           {"intrinsics_uncertainty: {offset: 3}", "'intrinsics_uncertainty.offset' must be in"},
           {"intrinsics_uncertainty: {scale: -0.001}", "intrinsics_uncertainty.scale"},
           {"intrinsics_uncertainty: {focal: .inf}", "intrinsics_uncertainty.focal"},
           {"intrinsics_uncertainty: {depth: 0.001}", "intrinsics_uncertainty.depth"}}) {
    const auto bad = ParseSensorConfig(good + section + "\n", "cam.yaml");
    ASSERT_FALSE(bad.ok()) << section;
    EXPECT_NE(bad.error().message.find(expected), std::string::npos) << bad.error().message;
  }
}

TEST(SensorConfig, CalibrateIntrinsicsIsOptionalAndChecked) {
  const std::string good = kCamera;
  const auto plain = ParseSensorConfig(good, "cam.yaml");
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain->calibrate_intrinsics, "");
  for (const std::string choice : {"none", "auto", "offset", "scale+focal"}) {
    const auto given = ParseSensorConfig(good + "calibrate_intrinsics: " + choice + "\n", "c.yaml");
    ASSERT_TRUE(given.ok()) << choice << ": " << given.error().message;
    EXPECT_EQ(given->calibrate_intrinsics, choice);
  }
  for (const std::string choice : {"depth", "offset+", "[offset]", "scale+sheer"}) {
    const auto bad = ParseSensorConfig(good + "calibrate_intrinsics: " + choice + "\n", "c.yaml");
    ASSERT_FALSE(bad.ok()) << choice;
    EXPECT_NE(bad.error().message.find("calibrate_intrinsics"), std::string::npos)
        << bad.error().message;
  }
}

// Found by fuzz_sensor_file: a key given twice was read from its first place and the second
// value dropped without a word (yaml-cpp keeps both entries, a lookup finds the first). Every
// strict reader refuses it, naming the key and both lines.
TEST(SensorConfig, AKeyGivenTwiceIsRefusedWithBothLines) {
  const std::string text = std::string(kCamera) + "resolution: {x: 8, y: 6}\n";
  const auto twice = ParseSensorConfig(text, "cam.yaml");
  ASSERT_FALSE(twice.ok());
  EXPECT_EQ(twice.error().message, "cam.yaml: key 'resolution' is given twice (lines 3 and 10)");
  std::string nested = text.substr(0, text.rfind("resolution"));
  nested.replace(nested.find("n: 2, m: 2"), 10, "n: 2, m: 2, n: 3");
  const auto inner = ParseSensorConfig(nested, "cam.yaml");
  ASSERT_FALSE(inner.ok());
  EXPECT_NE(inner.error().message.find("key 'preprocessing.n' is given twice (lines 6 and 6)"),
            std::string::npos)
      << inner.error().message;
}

// The engine's limits (core/calib/parameter_limits.h), named by the key they came from.
TEST(SensorConfig, TableIValuesWithinTheEnginesLimits) {
  const std::string good = kCamera;
  auto error_with = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const auto parsed = ParseSensorConfig(text.replace(text.find(from), from.size(), to), "c.yaml");
    return parsed.ok() ? std::string("accepted") : parsed.error().message;
  };
  auto mentions = [](const std::string& message, const std::string& text) {
    return message.find(text) != std::string::npos;
  };
  EXPECT_PRED2(mentions, error_with("g_min: 0.8", "g_min: 1.5"),
               "key 'preprocessing.g_min' must be in [0, 1]");
  EXPECT_PRED2(mentions, error_with("m: 2,", "m: -1,"), "key 'preprocessing.m' must be at least 0");
  EXPECT_PRED2(mentions, error_with("n: 2,", "n: -1,"), "key 'preprocessing.n' must be at least 0");
  EXPECT_PRED2(mentions, error_with("f_min: 0.8", "f_min: -2"),
               "key 'match_validation.f_min' must be in [-1, 1]");
  EXPECT_PRED2(mentions, error_with("d_max: 0.02", "d_max: 0"),
               "key 'match_validation.d_max' must be positive and finite");
  EXPECT_PRED2(mentions, error_with("d_max: 0.02", "d_max: .inf"),
               "key 'match_validation.d_max' must be positive and finite");
  EXPECT_PRED2(mentions, error_with("epsilon: 1.0e-4", "epsilon: -1.0e-4"),
               "key 'stop.epsilon' must be finite and not negative");
  EXPECT_PRED2(mentions, error_with("i_max: 50", "i_max: 0"),
               "key 'stop.i_max' must be at least 1");
  // As the engine: epsilon 0 stops by i_max only.
  EXPECT_EQ(error_with("epsilon: 1.0e-4", "epsilon: 0"), "accepted");
  EXPECT_EQ(error_with("g_min: 0.8", "g_min: 0"), "accepted");
  EXPECT_EQ(error_with("f_min: 0.8", "f_min: -1"), "accepted");
}

}  // namespace
}  // namespace selfcal
