// CalibrationOptions::IsValid: every option's range, and a message that names what is wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "core/calib/calibrate.h"

namespace selfcal::calib {
namespace {

std::string ErrorOf(const std::function<void(CalibrationOptions&)>& change) {
  CalibrationOptions options;
  change(options);
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_FALSE(options.IsValid(nullptr));
  return error;
}

TEST(CalibrationOptions, DefaultsAreValid) {
  std::string error = "untouched";
  EXPECT_TRUE(CalibrationOptions{}.IsValid(&error));
  EXPECT_EQ(error, "untouched");
  CalibrationOptions reference;
  reference.search = SearchStrategy::kReference;
  reference.solver = SolverKind::kReference;
  reference.filter_n = reference.filter_m = 0;
  reference.epsilon = 0;
  reference.i_max = 1;
  reference.lm_max_iterations = 1;
  EXPECT_TRUE(reference.IsValid(nullptr));
}

TEST(CalibrationOptions, ElasticityNeedsTheFastSolver) {
  CalibrationOptions elastic;
  elastic.elasticity = true;
  EXPECT_TRUE(elastic.IsValid(nullptr));
  elastic.search = SearchStrategy::kReference;  // the search is free to choose
  EXPECT_TRUE(elastic.IsValid(nullptr));
  EXPECT_EQ(ErrorOf([](CalibrationOptions& o) {
              o.elasticity = true;
              o.solver = SolverKind::kReference;
            }),
            "elasticity needs solver fast (the reference solver has no compliance parameters)");
}

TEST(CalibrationOptions, TheNoiseCorrectionNeedsTheFastSolver) {
  CalibrationOptions corrected;
  corrected.ray_noise_correction = true;
  EXPECT_TRUE(corrected.IsValid(nullptr));
  EXPECT_EQ(ErrorOf([](CalibrationOptions& o) {
              o.ray_noise_correction = true;
              o.solver = SolverKind::kReference;
            }),
            "ray_noise_correction needs solver fast (the reference solver keeps the paper's "
            "cost)");
}

// One choice replaces the last (a sensor file's default, then --intrinsics); a wrong one
// leaves the options as they were and says what is wrong.
TEST(CalibrationOptions, ChoosingIntrinsicsReplacesTheLastChoice) {
  CalibrationOptions options;
  EXPECT_EQ(options.IntrinsicsName(), "none");
  EXPECT_EQ(options.ChooseIntrinsics("auto"), "");
  EXPECT_TRUE(options.intrinsics.automatic);
  EXPECT_EQ(options.ChooseIntrinsics("focal+offset"), "");
  EXPECT_FALSE(options.intrinsics.automatic);
  EXPECT_EQ(options.IntrinsicsName(), "offset+focal");
  EXPECT_EQ(options.ChooseIntrinsics("offset+skew"),
            "must be none, auto or a '+'-list of scale, offset and focal, not 'offset+skew'");
  EXPECT_EQ(options.IntrinsicsName(), "offset+focal");
  EXPECT_NE(options.ChooseIntrinsics(""), "");
  EXPECT_EQ(options.ChooseIntrinsics("none"), "");
  EXPECT_FALSE(options.AnyIntrinsic());
}

TEST(CalibrationOptions, NamesTheOptionItsValueAndItsRange) {
  EXPECT_EQ(ErrorOf([](auto& o) { o.d_max = -0.02; }),
            "d_max = -0.02 m, must be positive and finite");
  EXPECT_EQ(ErrorOf([](auto& o) { o.filter_n = -1; }), "filter_n = -1, must be at least 0");
  EXPECT_EQ(ErrorOf([](auto& o) { o.filter_m = -2; }), "filter_m = -2, must be at least 0");
  EXPECT_EQ(ErrorOf([](auto& o) { o.g_min = 1.5; }), "g_min = 1.5, must be in [0, 1]");
  EXPECT_EQ(ErrorOf([](auto& o) { o.f_min = -2; }), "f_min = -2, must be in [-1, 1]");
  EXPECT_EQ(ErrorOf([](auto& o) { o.epsilon = -1e-4; }),
            "epsilon = -0.0001, must be finite and not negative");
  EXPECT_EQ(ErrorOf([](auto& o) { o.i_max = 0; }), "i_max = 0, must be at least 1");
  EXPECT_EQ(ErrorOf([](auto& o) { o.query_stride = 0; }), "query_stride = 0, must be at least 1");
  EXPECT_EQ(ErrorOf([](auto& o) { o.coarse_stride = 0; }), "coarse_stride = 0, must be at least 1");
  EXPECT_EQ(ErrorOf([](auto& o) { o.flying_pixel_angle_deg = 90; }),
            "flying_pixel_angle = 90 deg, must be in [0, 90) (0 = off)");
  EXPECT_EQ(ErrorOf([](auto& o) { o.link_margin_m = -0.01; }),
            "link_margin = -0.01 m, must be in [0, 0.2]");
  EXPECT_EQ(ErrorOf([](auto& o) { o.knot_max_joint_step = 0; }),
            "knot_max_joint_step = 0, must be positive and finite");
  EXPECT_EQ(ErrorOf([](auto& o) { o.threads = -1; }),
            "threads = -1, must be at least 0 (0 = all cores)");
  EXPECT_EQ(ErrorOf([](auto& o) { o.lm_max_iterations = 0; }),
            "lm_max_iterations = 0, must be at least 1");
  EXPECT_EQ(ErrorOf([](auto& o) { o.search = static_cast<SearchStrategy>(7); }),
            "search = 7, must be fast or reference");
  EXPECT_EQ(ErrorOf([](auto& o) { o.solver = static_cast<SolverKind>(7); }),
            "solver = 7, must be fast or reference");
}

TEST(CalibrationOptions, NotANumberIsOutOfEveryRange) {
  const double nan = std::nan("");
  EXPECT_NE(ErrorOf([&](auto& o) { o.d_max = nan; }).find("d_max"), std::string::npos);
  EXPECT_NE(ErrorOf([&](auto& o) { o.g_min = nan; }).find("g_min"), std::string::npos);
  EXPECT_NE(ErrorOf([&](auto& o) { o.f_min = nan; }).find("f_min"), std::string::npos);
  EXPECT_NE(ErrorOf([&](auto& o) { o.epsilon = nan; }).find("epsilon"), std::string::npos);
  EXPECT_NE(ErrorOf([](auto& o) { o.d_max = INFINITY; }).find("d_max"), std::string::npos);
}

}  // namespace
}  // namespace selfcal::calib
