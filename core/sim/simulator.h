// Runs a scan plan on the true robot model in a scene and produces what the robot's drivers
// would publish: joint states (encoder noise, host-time jitter), sensor frames (ray casting,
// Gaussian noise, NaN gaps) and scan markers. Times are integer microseconds since the start of
// the recording; protocols/scenario turns this into LCM messages.
//
// Timing of a scan, per docs/recording.md: BEGIN, then the sensor's messages, then END. A sensor
// message stamped s was measured at s + latency (ray i of a LiDAR rotation at s + latency +
// i * time_per_ray), so an engine given the same latency interpolates the joint states to the
// true measurement time.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/model/robot_model.h"
#include "core/sim/field_effects.h"
#include "core/sim/motion.h"
#include "core/sim/ray_caster.h"
#include "core/sim/scan_plan.h"
#include "core/sim/sensor_model.h"

namespace selfcal::sim {

struct RecordingOptions {
  double joint_rate_hz = 200;      // 200 Hz like Drake's IIWA_STATUS, 1000 Hz like FRI
  double encoder_noise = 2e-5;     // rad (or m), Gaussian sigma of the measured joint positions
  double timestamp_jitter = 5e-5;  // s, Gaussian sigma of the joint states' host time stamps
  double latency = 0;              // s, sensor stamp = measurement time - latency
  double settle_time = 0.2;        // s held still before and after every scan
  double transit_fraction = 0.5;   // of each joint's velocity/acceleration limit between scans
  double stationary_hold = 0.1;    // s between BEGIN and END of a stationary (camera) scan
  std::uint64_t seed = 1;
  FieldEffects effects;  // all off: the ideal world, today's recordings bit for bit
};

struct SimJointState {
  std::int64_t stamp_us = 0;         // host time of the sample, with jitter
  std::int64_t device_stamp_us = 0;  // the controller's clock: the ideal sample time
  std::vector<double> positions;     // measured: true + encoder noise
  std::vector<double> velocities;    // true
};

struct SimMarker {
  std::int64_t stamp_us = 0;
  bool begin = true;
  ScanPurpose purpose = ScanPurpose::kFit;
  int scan_index = 0;
};

struct SimFrame {
  std::int64_t stamp_us = 0;         // message time (first ray of a LiDAR rotation)
  std::int64_t device_stamp_us = 0;  // true measurement time on the sensor's clock
  std::int64_t counter = 0;          // frame / profile / rotation counter of the sensor
  std::vector<float> ranges;         // LiDAR: metres along each ray, NaN = no return
  std::vector<Eigen::Vector3f>
      points;  // line scanner (y = 0) and cameras, sensor frame, NaN = none
};

// Everything in one time window: the move to scan k, scan k, and the settling after it.
struct SimSegment {
  int scan_index = 0;
  std::int64_t start_us = 0, end_us = 0;
  std::vector<SimJointState> joint_states;
  std::vector<SimMarker> markers;
  std::vector<SimFrame> frames;
};

class Simulator {
 public:
  // `truth` includes the sensor mount in its tool. `caster` must outlive the simulator.
  Simulator(RobotModel truth, SensorModel sensor, const RayCaster& caster, ScanPlan plan,
            RecordingOptions options);

  int SegmentCount() const { return static_cast<int>(plan_.scans.size()); }
  // Deterministic: the same segment whatever the thread count or the order of calls.
  SimSegment Segment(int k) const;
  // Total duration [s] of the recording.
  double Duration() const { return timeline_.end_time(); }

  // The true sensor pose at time t [s since the start of the recording].
  Eigen::Isometry3d TrueSensorPose(double t) const;
  // The arm's commanded joint positions at time t: what noise-free encoders read without the
  // field effects.
  std::vector<double> CommandedJoints(double t) const;
  // From the start of the recording to scan k's BEGIN marker [s].
  double ScanBegin(int k) const;
  // From scan k's BEGIN to its END marker [s].
  double ScanSeconds(int k) const;

 private:
  struct ScanTiming {
    std::int64_t segment_start_us, begin_us, end_us, segment_end_us;
  };
  // Message stamps of the frames of one scan; `period_us` between frames.
  std::vector<std::int64_t> FrameStamps(const ScanTiming& timing, std::int64_t& period_us) const;
  void SimulateFrames(int k, const ScanTiming& timing, std::vector<SimFrame>& frames) const;
  // Pass 1 of SimulateFieldFrame: per cell the clean measure with its systematic errors and the
  // cosine of incidence (NaN where nothing returns).
  void MeasureFieldCells(int k, double measured, std::uint64_t base,
                         const DynamicGeometry& geometry, std::vector<double>& measures,
                         std::vector<double>& cosines) const;
  // The frame's cells through the measurement effects of options_.effects.
  void SimulateFieldFrame(int k, const ScanTiming& timing, double measured, std::uint64_t base,
                          SimFrame& frame) const;
  // Pass 2: unit noise per cell of the frame whose first cell is `base` (speckle-correlated
  // along a line, otherwise independent).
  std::vector<double> CellNoise(int k, std::uint64_t base) const;
  // The true model's flat parameters at t: the truth, grown by thermal_growth when it is on
  // (then held in `storage`).
  const double* TrueParameters(double t, std::vector<double>& storage) const;
  // The arm's true configuration at t (backlash and joint elasticity included) and its sensor
  // pose, with the parameters of TrueParameters.
  void TrueConfiguration(double t, const double* parameters, double* q) const;
  Eigen::Isometry3d PoseOf(const double* q, const double* parameters) const;
  // True when the second viewpoint (baseline_shadows) cannot see `point`.
  bool Shadowed(const Eigen::Isometry3d& T_base_sensor, const Eigen::Vector3d& point,
                const DynamicGeometry& geometry) const;

  RobotModel truth_;
  std::vector<JointType> joint_types_;
  std::vector<double> truth_parameters_;
  SensorModel sensor_;
  std::vector<Eigen::Vector3d> rays_;       // the sensor file's rays: how points are recorded
  std::vector<Eigen::Vector3d> true_rays_;  // the rays it really casts (intrinsics effect)
  const RayCaster& caster_;
  ScanPlan plan_;
  RecordingOptions options_;
  Timeline timeline_;
  std::vector<std::vector<double>> backlash_starts_;  // joint outputs at each move's start
  std::vector<ScanTiming> timings_;
};

}  // namespace selfcal::sim
