// The calibration engine: the paper's ICP bundle adjustment (section "Approach", Algorithm 1).
// This is the API the daemon and `selfcal calibrate` call; keep it stable.
//
//   // protocols/recording:
//   auto datasets = selfcal::recording::LoadRecording(log, nominal, sensor, {});
//   auto options = selfcal::recording::CalibrationOptionsFromSensor(sensor);
//   CalibrationResult result = Calibrate(*datasets, nominal, options, progress, &cancel);
//   if (result.usable) WriteModelFile(path, result.model, FormatCalibrationYaml(result));
//
// Never throws for bad data: an unusable or non-converged calibration is data in the result.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "core/calib/dataset.h"
#include "core/calib/held_out_registration.h"
#include "core/calib/intrinsics_choice.h"
#include "core/calib/pose_knots.h"
#include "core/calib/predicted_error.h"
#include "core/model/model_change.h"
#include "core/model/robot_model.h"
#include "core/util/enum_names.h"

namespace selfcal::calib {

// The two choices that separate the fast mode from the paper's way. Every combination is valid;
// `selfcal calibrate --solver` picks both together unless `--search` is given.
//
// How the data association (project / filter / match) finds the matches. Both are exact: the
// fast strategy only skips matches that rejection would remove.
enum class SearchStrategy {
  kFast,       // projection through pose knots (pose_knots.h), a rigid scan's tree in its sensor
               // frame built once, searches bounded by d_max, non-overlapping pairs skipped
  kReference,  // the paper's way: every point along the full chain, base-frame trees rebuilt
               // every iteration, unbounded nearest-neighbour search
};
// The names of these choices, as the command line reads them and results and logs print them.
inline constexpr EnumNames<SearchStrategy, 2> kSearchNames{{
    {SearchStrategy::kFast, "fast"},
    {SearchStrategy::kReference, "reference"},
}};
// How the matches' point-to-plane cost is minimized.
enum class SolverKind {
  kFast,       // own Levenberg-Marquardt on J^T J from per-pose Jacobians (point_to_plane.h)
  kReference,  // Ceres, one full-chain autodiff residual block per match (reference_solver.h)
};
inline constexpr EnumNames<SolverKind, 2> kSolverNames{{
    {SolverKind::kFast, "fast"},
    {SolverKind::kReference, "reference"},
}};
// Which plane a match <q_i, q_j>'s residual c = (q_i - q_j) . n measures against.
enum class CostKind {
  kPaper,      // n = n(q_i), the query's own normal (the paper's cost function)
  kTarget,     // n = n(q_j), the matched point's normal (Chen and Medioni's point-to-plane)
  kSymmetric,  // n = (n(q_i) + n(q_j)) / |...| (Rusinkiewicz 2019, "A symmetric objective
               // function for ICP"): zero for any two points on one sphere (docs/engine.md,
               // deviation 13: measured, the border matches and not the plane bias the cost)
};
inline constexpr EnumNames<CostKind, 3> kCostNames{{
    {CostKind::kPaper, "paper"},
    {CostKind::kTarget, "target"},
    {CostKind::kSymmetric, "symmetric"},
}};
// How a point's normal is estimated (normals.h).
enum class NormalKind {
  kNeighbours,  // the paper's: crosses of the two grid triangles at the point
  kFit,         // a plane fitted to the filter window's points along their view rays
                // (docs/engine.md, deviation 22)
};
inline constexpr EnumNames<NormalKind, 2> kNormalNames{{
    {NormalKind::kNeighbours, "neighbours"},
    {NormalKind::kFit, "fit"},
}};
// How a match's residual c enters the cost (docs/engine.md, deviation 14).
enum class LossKind {
  kSquared,  // c^2, the paper's least squares
  kCauchy,   // iteratively reweighted least squares with Cauchy's kernel: w c^2, the weight
             // w = 1 / (1 + (c / (loss_width sigma))^2) computed from c when the matches are
             // frozen and held fixed during that iteration's solve (robust_loss.h)
};
inline constexpr EnumNames<LossKind, 2> kLossNames{{
    {LossKind::kSquared, "squared"},
    {LossKind::kCauchy, "cauchy"},
}};
// What epsilon bounds: how an ICP iteration's step is measured (docs/engine.md, deviation 18).
enum class StepMeasure {
  kSensor,      // the motion of the sensor pose over the fit scans' poses (sensor_motion.h)
  kParameters,  // |delta k_hat|, the paper's
};
inline constexpr EnumNames<StepMeasure, 2> kStepMeasureNames{{
    {StepMeasure::kSensor, "sensor"},
    {StepMeasure::kParameters, "parameters"},
}};
// What the step is called in messages and progress: "sensor step" or "|delta k|".
const char* StepMeasureLabel(StepMeasure measure);
const char* SearchName(SearchStrategy search);
const char* SolverName(SolverKind kind);
const char* CostName(CostKind cost);
const char* NormalName(NormalKind normals);
const char* LossName(LossKind loss);

struct CalibrationOptions {
  // Table I of the paper, per sensor (config/sensors/*.yaml).
  int filter_n = 2;       // edge/noise filter window radius along rows
  int filter_m = 2;       // ... along columns
  double g_min = 0.75;    // minimum normal overlap in the window
  double d_max = 0.020;   // m: maximum match distance
  double f_min = 0.80;    // minimum normal overlap of a match (cosine)
  double epsilon = 1e-4;  // stop when the step (step_measure) <= epsilon (normalized parameters)
  int i_max = 50;         // maximum ICP iterations
  // DELIBERATE DEVIATION (docs/engine.md, deviation 18): epsilon bounds how far a step moves the
  // sensor, not |delta k_hat| (which a parametric singularity of the MCPC tool transform keeps
  // large), and ICP's fixed-point iteration is accelerated by Anderson's method with this memory
  // (anderson_acceleration.h; 0: the paper's plain loop). Measured on the field Hokuyo: the
  // paper's loop ends at i_max on every seed, this one converges in 11-16 iterations.
  StepMeasure step_measure = StepMeasure::kSensor;
  int acceleration = 5;
  // DELIBERATE DEVIATION (docs/engine.md, deviation 10): also reject a match whose q_j lies on the
  // border of Q_j's coverage (ProjectedCloud::boundary, edge_filter.h). On for line scanners
  // (CalibrationOptionsFromSensor): measured there; a depth camera's noise filter keeps too
  // few points for it (most of Q would be border).
  bool reject_coverage_border = false;
  // DELIBERATE DEVIATION (docs/engine.md, deviation 12): the border that rejection uses is that
  // of the measured surface (MarkSurfaceBoundary, edge_filter.h: no return, the grid's edge, or a
  // depth step the noise cannot make within the filter window grown by one), not that of Q, so
  // that the scattered holes a noisy depth camera's filter leaves are not border. Needs
  // reject_coverage_border; the step is d_max / 2 + 3 sample spacings + 5 sqrt(2) (sigma_abs +
  // sigma_rel * range). Off unless the sensor file asks (border_rule: surface): it removes the
  // noise-free bias, but was worse on one noisy Kinect recording.
  bool surface_border = false;
  double sigma_abs = 0;  // m: the sensor's noise (its file's Table I values)
  double sigma_rel = 0;  // fraction of the range
  // DELIBERATE DEVIATION (docs/engine.md, deviation 19): points on a depth step (a flying pixel,
  // a mixed return, the two sides of the step) are removed before projection: grid neighbours
  // whose difference lies within this angle of the view ray and exceeds 5 sqrt(2) sigma of the
  // noise (flying_pixels.h). 0 = off, the paper's.
  double flying_pixel_angle_deg = 0;
  // DELIBERATE DEVIATION (docs/engine.md, deviation 20): where the robot model gives its links'
  // radius (RobotModel::link_radius), points within that radius plus this margin of a link are
  // removed before matching (link_mask.h), the links placed by the model the calibration starts
  // from. The margin covers that model's error. Without a radius nothing is removed (the paper).
  double link_margin_m = 0.03;
  // Not in the paper (docs/engine.md, deviation 11): the points of Q_i that look for a nearest
  // neighbour are every query_stride-th row and column of its grid (1 = all, as the paper);
  // Q_j's tree keeps every point. For sensors whose images hold far more points than the
  // calibration needs (PhotoNeo: 0.9 M per scan).
  int query_stride = 1;
  // Not in the paper (docs/engine.md, deviation 24), on request: coarse to fine. The ICP loop
  // starts with a query stride of coarse_stride and, each time it converges, halves it, until it
  // converges at query_stride; the result is judged there as without. At most query_stride: off.
  int coarse_stride = 1;
  // Not in the paper (docs/engine.md, deviation 9): scans that move while they measure have their
  // poses' forward kinematics computed at knots no joint turns more than this apart [rad or m], and
  // blended in between (pose_knots.h); about (step^2 / 8) * distance from the turning axis off.
  double knot_max_joint_step = kMaxJointStep;

  SearchStrategy search = SearchStrategy::kFast;
  SolverKind solver = SolverKind::kFast;
  CostKind cost = CostKind::kPaper;
  NormalKind normals = NormalKind::kNeighbours;
  // DELIBERATE DEVIATION (docs/engine.md, deviation 23), on request: with free intrinsics, take
  // the part of the cost that the sensor's noise (sigma_abs, sigma_rel along the rays) adds and
  // the intrinsics change out of the cost of scans taken in one pose each (rigid_pair.h,
  // RayNoise); other scans keep the paper's cost.
  bool ray_noise_correction = false;
  // DELIBERATE DEVIATION (docs/engine.md, deviation 14): a robust loss, its scale the match's
  // noise from sigma_abs and sigma_rel (sigma of the difference of two measurements) times
  // loss_width (2.3849: Cauchy's kernel at 95 % efficiency for Gaussian noise). With a
  // noise-free sensor (both sigmas 0) there is no scale and the loss is the squared one.
  // The default stays the paper's: measured on the small scenario and kinect-bunny's field twin
  // (docs/accuracy.md), cauchy changed the sensor pose error by a few percent either way.
  LossKind loss = LossKind::kSquared;  // measured: cauchy is no better on the Kinect
  double loss_width = 2.3849;
  // Not in the paper (docs/engine.md, deviation 15): also calibrate a compliance per joint,
  // q_real = q + c_j tau_j(q) with tau the gravity torque of the robot model's masses
  // (RobotModel::gravity, core/model/gravity.h). Needs those masses and the fast solver; joints
  // whose gravity torque over the fit scans stays below 0.5 % of the largest stay rigid
  // (joint_correction.h). The result's parameters then end with "A2.compliance" etc. (rad/Nm).
  bool elasticity = false;
  // Not in the paper (docs/engine.md, deviation 16): also calibrate the sensor latency, one
  // parameter per recording (Dataset::recording) in s, starting from the latency the recording
  // interpolated its joints at (Dataset::joint_latency_s, the --latency option); the joints are
  // re-interpolated at every latency (joint_correction.h). Needs the datasets' joint timing
  // (Dataset::pose_utime, joint_states) and the fast solver. A recording scanned at rest keeps
  // its start value and is named poorly observable. The result's parameters then end with
  // "sensor.latency" [s].
  bool estimate_latency = false;
  // Not in the paper (docs/engine.md, deviation 17): also calibrate the sensor's intrinsics
  // (core/calib/sensor_intrinsics.h): a scale and/or an offset of the measure along each ray (a
  // depth camera's or a line scanner's depth, a LiDAR's range) and a depth sensor's focal length
  // (lateral scale). Needs the fast solver and one kind of sensor; a free scale also needs a
  // length of the arm kept (else it is a gauge: refused). `automatic` picks what the sensor
  // and the mask can show: the offset, a depth sensor's focal length, the scale where it is no
  // gauge. The result's parameters then end with "sensor.depth_scale" [1],
  // "sensor.depth_offset" [m] and "sensor.focal_scale" [1] (a LiDAR: "sensor.range_..."), the
  // correction the engine applies.
  IntrinsicsChoice intrinsics;
  bool AnyIntrinsic() const { return intrinsics.Any(); }
  // Sets `intrinsics` from "none", "auto" or a '+'-list of scale, offset and focal (the
  // sensor file's calibrate_intrinsics and the CLI's --intrinsics). Returns what is wrong with
  // `choice`, or an empty string; the options are unchanged on an error.
  std::string ChooseIntrinsics(const std::string& choice);
  std::string IntrinsicsName() const;  // the inverse: "none", "auto" or the '+'-list
  // Not in the paper (docs/engine.md, deviation 21): how uncertain the sensor's intrinsics are
  // where the calibration holds them at the file's values (1 sigma: the measure's scale, its
  // offset [m], the focal length's scale; the sensor file's intrinsics_uncertainty). What that
  // does to the estimate joins its covariance, std_dev and predicted error (a consider
  // covariance, covariance.h): no scan can show an error common to all of them. 0 = exact.
  double intrinsic_scale_sd = 0;
  double intrinsic_offset_sd_m = 0;
  double intrinsic_focal_sd = 0;
  int threads = 0;                // 0 = all cores; results are identical for any count
  int lm_max_iterations = 20;     // Levenberg-Marquardt iterations per ICP iteration
  std::size_t min_matches = 100;  // fewer valid matches in an iteration = not usable

  // True when every option is in its range. Otherwise false, and *error (when not null) names
  // the first option out of range, its value and the range, e.g. "d_max = -0.02 m, must be
  // positive". Calibrate() checks it first; callers may check earlier to fail before loading.
  bool IsValid(std::string* error) const;
};

enum class Termination {
  kConverged,      // the step <= epsilon
  kMaxIterations,  // i_max reached
  kCancelled,      // *cancel became true
  kTooFewMatches,  // the scans do not overlap enough (see message)
  kSolverFailed,   // non-finite cost or parameters
  kInvalidInput,   // datasets inconsistent with the model (see message)
};
const char* TerminationName(Termination termination);

struct IterationReport {
  int iteration = 0;              // from 1
  std::size_t valid_matches = 0;  // after rejection
  double rms_before_m = 0;        // point-to-plane RMS of this iteration's matches, before LM
  double rms_after_m = 0;         // ... after LM
  double delta = 0;               // |delta k_hat|
  double step = 0;                // the step as the stop measures it (step_measure)
  int lm_iterations = 0;          // Levenberg-Marquardt steps of this iteration's solve
  double seconds = 0;             // wall time of the iteration
  double matching_seconds = 0;    // ... of it: projection, normals, filter, matching, rejection
  double noise_fraction = 0;      // share of the expected ray noise taken out (0: no correction)
};

struct ValidationReport {
  bool available = false;  // false when the recording has no validation scan
  std::size_t matches_before = 0, matches_after = 0;
  double rms_before_m = 0, rms_after_m = 0;  // point-to-plane RMS on validation matches
};

struct ParameterReport {
  std::string name;          // ParameterName(), e.g. "A2->A3.beta", or "A2.compliance"
  double nominal = 0;        // rad or m (compliance: rad/Nm)
  double calibrated = 0;     // rad or m (compliance: rad/Nm)
  double std_dev = 0;        // rad or m: the jackknife over scans (covariance.h)
  double naive_std_dev = 0;  // rad or m: sigma^2 (J^T J)^-1, every match independent
};

struct CalibrationResult {
  RobotModel model;  // the calibrated model (the nominal one when nothing could be fitted)
  Termination termination = Termination::kInvalidInput;
  std::string message;  // why it stopped, in words
  bool converged = false;
  // Finite, fitted and stopped by epsilon or i_max. Whether it is good enough to install is the
  // acceptance gate's decision (daemon/gate.h), which also looks at the validation scans.
  bool usable = false;
  std::vector<IterationReport> iterations;
  double runtime_s = 0;
  double scale_m = 0;  // the normalization scale s
  std::size_t fit_scans = 0, validation_scans = 0, points = 0;
  std::size_t points_on_links = 0;  // removed as the arm's own links (link_mask.h)
  ValidationReport validation;
  // How far each validation scan must move to fit the fit scans at the calibrated model: the
  // model's pose error where it was not fitted, including what no parameter can express.
  HeldOutRegistration held_out;
  std::vector<ParameterReport> parameters;     // the calibrated (unmasked) parameters
  std::vector<std::string> poorly_observable;  // "name: reason", from the normal matrix
  // Calibrated parameters (or combinations) the scans cannot determine although they move the
  // sensor pose: "names: not observable from these scans" (covariance.h). Empty = all observed.
  std::vector<std::string> unobservable;
  Eigen::MatrixXd covariance;  // over `parameters`, SI (m, rad, rad/Nm); diagonal = std_dev^2
  // The same from the scans alone (the jackknife), without what the calibration holds at assumed
  // values (deviation 21), which errs alike in two sessions with the same sensor.
  Eigen::MatrixXd covariance_of_scans;
  std::size_t jackknife_scans = 0;  // fit scans of the jackknife; 0 = the naive covariance
  PredictedError predicted;         // the sensor pose error the covariance predicts
  PredictedError predicted_naive;   // ... that sigma^2 (J^T J)^-1 would predict (for comparison)
  // The part of `predicted` that the uncertainty of what the calibration holds at assumed values
  // accounts for (intrinsic_*_sd, the robot file's compliance_sd); samples 0 = none held.
  PredictedError predicted_held;
  SearchStrategy search = SearchStrategy::kFast;
  SolverKind solver = SolverKind::kFast;
  StepMeasure step_measure = StepMeasure::kSensor;
  int accelerated = 0;           // points taken by Anderson acceleration
  int acceleration_dropped = 0;  // ... of them dropped by its safeguard
  int threads = 1;
  // What changed against the model the calibration started from (the installed one, for the
  // daemon), judged against the covariance (core/model/model_change.h). Valid when fitted.
  ModelChange change;
  bool change_known = false;
};

// Where a progress report comes from, as in Algorithm 1 (plus the steps around the loop).
enum class CalibrationStage { kValidation, kMatching, kSolving, kIterationDone, kCovariance };
const char* StageName(CalibrationStage stage);  // "validation", "matching", ...

struct CalibrationProgress {
  int iteration = 0;  // 0 = before the first iteration
  int max_iterations = 0;
  CalibrationStage stage = CalibrationStage::kValidation;
  std::size_t valid_matches = 0;
  double delta = 0;  // kIterationDone: the step as the stop measures it (step_measure)
};
using ProgressCallback = std::function<void(const CalibrationProgress&)>;

// Calibrates the parameters of `nominal` selected by nominal.mask from `datasets` (fit and
// validation scans; validation scans are never fitted). `cancel` may be null.
CalibrationResult Calibrate(const std::vector<Dataset>& datasets, const RobotModel& nominal,
                            const CalibrationOptions& options,
                            const ProgressCallback& progress = {},
                            const std::atomic<bool>* cancel = nullptr);
// The same on datasets the caller gives up: with intrinsics the engine corrects their points in
// place rather than in a copy of every scan (a LiDAR's copy would hold its per-point joints
// twice). Their points are left as the engine last corrected them.
CalibrationResult Calibrate(std::vector<Dataset>&& datasets, const RobotModel& nominal,
                            const CalibrationOptions& options,
                            const ProgressCallback& progress = {},
                            const std::atomic<bool>* cancel = nullptr);

}  // namespace selfcal::calib
