// Synthetic in-memory data for the engine's tests: a scene of planes, spheres and boxes, ray cast
// by an ideal depth camera or line scanner carried by the robot. No simulator needed.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/calib/calibrate.h"
#include "core/calib/dataset.h"
#include "core/camera/pinhole_intrinsics.h"
#include "core/model/evaluation.h"
#include "core/model/kinematics.h"
#include "protocols/model_file/model_file.h"

namespace selfcal::calib::testing {

struct Plane {
  Eigen::Vector3d normal;  // unit
  double offset;           // points p with normal . p = offset
};
struct Sphere {
  Eigen::Vector3d center;
  double radius;
};
struct Cuboid {  // axis-aligned
  Eigen::Vector3d min, max;
};

struct Scene {
  std::vector<Plane> planes;
  std::vector<Sphere> spheres;
  std::vector<Cuboid> cuboids;

  // Distance along the unit ray from origin to the first surface, or infinity.
  double Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    double best = std::numeric_limits<double>::infinity();
    for (const Plane& plane : planes) {
      const double denominator = plane.normal.dot(direction);
      if (std::abs(denominator) < 1e-12) continue;
      const double t = (plane.offset - plane.normal.dot(origin)) / denominator;
      if (t > 1e-9 && t < best) best = t;
    }
    for (const Sphere& sphere : spheres) {
      const Eigen::Vector3d oc = origin - sphere.center;
      const double b = oc.dot(direction);
      const double c = oc.squaredNorm() - sphere.radius * sphere.radius;
      const double discriminant = b * b - c;
      if (discriminant < 0) continue;
      const double t = -b - std::sqrt(discriminant);
      if (t > 1e-9 && t < best) best = t;
    }
    for (const Cuboid& box : cuboids) {  // slab method
      double t_near = -std::numeric_limits<double>::infinity(),
             t_far = std::numeric_limits<double>::infinity();
      bool miss = false;
      for (int a = 0; a < 3; ++a) {
        if (std::abs(direction[a]) < 1e-12) {
          if (origin[a] < box.min[a] || origin[a] > box.max[a]) miss = true;
          continue;
        }
        double t0 = (box.min[a] - origin[a]) / direction[a];
        double t1 = (box.max[a] - origin[a]) / direction[a];
        if (t0 > t1) std::swap(t0, t1);
        t_near = std::max(t_near, t0);
        t_far = std::min(t_far, t1);
      }
      if (!miss && t_near <= t_far && t_near > 1e-9 && t_near < best) best = t_near;
    }
    return best;
  }
};

// A closed room around the robot with spheres and boxes in it: every view sees structure.
inline Scene RoomScene() {
  Scene scene;
  scene.planes = {{{0, 0, 1}, -0.4}, {{0, 0, 1}, 2.6},  {{1, 0, 0}, -2.0},
                  {{1, 0, 0}, 2.2},  {{0, 1, 0}, -2.1}, {{0, 1, 0}, 1.9}};
  std::mt19937 random(7);
  std::uniform_real_distribution<double> position(-1.6, 1.6), height(-0.3, 2.2), radius(0.15, 0.4);
  for (int i = 0; i < 14; ++i) {
    Eigen::Vector3d center(position(random), position(random), height(random));
    if (center.head<2>().norm() < 0.9) center.head<2>() *= 0.9 / center.head<2>().norm() + 0.4;
    scene.spheres.push_back({center, radius(random)});
  }
  for (int i = 0; i < 8; ++i) {
    Eigen::Vector3d corner(position(random), position(random), -0.4);
    if (corner.head<2>().norm() < 1.0) corner.head<2>() *= 1.6;
    const Eigen::Vector3d size(0.2 + 0.3 * std::abs(radius(random)),
                               0.2 + 0.4 * std::abs(radius(random)),
                               0.3 + 1.5 * std::abs(radius(random)));
    scene.cuboids.push_back({corner, corner + size});
  }
  return scene;
}

inline RobotModel LoadIiwa() {
  const char* source = std::getenv("SELFCAL_SOURCE_DIR");
  const std::string root = source != nullptr ? source : ".";
  auto file = ReadModelFile(root + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  if (!file) {
    std::fprintf(stderr, "%s\n", file.error().message.c_str());
    std::abort();
  }
  RobotModel model = file->model;
  // A sensor mount like the scenarios': 10 cm beyond the flange, slightly tilted.
  model.tool = {0.02, -0.03, 0.3, 0.01, -0.02, 0.226};
  return model;
}

// The truth: the nominal model with every calibrated parameter perturbed (mm and tenths of a
// degree, the size of real manufacturing errors).
inline RobotModel PerturbedModel(const RobotModel& nominal, unsigned seed,
                                 double translation = 0.003, double angle = 0.004) {
  std::mt19937 random(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<double> k = ToParameterVector(nominal);
  for (std::size_t i = 0; i < k.size(); ++i) {
    if (!nominal.mask[i]) continue;
    k[i] += (IsTranslationParameter(nominal, i) ? translation : angle) * unit(random);
  }
  RobotModel truth = nominal;
  FromParameterVector(k, truth);
  return truth;
}

// Random joint configurations around a pose that looks outwards and down: the workspace the
// synthetic scans are taken in.
inline std::vector<std::vector<double>> WorkspaceConfigurations(std::size_t count, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> offset(-0.7, 0.7), turn(-3.0, 3.0);
  std::vector<std::vector<double>> result;
  for (std::size_t i = 0; i < count; ++i) {
    result.push_back({turn(random), 0.6 + 0.5 * offset(random), offset(random),
                      -1.2 + 0.5 * offset(random), offset(random), 0.9 + 0.6 * offset(random),
                      turn(random)});
  }
  return result;
}

struct SyntheticCamera {
  std::size_t width = 80, height = 64;
  PinholeIntrinsics intrinsics{52, 56, 39.5, 31.5};
  double max_range = 5.0;
};

// A depth image of `scene` taken with the sensor at T_base_sensor(truth, joints).
inline Dataset DepthScan(const Scene& scene, const RobotModel& truth,
                         const std::vector<double>& joints, const SyntheticCamera& camera,
                         int scan_index, double noise_m = 0.0, unsigned seed = 1) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Dataset dataset;
  dataset.scan_index = scan_index;
  dataset.layout = PoseLayout::kOnePerScan;
  dataset.rows = camera.height;
  dataset.cols = camera.width;
  dataset.joint_count = joints.size();
  dataset.pose_joints = joints;
  const Transform3<double> T_base_sensor = ForwardKinematics(truth, joints);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t r = 0; r < camera.height; ++r) {
    for (std::size_t c = 0; c < camera.width; ++c) {
      const Eigen::Vector3d ray_sensor =
          camera.intrinsics.Unproject(static_cast<double>(c), static_cast<double>(r), 1.0);
      const Eigen::Vector3d direction = (T_base_sensor.linear() * ray_sensor).normalized();
      double t = scene.Cast(T_base_sensor.translation(), direction);
      if (!(t < camera.max_range)) {
        dataset.x.push_back(nan);
        dataset.y.push_back(nan);
        dataset.z.push_back(nan);
        continue;
      }
      t += noise_m * noise(random);
      const Eigen::Vector3d p = ray_sensor.normalized() * t;
      dataset.x.push_back(static_cast<float>(p.x()));
      dataset.y.push_back(static_cast<float>(p.y()));
      dataset.z.push_back(static_cast<float>(p.z()));
    }
  }
  return dataset;
}

// A rotating LiDAR (a pose per point, docs/recording.md) swept by turning the joints from
// `from` to `to` in `seconds`: joint samples at `rate_hz` with encoder noise, interpolated
// linearly to every ray's time as the recording does. Scan plane z = 0 of the sensor frame.
struct LidarSweepOptions {
  std::size_t rays = 1081;   // per line, over 270 degrees
  double line_rate_hz = 40;  // rotations per second
  double seconds = 0.5;
  double rate_hz = 200;         // joint states
  double encoder_noise = 2e-5;  // rad
  double max_range = 8.0;
};
inline Dataset LidarSweep(const Scene& scene, const RobotModel& truth,
                          const std::vector<double>& from, const std::vector<double>& to,
                          int scan_index, const LidarSweepOptions& options = {},
                          unsigned seed = 1) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, options.encoder_noise);
  const std::size_t joints = from.size();
  // Joint samples: the straight path plus encoder noise.
  const std::size_t samples = static_cast<std::size_t>(options.seconds * options.rate_hz) + 2;
  std::vector<std::vector<double>> sample(samples, std::vector<double>(joints));
  for (std::size_t s = 0; s < samples; ++s) {
    const double f = std::min(1.0, static_cast<double>(s) / options.rate_hz / options.seconds);
    for (std::size_t j = 0; j < joints; ++j)
      sample[s][j] = from[j] + f * (to[j] - from[j]) + noise(random);
  }
  const std::size_t lines = static_cast<std::size_t>(options.seconds * options.line_rate_hz);
  const double time_per_ray = 1.0 / options.line_rate_hz / 1440.0;  // 1440 steps per rotation
  Dataset dataset;
  dataset.scan_index = scan_index;
  dataset.layout = PoseLayout::kOnePerPoint;
  dataset.rows = options.rays;
  dataset.cols = lines;
  dataset.joint_count = joints;
  const std::size_t n = dataset.rows * dataset.cols;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  dataset.x.assign(n, nan);
  dataset.y.assign(n, nan);
  dataset.z.assign(n, nan);
  dataset.pose_joints.resize(n * joints);
  for (std::size_t c = 0; c < lines; ++c) {
    for (std::size_t r = 0; r < options.rays; ++r) {
      const std::size_t point = r * lines + c;
      const double t =
          static_cast<double>(c) / options.line_rate_hz + static_cast<double>(r) * time_per_ray;
      const double position = t * options.rate_hz;
      const std::size_t s = std::min(samples - 2, static_cast<std::size_t>(position));
      const double w = position - static_cast<double>(s);
      std::vector<double> q(joints);
      for (std::size_t j = 0; j < joints; ++j) q[j] = (1 - w) * sample[s][j] + w * sample[s + 1][j];
      std::copy(q.begin(), q.end(),
                dataset.pose_joints.begin() + static_cast<long>(point * joints));
      const double angle = -0.75 * M_PI + static_cast<double>(r) *
                                              (1.5 * M_PI / static_cast<double>(options.rays - 1));
      const Eigen::Vector3d ray_sensor(std::cos(angle), std::sin(angle), 0.0);
      const Transform3<double> T_base_sensor = ForwardKinematics(truth, q);
      const double range =
          scene.Cast(T_base_sensor.translation(), T_base_sensor.linear() * ray_sensor);
      if (!(range < options.max_range)) continue;
      dataset.x[point] = static_cast<float>(range * ray_sensor.x());
      dataset.y[point] = static_cast<float>(range * ray_sensor.y());
      dataset.z[point] = 0.0f;
    }
  }
  return dataset;
}

// Table I's Hokuyo row, for LiDAR sweeps.
inline CalibrationOptions HokuyoOptions(SolverKind solver = SolverKind::kFast) {
  CalibrationOptions options;
  options.filter_n = 2;
  options.filter_m = 4;
  options.g_min = 0.6;
  options.d_max = 0.02;
  options.f_min = 0.75;
  options.solver = solver;
  options.threads = 2;
  return options;
}

// Where the engine's tests measure accuracy (SensorPoseError of core/model/evaluation.h): 200
// configurations of the scans' workspace, not of the whole joint range, since the synthetic scans
// only observe the chain there (measured: the LiDAR sweep test's result is 1.0 mm off here and
// 2.7 mm over the whole joint range).
inline std::vector<std::vector<double>> EvaluationConfigurations() {
  return WorkspaceConfigurations(200, 999);
}

}  // namespace selfcal::calib::testing
