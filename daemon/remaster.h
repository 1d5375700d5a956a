// Quick remastering (docs/engine.md "Quick remastering"), as `selfcal calibrate --mode remaster`
// and selfcald's remaster plans (docs/daemon.md "Quick remastering") both run it: the engine starts
// from the installed model with only RemasterMask free (core/model/joint_offsets.h), and the
// answer is the zero offset per axis as a controller takes it, against the installed model.
#pragma once

#include <string>

#include "core/model/joint_offsets.h"
#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "daemon/config.h"

namespace selfcal::daemon {

// `installed` with the mask of a remastering: the joints' zero offsets and the sensor mount.
Expected<RobotModel> RemasterStart(const RobotModel& installed);

// Whether a result's `calibration:` section (YAML text) is a remastering's: it holds the
// `remaster:` section that DescribeRemaster() adds, as `selfcal calibrate --mode remaster` and
// selfcald's remaster sessions write it. Errors: the text is not YAML (the message says where).
Expected<bool> IsRemastering(const std::string& calibration_yaml);

// The model the gate judges a result against: the one the engine started from. For a
// remastering that is RemasterStart(installed), whose mask is what the engine could move (the
// gate refuses a result that moved anything else); otherwise `installed` as it is. selfcald and
// `selfcal calibrate` judge against their engine's start, and `selfcal report` re-judges a result
// file through this, so its gate section decides as they did: against the file's own mask a
// remastering's result that moved a link length would pass there and be refused here.
Expected<RobotModel> JudgedAgainst(const RobotModel& installed,
                                   const std::string& calibration_yaml);

// The gate's settings for judging a remastering: the site's, without the improvement margin
// (min_improvement). A remastering corrects zero offsets of a fraction of a degree, which barely
// move the validation residual at a sensor's noise (0.5 deg on A4 of the demo twin: 8.197 ->
// 8.183 mm), so a margin on that residual refuses every remastering. The other rules stay:
// converged, validation not worse, predicted error within the bound, plausible changes, nothing
// but the remastering's parameters moved.
AcceptanceConfig RemasterAcceptance(AcceptanceConfig site);

struct RemasterCorrections {
  JointOffsetFit fit;  // FitJointOffsets(installed, calibrated)
  // Printed lines: the header, one line per joint in degrees (mm for a prismatic joint), the mount.
  std::string text;
  // `remaster:` for the result's calibration: section (docs/formats.md "Result file").
  std::string yaml;
  // One line for the result message and the history: "zero offsets to add to the measured
  // position: A2 +0.0012 deg, ..., A6 -0.0005 deg; sensor mount 0.120 mm, 0.0040 deg".
  std::string summary;
};

// The corrections of `calibrated` against `installed`; `against` names the installed model in
// the text ("the --robot model", "the installed model").
RemasterCorrections DescribeRemaster(const RobotModel& installed, const RobotModel& calibrated,
                                     const std::string& against);

}  // namespace selfcal::daemon
