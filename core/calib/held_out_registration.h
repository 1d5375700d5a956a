// How far each held-out (validation) scan must move, as a rigid body, to fit the fit scans.
//
// The validation RMS compares the held-out scans with the fit scans through point-to-plane
// residuals, which the sensor's noise dominates: on a depth camera with 1-2 mm of noise a 5 mm
// pose error moves that RMS by a few percent. Registering each held-out scan rigidly onto the
// fit scans (point-to-plane ICP of its 6 pose parameters, the fit scans fixed at the calibrated
// model) measures the pose error itself, at a configuration the calibration never saw: the
// offset of its sensor origin is what the model gets wrong there, relative to the fit scans. It
// sees the error that no parameter of the model can express (a deflection that depends on the
// configuration), which a covariance of the parameters cannot, and it averages the noise over
// every point of the scan.
//
// It does not see an error common to every scan (the fit scans are its reference), and a scene
// that does not pin a scan down in some direction (one plane) leaves that direction's offset
// near zero.
#pragma once

#include <cstddef>
#include <vector>

#include "core/calib/dataset.h"
#include "core/calib/projection.h"

namespace selfcal::calib {

struct HeldOutOffset {
  int scan_index = 0;       // the recording's scan_index of the validation scan
  std::size_t matches = 0;  // point-to-plane matches of the last registration step
  double position_m = 0;    // how far the registration moves the scan's sensor origin
  double angle_rad = 0;     // ... and turns the scan
};

struct HeldOutRegistration {
  std::vector<HeldOutOffset> scans;  // every validation scan with enough matches, in order
  double rms_position_m = 0;         // RMS of scans[].position_m
  double worst_position_m = 0;
};

// `clouds`: every dataset projected, with normals and the noise/edge filter, at the calibrated
// model (PairMatcher::Prepare), in the normalized units of `scale`; consumed: each fit scan's
// cloud is freed as soon as the reference map holds its points. Matches are searched within
// `d_max_m` and kept when the normals agree to `f_min` (a cosine), as the engine matches; with
// `reject_border`, not when the fit scan's point is on the border of its coverage
// (ProjectedCloud::boundary; docs/engine.md, deviation 10).
HeldOutRegistration RegisterHeldOutScans(const std::vector<Dataset>& datasets,
                                         std::vector<ProjectedCloud>&& clouds, double d_max_m,
                                         double f_min, bool reject_border, double scale,
                                         int threads);

}  // namespace selfcal::calib
