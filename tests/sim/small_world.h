// The small worlds the simulator's tests cast in: a point robot standing still, a Kinect-like
// camera, a Wenglor-like line scanner, and a concave corner.
#pragma once

#include <Eigen/Core>

#include "core/model/robot_model.h"
#include "core/sim/mesh.h"
#include "core/sim/scan_plan.h"
#include "core/sim/scene.h"
#include "core/sim/sensor_model.h"

namespace selfcal::sim::small_world {

// A one-joint robot whose sensor sits at the base origin for q = 0 (identity tool).
inline RobotModel PointRobot() {
  RobotModel model;
  model.name = "point";
  model.joints.push_back({"J1", JointType::kRevolute, -3, 3, 1, 5});
  model.mask = DefaultMask(model);
  return model;
}

// One fitted scan standing still at q = 0.
inline ScanPlan StillPlan() {
  ScanPlan plan;
  PlannedScan scan;
  scan.start = {0.0};
  scan.end = {0.0};
  plan.scans.push_back(scan);
  return plan;
}

// A Kinect-like camera (NFOV 2x2 binned geometry), noise-free unless set.
inline SensorModel Camera(double sigma = 0) {
  SensorModel m;
  m.kind = SensorLayout::kDepthCamera;
  m.width = 320;
  m.height = 288;
  m.range_min = 0.3;
  m.range_max = 5.46;
  m.sigma_abs = sigma;
  m.intrinsics = {208.5, 226.0, 159.5, 143.5};
  m.frame_period = 1.0 / 30;
  return m;
}

// A Wenglor-like line scanner (1280 points over 0.5 rad, 0.3-1.5 m), noise-free unless set.
inline SensorModel LineScanner(double sigma = 0) {
  SensorModel line;
  line.kind = SensorLayout::kLineScanner;
  line.width = 1280;
  line.range_min = 0.3;
  line.range_max = 1.5;
  line.sigma_abs = sigma;
  line.fan_angle = 0.5;
  line.line_period = 1.0 / 500;
  return line;
}

// A concave corner: a far plane z = 1 facing the camera left of x = 0.2 and a side wall x = 0.2
// (z 0 .. 1) meeting it in a crease at x = 0.2, z = 1.
inline Scene CornerScene() {
  Scene scene;
  scene.mesh = MakeQuad(Eigen::Vector3d(-3, -3, 1), Eigen::Vector3d(3.2, 0, 0),
                        Eigen::Vector3d(0, 6, 0), 32);
  scene.mesh.Append(MakeQuad(Eigen::Vector3d(0.2, -3, 0), Eigen::Vector3d(0, 6, 0),
                             Eigen::Vector3d(0, 0, 1), 32));
  return scene;
}

}  // namespace selfcal::sim::small_world
