// Ranges computed by core/sim: the simulated Hokuyo sits on the flange of a simulated robot
// (a scenario file: robot, sensor mount, scene, ground-truth perturbation, seed) whose joint
// positions arrive as a stream (SELFCAL_JOINT_STATE). Every ray is cast from the sensor pose at
// the ray's own true time, with the joints interpolated linearly to it, through the robot's
// true (perturbed) kinematics, exactly as `selfcal simulate` builds them.
//
// A scenario with an `effects:` section (config/scenarios/field/) is served as `selfcal
// simulate` measures it, through core/sim/device_frame.h: the sensor file's Gaussian noise and
// every sensor and robot effect (mixed pixels, range bias with its reflectivity term, incidence
// noise, grazing and dark-surface dropout, intrinsics, joint elasticity, the arm's own links,
// thermal growth, backlash), the scenario's sensor latency and its timing effect (joint states
// that lag the arm; the clock drift is the device's, ClockDriftPpm). The walker and the moved box
// follow the scan markers (SELFCAL_SCAN_MARKER): the walker walks through a scan of its list over
// the time `selfcal simulate` gives that scan of the scenario's plan, from its BEGIN; thermal
// growth counts from the first BEGIN. Without the section the ranges are the ideal ray casts.
#pragma once

#include <deque>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "core/model/kinematics.h"
#include "core/model/robot_model.h"
#include "core/util/expected.h"
#include "protocols/scenario/device_scenario.h"
#include "tools/sim_scip/range_source.h"

namespace selfcal::sim_scip {

class SceneRangeSource final : public RangeSource {
 public:
  static Expected<std::unique_ptr<SceneRangeSource>> Create(const std::string& scenario_path);

  // Joint positions (model order) at host CLOCK_MONOTONIC time [us]; samples older than 10 s
  // before the newest are forgotten. Thread-safe.
  void AddJointState(double host_monotonic_us, std::vector<double> positions);
  // A scan marker at host CLOCK_MONOTONIC time [us]: BEGIN (`begin`) or END of scan
  // `scan_index` of the plan. Thread-safe.
  void AddScanMarker(double host_monotonic_us, int scan_index, bool begin);
  // The device clock's rate error the scenario's timing effect gives [ppm] (0 when it is off).
  double ClockDriftPpm() const;
  // Joint names of the robot model, base to tip (the order AddJointState expects).
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  const RobotModel& truth() const { return scenario_.setup.truth; }

  // Range [m] along the ray of `angle` (rad, in the sensor's xy plane) with the robot at
  // `joints`; +infinity when nothing is hit.
  double RangeAt(std::span<const double> joints, double angle) const;

  void Ranges(const ScanTiming& timing, std::span<std::uint32_t> ranges_mm,
              std::span<std::uint32_t> intensities) override;

 private:
  SceneRangeSource() = default;
  // The joints at `host_us` from the stream: where the arm really is (after backlash, when on).
  bool JointsAt(double host_us, std::vector<double>& joints);
  // Backlash: the arm at `output` follows the joint states, which have since moved monotonically
  // to `joints`, to where it is now (in `joints`); nothing when the effect is off.
  void Play(const std::vector<double>& output, std::vector<double>& joints) const;
  // How far the walker has come through the current scan at `host_us` (0..1).
  double WalkerFraction(double host_us) const;
  // Seconds since the first BEGIN (0 before it): the arm's warm-up for thermal growth.
  double Elapsed(double host_us) const;
  // The ranges [m] (NaN: none) of a request through the field effects, before rounding.
  void FieldRanges(const ScanTiming& timing, std::vector<double>& ranges);

  DeviceScenario scenario_;
  std::vector<JointType> joint_types_;
  std::vector<double> parameters_;
  std::vector<std::string> joint_names_;
  std::mutex mutex_;
  struct Sample {
    double host_us;
    std::vector<double> positions;
    std::vector<double> output;  // where the arm is: the positions through the backlash
  };
  std::deque<Sample> samples_;
  std::vector<double> scan_seconds_;  // per scan of the scenario's plan (for the walker)
  int scan_ = -1;                     // the scan the last BEGIN started
  double scan_begin_us_ = 0;
  double first_begin_us_ = -1;  // < 0: none yet
  std::vector<double> joints_;  // scratch
};

}  // namespace selfcal::sim_scip
