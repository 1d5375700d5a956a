// Noise-free scans of the planner's candidate views, as the engine's datasets: the simulator
// (core/sim/simulator.h) on the nominal model with every noise off (sensor, encoders, time
// stamps), at a resolution coarse enough to match every pair of candidates in seconds.
//   camera: its one frame, binned; one pose per scan.
//   sweep (LiDAR, line scanner): its lines, thinned along a line and in lines per second; one
//     pose per line, the arm's commanded joints at its measurement time.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/calib/dataset.h"
#include "core/model/robot_model.h"
#include "core/sim/scan_plan.h"
#include "core/sim/scene.h"
#include "core/sim/sensor_model.h"
#include "core/util/expected.h"

namespace selfcal::plan {

using PlanProgress = std::function<void(const std::string& line)>;

// How much coarser than the sensor the planner looks: every `along`-th point of a line (of a
// camera's rows and columns alike) and every `lines`-th line of a sweep.
struct Thinning {
  int along = 1;
  int lines = 1;
};

struct SimulatedViews {
  std::vector<calib::Dataset> datasets;  // of the sighted views
  std::vector<int> sighted;              // their generator indices
  Thinning thinning;
  // The measurements the sensor itself takes in the sighted views per one the datasets keep:
  // what scales their J^T J to the sensor's.
  double measurements_per_kept = 1;
};

// The least thinning that leaves at most `cells` measurements per view: of a camera's grid
// (binned), or of a sweep of `lines` lines, thinned so that its points end about as far apart
// along a line as from line to line (`spacing_ratio`: line-to-line over along-a-line distance
// at the sensor's resolution; 0 = unknown, thinned alike).
Thinning PlanningThinning(const sim::SensorModel& sensor, double lines, double spacing_ratio,
                          int cells);

// `views` simulated with PlanningThinning (a sweep's lines and spacing from the view with the
// median scan time, simulated at the sensor's resolution); a view whose rays return on fewer
// than `min_coverage` of its measurements sees nothing and is left out.
Expected<SimulatedViews> SimulateViews(const RobotModel& nominal, const sim::SensorModel& sensor,
                                       const sim::Scene& scene,
                                       const std::vector<sim::PlannedScan>& views, int cells,
                                       double min_coverage, const PlanProgress& progress);

}  // namespace selfcal::plan
