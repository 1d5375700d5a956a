// Whether the held-out scans' registration offsets (core/calib/held_out_registration.h) track
// the model's actual sensor pose error: for a calibrated MODEL and the simulation's TRUTH, prints
// per validation scan the offset of its rigid registration onto the fit scans next to the actual
// sensor position error at that scan's configuration, then both RMS and the actual error over
// 500 configurations (seed 1, as `selfcal evaluate`). Never run by ctest.
//
// Usage: held_out_check MODEL.yaml TRUTH.yaml SENSOR.yaml RECORDING.lcmlog [FIT_SCANS]
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/validation_residuals.h"
#include "core/model/evaluation.h"
#include "protocols/model_file/model_file.h"
#include "tests/bench/calib/bench_recording.h"

namespace {

using namespace selfcal;
using namespace selfcal::calib;

int Fail(const std::string& message) {
  std::fprintf(stderr, "%s\n", message.c_str());
  return 1;
}

int Run(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr,
                 "usage: %s MODEL.yaml TRUTH.yaml SENSOR.yaml RECORDING.lcmlog [FIT_SCANS]\n",
                 argv[0]);
    return 2;
  }
  auto truth = ReadModelFile(argv[2]);
  if (!truth) return Fail(truth.error().message);
  auto loaded = bench::LoadBenchRecording(argv[1], argv[3], argv[4], argc > 5 ? argv[5] : nullptr);
  if (!loaded) return 1;
  const RobotModel& model = loaded->model.model;
  const std::vector<Dataset>& datasets = loaded->datasets;
  CalibrationOptions options = loaded->options;
  options.threads = 2;
  const HeldOutRegistration registration = RegisterHeldOutScans(datasets, model, options);

  std::printf("scan  matches  offset_mm  angle_deg  actual_mm\n");
  double actual_squared = 0;
  for (const HeldOutOffset& offset : registration.scans) {
    std::vector<double> joints;
    for (const Dataset& dataset : datasets) {
      if (dataset.scan_index != offset.scan_index || !dataset.validation) continue;
      std::vector<double> buffer(dataset.joint_count);
      const double* q = dataset.JointsOfPose(0, buffer.data());
      joints.assign(q, q + dataset.joint_count);
    }
    const std::vector<std::vector<double>> configuration{joints};
    const PoseErrorStats actual = SensorPoseError(truth->model, model, configuration);
    actual_squared += actual.rms_position_m * actual.rms_position_m;
    std::printf("%4d %8zu %10.3f %10.4f %10.3f\n", offset.scan_index, offset.matches,
                offset.position_m * 1e3, offset.angle_rad * 180 / M_PI,
                actual.rms_position_m * 1e3);
  }
  const double n = static_cast<double>(registration.scans.size());
  const PoseErrorStats over_space = SensorPoseError(truth->model, model, 500, 1);
  std::printf(
      "held-out offset RMS %.3f mm, worst %.3f mm; actual at those scans RMS %.3f mm; "
      "actual over 500 configurations RMS %.3f mm\n",
      registration.rms_position_m * 1e3, registration.worst_position_m * 1e3,
      n > 0 ? std::sqrt(actual_squared / n) * 1e3 : 0.0, over_space.rms_position_m * 1e3);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return Run(argc, argv); }
