// Convergence on the demo's field Hokuyo (config/scenarios/field/hokuyo-demo.yaml: 8 + 2 sweeps
// with noise and every field effect the SCIP simulator serves; the sensor looks sideways, so the
// tool's beta is -90 deg and its alpha + gamma moves no sensor pose). The paper's loop ends
// there at i_max = 50 on every seed tried; deviation 18 (the step measured by the sensor's
// motion, Anderson acceleration) converges (docs/engine.md). And acceleration must not leave the
// plain loop's minimum where that one converges.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/calib/calibrate.h"
#include "core/model/evaluation.h"
#include "tests/calib/simulated_scenario.h"

namespace selfcal::calib {
namespace {

class FieldHokuyo : public simulated::ScenarioTest<FieldHokuyo> {
 public:
  static constexpr const char* kScenario = "config/scenarios/field/hokuyo-demo.yaml";
  static constexpr const char* kSensor = "config/sensors/hokuyo_utm30lx.yaml";
  static constexpr const char* kTag = "convergence";
};

TEST_F(FieldHokuyo, ConvergesWellBeforeIMaxAndCloserToTheTruth) {
  const CalibrationResult result = Calibrate(datasets_, nominal_, options_);
  const double nominal = SensorPoseError(truth_, nominal_, 500, 1).rms_position_m;
  const double calibrated = SensorPoseError(truth_, result.model, 500, 1).rms_position_m;
  std::printf("%s after %zu iterations (%d accelerated, %d dropped): %.3f mm -> %.3f mm\n",
              TerminationName(result.termination), result.iterations.size(), result.accelerated,
              result.acceleration_dropped, nominal * 1e3, calibrated * 1e3);
  EXPECT_EQ(result.termination, Termination::kConverged) << result.message;
  EXPECT_LE(result.iterations.size(), 25u);
  EXPECT_GT(result.accelerated, 0);
  // The field effects keep it millimetres from the truth (docs/accuracy.md); the start is 28 mm.
  EXPECT_LT(calibrated, 8e-3);
  EXPECT_LT(calibrated, nominal / 3);
}

// The same kinect twin without effects where acceleration from the second iteration jumped to
// another local minimum (tests/calib/data/kinect-bunny-ideal-seed4.yaml): 62 mm from the truth
// after i_max. Waiting for a run of shorter steps keeps it near the plain loop's 0.38 mm.
class KinectBunnySeed4 : public simulated::ScenarioTest<KinectBunnySeed4> {
 public:
  static constexpr const char* kScenario = "tests/calib/data/kinect-bunny-ideal-seed4.yaml";
  static constexpr const char* kSensor = "config/sensors/kinect_azure_nfov_binned.yaml";
  static constexpr const char* kTag = "convergence_kinect";
};

TEST_F(KinectBunnySeed4, AccelerationStaysInThePlainLoopsMinimum) {
  const CalibrationResult result = Calibrate(datasets_, nominal_, options_);
  const double calibrated = SensorPoseError(truth_, result.model, 500, 1).rms_position_m;
  std::printf("%s after %zu iterations (%d accelerated, %d dropped): %.3f mm\n",
              TerminationName(result.termination), result.iterations.size(), result.accelerated,
              result.acceleration_dropped, calibrated * 1e3);
  EXPECT_EQ(result.termination, Termination::kConverged) << result.message;
  EXPECT_LT(calibrated, 1.5e-3);
}

}  // namespace
}  // namespace selfcal::calib
