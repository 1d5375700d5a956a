// The validation of a given model, as Calibrate() validates its result: the residuals behind the
// validation RMS, one per match (what the report's histograms show), and the held-out scans'
// registration.
// Matched exactly as Calibrate() validates (pairs touching a validation scan, PairMatcher with
// the options' search, rejection by d_max and f_min), so their RMS is the result's validation RMS
// of that model.
#pragma once

#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/dataset.h"
#include "core/model/robot_model.h"

namespace selfcal::calib {

// Signed point-to-plane residuals [m], (q_i - q_j) . n(q_i), of the validation matches with
// `model`. `scale` is the normalization scale s of the calibration (CalibrationResult::scale_m;
// it only changes rounding); 0 = computed as Calibrate() does, from the first fit scan with
// `model`. Empty when no dataset is a validation scan.
std::vector<float> ValidationResiduals(const std::vector<Dataset>& datasets,
                                       const RobotModel& model, const CalibrationOptions& options,
                                       double scale = 0);

// Every validation scan registered rigidly onto the fit scans at `model`, as Calibrate() does
// for its result (held_out_registration.h); `scale` as above.
HeldOutRegistration RegisterHeldOutScans(const std::vector<Dataset>& datasets,
                                         const RobotModel& model, const CalibrationOptions& options,
                                         double scale = 0);

}  // namespace selfcal::calib
