// Field effects: the error sources of real sensors, arms and rooms that the ideal simulator
// leaves out. Each effect is off unless its `enabled` is set (the scenario file's `effects:`
// section sets it); with every effect off the simulator produces today's recordings bit for
// bit. Magnitudes and their sources are in docs/simulation.md ("Field effects").
//
// The functions below are the models themselves, pure and testable on known geometry; the
// simulator (simulator.cc) applies them per cell.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "core/model/robot_model.h"
#include "core/model/sensor_layout.h"
#include "core/sim/ray_caster.h"

namespace selfcal::sim {

// Flying pixels at depth discontinuities: a cell whose neighbour (4-neighbourhood on a camera,
// left and right on a LiDAR rotation or a line profile) differs by more than `min_jump` returns,
// with `probability`, the mix w * own + (1 - w) * neighbour, w uniform in (0, 1): the footprint
// (pixel or beam) straddles both surfaces.
struct MixedPixelEffect {
  bool enabled = false;
  double probability = 0.5;
  double min_jump = 0.02;  // m
};

// Systematic range error added to the measure (LiDAR range, camera and line scanner depth):
// offset + per_metre * measure + incidence * (1 - cos(incidence angle))
//        + warmup_offset * exp(-t / warmup_time_constant), t since the start of the recording.
struct RangeBiasEffect {
  bool enabled = false;
  double offset = 0;                  // m
  double per_metre = 0;               // m per m of measure
  double incidence = 0;               // m at grazing incidence
  double warmup_offset = 0;           // m at t = 0
  double warmup_time_constant = 900;  // s
};

// Noise growing with the angle of incidence: sigma * min(max_factor, 1 / cos^exponent).
struct IncidenceNoiseEffect {
  bool enabled = false;
  double exponent = 1.0;
  double max_factor = 4.0;
};

// No return where the angle of incidence exceeds `max_angle`.
struct GrazingDropoutEffect {
  bool enabled = false;
  double max_angle = 1.31;  // rad (75 deg)
};

// Triangulation and structured light need a second viewpoint: the line scanner's camera sits at
// (0, baseline, 0) beside its laser, a structured-light camera's projector at (baseline, 0, 0)
// beside its camera (sensor frame). A point the second viewpoint cannot see returns nothing.
struct BaselineShadowEffect {
  bool enabled = false;
  double baseline = 0.1;  // m
};

// The sensor's true intrinsics differ from its file: the measure is scaled and offset, and a
// camera's true focal lengths (a line scanner's true fan) are (1 + focal_scale) times the file's.
// The recorded points use the file's rays, as the device's own firmware would.
struct IntrinsicsEffect {
  bool enabled = false;
  double depth_scale = 0;   // relative
  double range_offset = 0;  // m
  double focal_scale = 0;   // relative
};

// Joints deflect under the gravity torque of the links beyond them: q_real = q + tau(q) / k.
// Point masses: link i (the body joint i turns) at the middle between joint i's origin and the
// next joint origin that differs from it (the flange for the last links), the sensor at the
// tool point. Gravity is -z of the base frame.
struct JointElasticityEffect {
  bool enabled = false;
  std::vector<double> stiffness;    // Nm/rad per joint
  std::vector<double> link_masses;  // kg per joint's link
  double sensor_mass = 0;           // kg
};

// Timing: joint states report the position of `joint_lag` seconds ago; the sensor's clock
// runs `clock_drift_ppm` fast, so its stamps run ahead of the truth by drift * t.
struct TimingEffect {
  bool enabled = false;
  double joint_lag = 0;        // s
  double clock_drift_ppm = 0;  // 1e-6
};

// The arm's own links as capsules along the true kinematics (between consecutive distinct joint
// origins, and from the base up to the first), seen by the sensor and occluding the scene.
// Rays that start inside a capsule (the sensor sits on the last link) ignore that capsule.
struct SelfViewEffect {
  bool enabled = false;
  double radius = 0.07;  // m
};

// A person (an upright capsule) that walks from `from` to `to` (foot points) during each listed
// scan, at constant speed from BEGIN to END.
struct WalkerEffect {
  bool enabled = false;
  std::vector<int> scans;
  Eigen::Vector3d from = Eigen::Vector3d::Zero();
  Eigen::Vector3d to = Eigen::Vector3d::Zero();
  double radius = 0.25;  // m
  double height = 1.75;  // m
};

// A box (`size`, bottom centre `position`) that stands in the scene and is moved by `shift`
// before scan `after_scan`.
struct MovedObjectEffect {
  bool enabled = false;
  int after_scan = 0;
  Eigen::Vector3d size = Eigen::Vector3d::Constant(0.2);
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
};

struct FieldEffects {
  MixedPixelEffect mixed_pixels;
  RangeBiasEffect range_bias;
  IncidenceNoiseEffect incidence_noise;
  GrazingDropoutEffect grazing_dropout;
  BaselineShadowEffect baseline_shadows;
  IntrinsicsEffect intrinsics;
  JointElasticityEffect joint_elasticity;
  TimingEffect timing;
  SelfViewEffect self_view;
  WalkerEffect walker;
  MovedObjectEffect moved_object;

  // True when any effect changes what the sensor measures (the per-cell field path).
  bool AnyMeasurementEffect() const;
  bool AnyEnabled() const;
};

// --- Sensor models -------------------------------------------------------------------------

// The systematic error of RangeBiasEffect at `measure`, incidence cosine `cos_incidence`,
// recording time `t`; 0 when disabled.
double RangeBias(const RangeBiasEffect& effect, double measure, double cos_incidence, double t);

// The factor on the noise sigma; 1 when disabled.
double IncidenceNoiseFactor(const IncidenceNoiseEffect& effect, double cos_incidence);

// True when the incidence is too grazing to return.
bool LostAtGrazingAngle(const GrazingDropoutEffect& effect, double cos_incidence);

// Flying pixels on a grid of measures (NaN = no return), `width` x `height`, row-major.
// `uniform(i, k)` gives uniform numbers in (0, 1) addressed by cell and draw (k = 0, 1).
// Returns the new measures; cells without a discontinuity are unchanged.
template <typename Uniform>
std::vector<double> MixPixels(const MixedPixelEffect& effect, const std::vector<double>& measures,
                              int width, int height, const Uniform& uniform);

// --- Robot ---------------------------------------------------------------------------------

// The joint deflections tau / k of JointElasticityEffect, from the joint frames of a
// configuration: `axes[i]` and `origins[i]` of joint i in the base frame, `tool_point` the
// sensor's origin. Sizes must match the effect's vectors.
std::vector<double> GravityDeflection(const JointElasticityEffect& effect,
                                      const std::vector<Eigen::Vector3d>& axes,
                                      const std::vector<Eigen::Vector3d>& origins,
                                      const Eigen::Vector3d& tool_point);

// Joint axes and origins of a configuration in the base frame (joint i's frame after its
// motion), the base frame's origin and the tool point (the sensor's origin).
struct ArmFrames {
  std::vector<Eigen::Vector3d> axes, origins;
  Eigen::Vector3d tool_point = Eigen::Vector3d::Zero();
};
ArmFrames ComputeArmFrames(std::span<const JointType> joint_types, const double* parameters,
                           const double* joint_positions);

// --- Dynamic geometry (the arm, a walker, a moved box) --------------------------------------

struct Capsule {
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double radius = 0;
};

// Distance along the unit `direction` to the first entry into the capsule, +infinity when the
// ray misses it or starts inside it.
double CastCapsule(const Capsule& capsule, const Eigen::Vector3d& origin,
                   const Eigen::Vector3d& direction, Eigen::Vector3d* normal);
// The same for an axis-aligned box.
double CastBox(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& origin,
               const Eigen::Vector3d& direction, Eigen::Vector3d* normal);

// What moves, at one instant: capsules (links, walker) and boxes, in the base frame.
struct DynamicGeometry {
  std::vector<Capsule> capsules;
  std::vector<Eigen::AlignedBox3d> boxes;
  bool empty() const { return capsules.empty() && boxes.empty(); }
  // Nearest entry within `max_distance`; +infinity (normal untouched) when none.
  double Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double max_distance,
              Eigen::Vector3d* normal) const;
};

// The links as capsules of `radius`: base origin to the first joint, then between consecutive
// distinct joint origins, then to the tool point.
std::vector<Capsule> ArmCapsules(const ArmFrames& frames, double radius);

// The walker and the moved box during scan `scan` at `fraction` (0..1) of its BEGIN..END.
void AddSceneMotion(const FieldEffects& effects, int scan, double fraction,
                    DynamicGeometry& geometry);

// --- One ray with the effects (shared by the simulator and the device simulators) ------------

// What a ray returns before noise: the distance along the unit `direction` to the nearest of the
// scene and the moving geometry, and the cosine of incidence there; +infinity on a miss and
// where the return is lost at a grazing angle.
struct RayReturn {
  double distance = std::numeric_limits<double>::infinity();
  double cosine = 1;
};
RayReturn CastFieldRay(const RayCaster& caster, const DynamicGeometry& geometry,
                       const FieldEffects& effects, const Eigen::Vector3d& origin,
                       const Eigen::Vector3d& direction, double reach);

// The clean measure (range or depth) with its systematic errors: range bias and intrinsics.
double SystematicMeasure(const FieldEffects& effects, double measure, double cosine, double t);

// True when the second viewpoint of BaselineShadowEffect (a line scanner's camera, a camera's
// projector) cannot see `point` (base frame) past the scene and the moving geometry.
bool ShadowedFromSecondViewpoint(const RayCaster& caster, const DynamicGeometry& geometry,
                                 const BaselineShadowEffect& effect, SensorLayout layout,
                                 const Eigen::Isometry3d& T_base_sensor,
                                 const Eigen::Vector3d& point);

// Adds the gravity deflection of JointElasticityEffect to the joint positions `q` (nothing when
// the effect is off).
void DeflectJoints(const JointElasticityEffect& effect, std::span<const JointType> joint_types,
                   const double* parameters, double* q);

// --- Template definitions ------------------------------------------------------------------

template <typename Uniform>
std::vector<double> MixPixels(const MixedPixelEffect& effect, const std::vector<double>& measures,
                              int width, int height, const Uniform& uniform) {
  std::vector<double> mixed = measures;
  if (!effect.enabled) return mixed;
  const auto at = [&](int u, int v) {
    return measures[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
                    static_cast<std::size_t>(u)];
  };
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const double own = at(u, v);
      if (!(own == own)) continue;  // NaN: nothing returned here
      double partner = own, jump = effect.min_jump;
      const int du[4] = {-1, 1, 0, 0}, dv[4] = {0, 0, -1, 1};
      for (int n = 0; n < 4; ++n) {
        const int nu = u + du[n], nv = v + dv[n];
        if (nu < 0 || nu >= width || nv < 0 || nv >= height) continue;
        const double other = at(nu, nv);
        if (other == other && std::abs(other - own) > jump) {
          jump = std::abs(other - own);
          partner = other;
        }
      }
      if (partner == own) continue;
      const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
                            static_cast<std::size_t>(u);
      if (uniform(i, 0) >= effect.probability) continue;
      const double w = uniform(i, 1);
      mixed[i] = w * own + (1 - w) * partner;
    }
  }
  return mixed;
}

}  // namespace selfcal::sim
