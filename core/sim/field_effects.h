// Field effects: the error sources of real sensors, arms and rooms that the ideal simulator
// leaves out. Each effect is off unless its `enabled` is set (the scenario file's `effects:`
// section sets it); with every effect off the simulator produces today's recordings bit for
// bit. Magnitudes and their sources are in docs/simulation.md ("Field effects").
//
// The functions below are the models themselves, pure and testable on known geometry; the
// simulator (simulator.cc) applies them per cell.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "core/model/arm_capsules.h"
#include "core/model/gravity.h"
#include "core/model/robot_model.h"
#include "core/model/sensor_layout.h"
#include "core/sim/ray_caster.h"

namespace selfcal::sim {

// Flying pixels at depth discontinuities: a cell whose neighbour (4-neighbourhood on a camera,
// left and right on a LiDAR rotation or a line profile) is off the surface the cell lies on by
// more than `min_jump` returns, with `probability`, the mix w * own + (1 - w) * neighbour, w
// uniform in (0, 1): the footprint (pixel or beam) straddles both surfaces. "Off the surface":
// farther than min_jump both from the cell's measure and from the continuation of the cell and
// its opposite neighbour (linear in 1 / measure), so that a surface seen at a grazing angle, whose
// samples are far apart but continuous, is not mixed: a footprint on one surface returns that
// surface.
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
  double reflectivity = 0;            // m on a black surface (albedo 0), 0 on a white one (1)
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

// Joints deflect under the gravity torque of the links beyond them: q_real = q + tau(q) / k,
// tau the point-mass gravity torque of core/model/gravity.h (GravityTorques), the one model the
// engine's compliance parameters use too.
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

// Thermal growth of the arm: every translation of the true model (the base column, the links,
// the flange and the sensor bracket) grows by expansion * dT(t), dT(t) = temperature_rise *
// (1 - exp(-t / time_constant)), t since the start of the recording: the arm warms up from the
// first scan to the last.
struct ThermalGrowthEffect {
  bool enabled = false;
  double expansion = 23e-6;     // 1/K (aluminium)
  double temperature_rise = 3;  // K after warming up
  double time_constant = 600;   // s
};

// Backlash (lost motion) of the gears. The encoders measure the input (motor) side; the output
// stays put until the input is more than angle / 2 away and then follows at that distance (the
// play operator), so after a motion the output lags the input by angle / 2 and the lag changes
// sign on reversal. The output starts centred on the input.
struct BacklashEffect {
  bool enabled = false;
  double angle = 2e-4;  // rad (or m), the full play of every joint
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

// Multipath in concave corners (time-of-flight): light that reaches a point by way of another
// nearby surface returns with a longer path and pulls the measured range longer. The excess is
// 2 * amplitude * f along the ray, f the cosine-weighted fraction of the hemisphere around the
// hit (about its normal, towards the sensor) that meets another surface within `radius`,
// weighted by that surface's albedo: `amplitude` on the crease of a right-angled corner (f =
// 1/2), falling to 0 at `radius` from it and on a plane. `samples` fixed directions.
struct MultipathEffect {
  bool enabled = false;
  double amplitude = 0.005;  // m
  double radius = 0.1;       // m
  int samples = 16;
};

// Dark surfaces and long ranges return too little light: the relative returned power
// s = albedo * cos(incidence) / range^2 [1/m^2] is lost with probability 1 - s / threshold
// where it is below `threshold` (range in m, along the ray).
struct DarkDropoutEffect {
  bool enabled = false;
  double threshold = 0.005;  // 1/m^2
};

// Speckle in laser triangulation (line scanners only): the centre of the imaged laser line
// wanders with the speckle pattern, so the depth noise of neighbouring points is correlated.
// With the effect on, the line scanner's Gaussian noise (the sensor file's sigma) has the
// autocorrelation exp(-(lag / correlation_length)^2) along the line, lag in points.
struct SpeckleEffect {
  bool enabled = false;
  double correlation_length = 3;  // points
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
  MultipathEffect multipath;
  DarkDropoutEffect dark_dropout;
  SpeckleEffect speckle;
  ThermalGrowthEffect thermal_growth;
  BacklashEffect backlash;

  // True when any effect changes what the sensor measures (the per-cell field path).
  bool AnyMeasurementEffect() const;
  bool AnyEnabled() const;
};

// --- Sensor models -------------------------------------------------------------------------

// The systematic error of RangeBiasEffect at `measure`, incidence cosine `cos_incidence`,
// recording time `t` on a surface of `albedo`; 0 when disabled.
double RangeBias(const RangeBiasEffect& effect, double measure, double cos_incidence, double t,
                 double albedo = 1);

// The factor on the noise sigma; 1 when disabled.
double IncidenceNoiseFactor(const IncidenceNoiseEffect& effect, double cos_incidence);

// True when the incidence is too grazing to return.
bool LostAtGrazingAngle(const GrazingDropoutEffect& effect, double cos_incidence);

// True when a return of `albedo`, incidence cosine `cosine` and `range` [m] along the ray is
// lost to DarkDropoutEffect, `uniform` a number uniform in (0, 1) drawn for the cell.
double ReturnedSignal(double albedo, double cosine, double range);
bool LostOnDarkSurface(const DarkDropoutEffect& effect, double albedo, double cosine, double range,
                       double uniform);

// Unit-variance noise of `n` cells along a line with SpeckleEffect's correlation:
// `gaussian(j)`, j in [0, SpeckleSupport(effect) + n), gives independent standard normal
// numbers, smoothed by a Gaussian kernel of width correlation_length / 2 (the autocorrelation of
// the result is then exp(-(lag / correlation_length)^2)).
int SpeckleSupport(const SpeckleEffect& effect);
template <typename Gaussian>
std::vector<double> SpeckleNoise(const SpeckleEffect& effect, int n, const Gaussian& gaussian);

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

// Joint axes and origins of a configuration in the base frame: core/model/gravity.h.
using ArmFrames = JointFrames;
inline ArmFrames ComputeArmFrames(std::span<const JointType> joint_types, const double* parameters,
                                  const double* joint_positions) {
  return ComputeJointFrames(joint_types, parameters, joint_positions);
}

// The factor (1 + expansion * dT(t)) of ThermalGrowthEffect on every translation; 1 when off.
double ThermalScale(const ThermalGrowthEffect& effect, double t);
// Scales the translations of the flat parameters (robot_model.h) of a `joint_count` chain.
void GrowLinks(const ThermalGrowthEffect& effect, double t, std::size_t joint_count,
               double* parameters);

// One step of the play operator of BacklashEffect: the output after the input moved
// monotonically to `input` from where the output was `output`.
double PlayOutput(double output, double input, double angle);

// --- Dynamic geometry (the arm, a walker, a moved box) --------------------------------------

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
  double albedo = 1;                                  // of the surface hit (scene key)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, facing the sensor
};
RayReturn CastFieldRay(const RayCaster& caster, const DynamicGeometry& geometry,
                       const FieldEffects& effects, const Eigen::Vector3d& origin,
                       const Eigen::Vector3d& direction, double reach);

// The range excess [m] of MultipathEffect at `point` on a surface of unit `normal` (facing the
// sensor); 0 when disabled.
double MultipathExcess(const MultipathEffect& effect, const RayCaster& caster,
                       const DynamicGeometry& geometry, const Eigen::Vector3d& point,
                       const Eigen::Vector3d& normal);

// The node spacing of MultipathGrid in `selfcal simulate` and the device simulators alike.
constexpr int kMultipathGridStep = 8;

// MultipathExcess over a frame's grid of hits (row-major, `width` x `height`; `valid[i]` 0
// where nothing returned), cheaply: exact on every `step`-th row and column (the nodes), and
// bilinear between those of the four nodes around a cell that lie on the cell's tangent plane
// (within radius / 20: across a crease or an edge they do not); exact where none does. The
// excess varies over the radius (tens of pixels), so the interpolation costs little accuracy.
// Zeros when disabled.
std::vector<double> MultipathGrid(const MultipathEffect& effect, const RayCaster& caster,
                                  const DynamicGeometry& geometry, int width, int height,
                                  const std::vector<Eigen::Vector3d>& points,
                                  const std::vector<Eigen::Vector3d>& normals,
                                  const std::vector<char>& valid, int step);

// The clean measure (range or depth) with its systematic errors: range bias and intrinsics.
double SystematicMeasure(const FieldEffects& effects, double measure, double cosine, double t,
                         double albedo = 1);

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
        if (!(other == other)) continue;
        const int ou = u - du[n], ov = v - dv[n];
        const bool inside = ou >= 0 && ou < width && ov >= 0 && ov < height;
        const double opposite = inside ? at(ou, ov) : own;
        // Linear in the inverse measure: exact for a plane seen by a pinhole camera.
        const double inverse = opposite == opposite ? 2 / own - 1 / opposite : 1 / own;
        const double continued =
            inverse > 0 ? 1 / inverse : std::numeric_limits<double>::infinity();
        const double off = std::min(std::abs(other - own), std::abs(other - continued));
        if (off > jump) {
          jump = off;
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

template <typename Gaussian>
std::vector<double> SpeckleNoise(const SpeckleEffect& effect, int n, const Gaussian& gaussian) {
  const int h = SpeckleSupport(effect) / 2;
  const double width = 0.5 * effect.correlation_length;
  std::vector<double> kernel(static_cast<std::size_t>(2 * h + 1));
  double norm = 0;
  for (int k = -h; k <= h; ++k) {
    const double w = std::exp(-0.5 * k * k / (width * width));
    kernel[static_cast<std::size_t>(k + h)] = w;
    norm += w * w;
  }
  norm = std::sqrt(norm);
  std::vector<double> white(static_cast<std::size_t>(n + 2 * h));
  for (std::size_t j = 0; j < white.size(); ++j) white[j] = gaussian(j);
  std::vector<double> noise(static_cast<std::size_t>(n), 0.0);
  for (int i = 0; i < n; ++i) {
    double sum = 0;
    for (int k = 0; k <= 2 * h; ++k) {
      sum += kernel[static_cast<std::size_t>(k)] * white[static_cast<std::size_t>(i + k)];
    }
    noise[static_cast<std::size_t>(i)] = sum / norm;
  }
  return noise;
}

}  // namespace selfcal::sim
