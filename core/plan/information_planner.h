// Planning by information: choose the scans of a calibration before the arm
// moves, so that they pin the calibrated parameters down best.
//
//   candidates: the paper-style generator's views or sweeps (core/sim/scan_plan.h, MakeScanPlan):
//     reachable by inverse kinematics within the joint limits, the sensor's origin in free space;
//     a view whose noise-free scan (candidate_scans.h) returns on fewer than `min_coverage` of its
//     rays sees nothing and is rejected, one whose links collide with the scene's obstacles where
//     it stands or along its sweep (sim::MoveIsFree) is never chosen;
//   information: the engine's own normal equations J^T J of every pair of candidates
//     (core/calib/pair_information.h: its matching, rejection and per-pose Jacobians), at the
//     nominal model, which is the solution for noise-free scans taken with it;
//   unobservable: what all candidates together cannot determine (core/calib/covariance.h,
//     FindUnobservable) is named and masked: the planner does not try to pin it down;
//   selection: greedy A-optimal on the predicted sensor position error over the joint space
//     (RMS over the engine's 500 prediction configurations, so coverage of the joint ranges is
//     part of the criterion: a parameter seen only in a corner of the joint space leaves the rest
//     uncertain), with the covariance sigma^2 (H_S + P)^-1 of the chosen set S: H_S the sum over
//     the chosen pairs, sigma the sensor's noise per match, P a weak prior (`prior_m`,
//     `prior_rad` per parameter) so that a direction the chosen scans do not see counts at the
//     prior's size instead of zero. It starts from the best pair and adds the candidate that
//     lowers that most, until the prediction meets `target_m` or `max_scans` is reached;
//   prediction: that, plus what the intrinsics the calibration will hold at the sensor file's
//     values move the estimate by, given their uncertainty (the engine's consider covariance,
//     covariance.h: D Sigma_h D^T, D = (H_S + P)^-1 H_S,eh), which no number of scans removes.
//     Ranking by it instead chose plans better in the median and worse in the worst case
//     (docs/planning.md), so it is reported, not optimized.
//
// The scans' part is that of the naive covariance (every match independent), from noise-free
// scans: it is optimistic against what a calibration's jackknife reports (docs/planning.md).
#pragma once

#include <string>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/pair_information.h"
#include "core/calib/predicted_error.h"
#include "core/model/robot_model.h"
#include "core/plan/candidate_scans.h"
#include "core/sim/scan_plan.h"
#include "core/sim/scene.h"
#include "core/sim/sensor_model.h"
#include "core/util/expected.h"

namespace selfcal::plan {

struct PlannerOptions {
  int max_scans = 28;          // fit scans at most
  int min_scans = 3;           // at least (a calibration's jackknife needs 3)
  double target_m = 0;         // stop once the predicted sensor position RMS is below; 0 = none
  int candidates = 0;          // candidate views; 0 = 3 * max_scans
  int planning_cells = 6000;   // measurements per view for planning (candidate_scans.h)
  double min_coverage = 0.05;  // of a candidate's rays that must return
  double prior_m = 0.05;       // 1 sigma prior per translation parameter
  double prior_rad = 0.05;     // ... per angle parameter
  // The arm's links as capsules of this radius must stay clear of the scene's obstacles and
  // inside its workspace (sim::LinksAreFree); a view whose links collide is never chosen. 0: off.
  double link_radius = 0.07;
  int threads = 0;  // 0 = all cores; the plan does not depend on it

  // False, and *error names the first option out of range, otherwise.
  bool IsValid(std::string* error) const;
};

// The candidates and what the engine's cost learns from each pair of them.
struct CandidateSet {
  RobotModel nominal;                   // with the mask the selection uses (masked removed)
  std::vector<sim::PlannedScan> views;  // every generated fit view (generator index = position)
  std::vector<sim::PlannedScan> validation;  // the generator's validation scans, unchanged
  std::vector<int> sighted;                  // generator indices of the views that see something
  // Generator indices of the views whose links collide with the scene (link_radius): simulated
  // with the rest (a paper-style plan's prediction counts them) but never chosen.
  std::vector<int> colliding;
  calib::PairInformation information;       // over the sighted views (dataset d = sighted[d])
  std::vector<std::string> unobservable;    // FindUnobservable's findings over all candidates
  std::vector<std::string> masked;          // the parameters masked because of them
  std::vector<std::size_t> selection_free;  // into information.free: the parameters kept
  double sigma_m = 0;                       // noise of one match (both ends)
  Thinning thinning;                        // of the sensor, for planning
  double information_factor = 1;            // J^T J scaled from the planning to the sensor
  double seconds = 0;
};

Expected<CandidateSet> MakeCandidates(const RobotModel& nominal, const sim::SensorModel& sensor,
                                      const sim::Scene& scene, const sim::PlanOptions& generator,
                                      const calib::CalibrationOptions& engine,
                                      const PlannerOptions& options,
                                      const PlanProgress& progress = {});

// The prediction the selection uses for the fit views with these generator indices (views
// that see nothing add nothing), over the selection's parameters: the sensor and flange error
// of sigma^2 (H_S + P)^-1 on the engine's prediction configurations.
calib::PredictedError PredictForViews(const CandidateSet& candidates,
                                      const std::vector<int>& generator_indices,
                                      const PlannerOptions& options);

struct InformationPlan {
  sim::ScanPlan plan;                    // the chosen fit scans in order, then the validation ones
  std::vector<int> chosen;               // generator indices, in the order chosen
  std::vector<double> predicted_rms_m;   // the whole prediction after each choice (first: the pair)
  calib::PredictedError predicted;       // of the whole plan
  calib::PredictedError predicted_held;  // the part of it from the held intrinsics
  bool target_met = false;
  double seconds = 0;  // the selection's
};

InformationPlan ChooseScans(const CandidateSet& candidates, const PlannerOptions& options,
                            const PlanProgress& progress = {});

}  // namespace selfcal::plan
