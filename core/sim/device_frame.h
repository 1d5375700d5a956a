// One frame as a device simulator serves it (selfcal-sim-scip, the fake GigE camera, the OpenNI2
// plugin, the fake Wenglor library): the scene, and the arm where it sees itself, cast along the
// device's true rays from the sensor pose on the true arm, with the field effects a device can
// show without knowing the scan plan (field_effects.h: mixed pixels, range bias with its warm-up on
// the device clock and its reflectivity term, incidence noise, grazing and dark-surface dropout,
// baseline shadows, multipath, intrinsics, joint elasticity, the arm's links), then the sensor
// file's Gaussian noise, correlated along the line with speckle; the walker and the moved box for
// a device that knows which scan of the plan it serves (Moving), thermal growth for one that knows
// how long the recording has run (SensorPose). Backlash and the timing effects act on the joint
// stream and the clocks, which the device simulators handle themselves.
//
// Two passes, as in simulator.cc: Cast (the ray casts, which a camera standing still computes
// once) and Measure (the systematic errors at the device time, flying pixels and noise, per
// frame). The same frame key gives the same frame.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "core/model/robot_model.h"
#include "core/sim/field_effects.h"
#include "core/sim/ray_caster.h"
#include "core/sim/sensor_model.h"

namespace selfcal::sim {

// What the sensor really is when its intrinsics differ from its file: wider or narrower rays.
SensorModel TrueSensorModel(SensorModel sensor, const IntrinsicsEffect& effect);

// Pass 1 of a frame, per cell: the distance along the ray in units of the ray's length (the
// range for unit rays, the depth z for rays scaled to z = 1), NaN where nothing returns, and the
// cosine of incidence there; the distance along the ray [m] and the albedo of the surface hit
// (for the dark-surface dropout and the reflectivity bias).
struct CellReturns {
  std::vector<double> measures;
  std::vector<double> cosines;
  std::vector<double> distances;
  std::vector<double> albedos;
};

class DeviceFrameCaster {
 public:
  // `truth`: the true arm with the sensor mount in its tool. `sensor`: the sensor file's model
  // (layout, rays, noise, view range). `seed`: the scenario's. `caster` must outlive this.
  DeviceFrameCaster(const RayCaster& caster, const RobotModel& truth, SensorModel sensor,
                    FieldEffects effects, std::uint64_t seed);

  const FieldEffects& effects() const { return effects_; }
  const SensorModel& sensor() const { return sensor_; }
  // The sensor file's rays (a point is measure * ray) and the rays the device really casts.
  const std::vector<Eigen::Vector3d>& rays() const { return rays_; }
  const std::vector<Eigen::Vector3d>& true_rays() const { return true_rays_; }
  // The factor on the file's focal length (on a fan or LiDAR angle: its inverse).
  double FocalFactor() const;

  // T_base_sensor at joint positions `q` (model order) of the true arm, the joints deflected
  // under gravity when joint elasticity is on, the links grown `elapsed` seconds into the
  // recording when thermal growth is on.
  Eigen::Isometry3d SensorPose(std::span<const double> q, double elapsed = 0) const;
  // The arm's links at `q` (deflected likewise); empty unless self_view is on.
  DynamicGeometry ArmLinks(std::span<const double> q) const;
  // What moves when the device serves scan `scan` of the scenario's plan at `fraction` (0..1) of
  // it: the arm's links at `q`, the walker and the moved box (AddSceneMotion), as `selfcal
  // simulate` places them.
  DynamicGeometry Moving(std::span<const double> q, int scan, double fraction) const;

  // Pass 1 with one pose for every cell of a grid `width` cells wide (a camera frame, a line
  // profile): rows in parallel. Multipath lengthens the measures here, since it depends only on
  // the geometry.
  CellReturns Cast(std::span<const Eigen::Vector3d> rays, int width,
                   const Eigen::Isometry3d& T_base_sensor, const DynamicGeometry& geometry) const;
  // Pass 1 with a pose per cell (a LiDAR on an arm that moves during the rotation; one row), in
  // order.
  CellReturns Cast(std::span<const Eigen::Vector3d> rays,
                   const std::function<Eigen::Isometry3d(std::size_t)>& T_base_sensor_of_cell,
                   const DynamicGeometry& geometry) const;

  // Pass 2 on a `width` x `height` grid: returns lost on dark surfaces, range bias and
  // intrinsics at `device_time` [s on the device's clock since it started], flying pixels, then
  // the noise (grown with incidence; a line scanner's correlated along the line with speckle);
  // NaN outside the view range. Random numbers are keyed by (seed, `frame_key`).
  std::vector<double> Measure(const CellReturns& cells, int width, int height, double device_time,
                              std::uint64_t frame_key) const;

 private:
  // Where each cell's ray hit, kept for the multipath pass only.
  struct Hits {
    std::vector<Eigen::Vector3d> points, normals;
    std::vector<char> valid;
  };
  Hits NoHits(std::size_t cells) const;
  void CastCell(std::size_t i, const Eigen::Vector3d& ray, const Eigen::Isometry3d& T,
                const DynamicGeometry& geometry, CellReturns& out, Hits& hits) const;
  // Adds MultipathGrid's excess along the rays of a `width`-wide grid; nothing when it is off.
  void AddMultipath(std::span<const Eigen::Vector3d> rays, int width,
                    const DynamicGeometry& geometry, const Hits& hits, CellReturns& out) const;
  // The unit noise of a frame's cells (Measure's last step).
  std::vector<double> UnitNoise(std::size_t cells, std::uint64_t frame_key) const;

  const RayCaster& caster_;
  std::vector<JointType> joint_types_;
  std::vector<double> parameters_;
  SensorModel sensor_;
  FieldEffects effects_;
  std::uint64_t seed_;
  std::vector<Eigen::Vector3d> rays_, true_rays_;
};

}  // namespace selfcal::sim
