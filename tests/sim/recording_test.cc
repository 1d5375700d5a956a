// `selfcal simulate` end to end: the recording decodes and follows docs/recording.md (channels,
// markers, one frame per camera scan, per-ray LiDAR times, joint states around every
// measurement), the same seed gives the same bytes whatever the thread count, and every
// measurement reprojected through truth.yaml and the interpolated joint states lies on the
// scene's surfaces (through nominal.yaml it does not).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include "core/camera/pinhole_intrinsics.h"
#include "core/model/kinematics.h"
#include "core/sim/scene.h"
#include "core/util/atomic_file.h"
#include "protocols/lcm_log/lcm_log.h"
#include "protocols/model_file/model_file.h"
#include "selfcal/depth_image_t.hpp"
#include "selfcal/joint_state_t.hpp"
#include "selfcal/range_scan_t.hpp"
#include "selfcal/scan_marker_t.hpp"

namespace selfcal {
namespace {

std::string Source(const std::string& relative) {
  const char* root = std::getenv("SELFCAL_SOURCE_DIR");
  return std::string(root ? root : ".") + "/" + relative;
}

// Removes a test's output folder when the test ends, also when it fails.
struct RemoveOnExit {
  std::string path;
  ~RemoveOnExit() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

// Runs the command; one thread unless a test needs more, so that parallel ctest stays light.
std::string Simulate(const std::string& scenario, const std::string& name,
                     const std::string& extra) {
  // The pid keeps concurrent runs (other build folders, other worktrees) apart.
  const std::string out =
      testing::TempDir() + "selfcal_sim_" + name + "_" + std::to_string(getpid());
  std::filesystem::remove_all(out);
  const std::string command = std::string(SELFCAL_BINARY) + " -q simulate " + Source(scenario) +
                              " --out " + out + " " + extra + " > /dev/null";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  return out;
}

struct Recording {
  std::vector<std::pair<std::int64_t, std::vector<double>>> joints;  // utime, positions
  std::vector<std::string> joint_names;
  std::vector<selfcal::scan_marker_t> markers;
  std::vector<selfcal::range_scan_t> range_scans;
  std::vector<selfcal::depth_image_t> depth_images;
  std::map<std::string, int> channel_counts;
};

Recording Load(const std::string& path) {
  Recording recording;
  auto reader = LcmLogReader::Open(path);
  EXPECT_TRUE(reader.ok());
  if (!reader.ok()) return recording;
  LogEvent event;
  std::int64_t last_log_time = 0;
  while (reader->Next(event)) {
    EXPECT_GE(event.utime, last_log_time) << "log events out of order";
    last_log_time = event.utime;
    ++recording.channel_counts[event.channel];
    if (event.channel == "SELFCAL_JOINT_STATE") {
      auto m = DecodeLcm<selfcal::joint_state_t>(event.data, event.channel);
      EXPECT_TRUE(m.ok());
      EXPECT_EQ(m->num_joints, 7);
      recording.joint_names = m->names;
      if (!recording.joints.empty()) {
        EXPECT_GT(m->utime, recording.joints.back().first);
      }
      recording.joints.emplace_back(m->utime, m->positions);
    } else if (event.channel == "SELFCAL_SCAN_MARKER") {
      auto m = DecodeLcm<selfcal::scan_marker_t>(event.data, event.channel);
      EXPECT_TRUE(m.ok());
      recording.markers.push_back(*m);
    } else if (event.channel == "SELFCAL_RANGE_SCAN") {
      auto m = DecodeLcm<selfcal::range_scan_t>(event.data, event.channel);
      EXPECT_TRUE(m.ok());
      recording.range_scans.push_back(*m);
    } else if (event.channel == "SELFCAL_DEPTH_IMAGE") {
      auto m = DecodeLcm<selfcal::depth_image_t>(event.data, event.channel);
      EXPECT_TRUE(m.ok());
      recording.depth_images.push_back(*m);
    } else {
      ADD_FAILURE() << "unexpected channel " << event.channel;
    }
  }
  return recording;
}

// Joint positions at `utime` by linear interpolation (the paper); both neighbours within 50 ms.
std::vector<double> Interpolate(const Recording& r, double utime) {
  auto it = std::lower_bound(
      r.joints.begin(), r.joints.end(), utime,
      [](const auto& sample, double t) { return static_cast<double>(sample.first) < t; });
  EXPECT_TRUE(it != r.joints.begin() && it != r.joints.end()) << "no joint states around " << utime;
  if (it == r.joints.begin() || it == r.joints.end()) return std::vector<double>(7, 0.0);
  const auto& after = *it;
  const auto& before = *(it - 1);
  EXPECT_LE(utime - static_cast<double>(before.first), 50000);
  EXPECT_LE(static_cast<double>(after.first) - utime, 50000);
  const double w =
      (utime - static_cast<double>(before.first)) / static_cast<double>(after.first - before.first);
  std::vector<double> q(before.second.size());
  for (std::size_t j = 0; j < q.size(); ++j)
    q[j] = (1 - w) * before.second[j] + w * after.second[j];
  return q;
}

// The scan a message stamped `utime` belongs to, by the markers (-1: none).
int ScanOf(const Recording& r, std::int64_t utime) {
  std::map<int, std::int64_t> begins;
  for (const auto& m : r.markers) {
    if (m.event == selfcal::scan_marker_t::BEGIN) begins[m.scan_index] = m.utime;
    if (m.event == selfcal::scan_marker_t::END && begins.count(m.scan_index) &&
        utime >= begins[m.scan_index] && utime <= m.utime) {
      return m.scan_index;
    }
  }
  return -1;
}

void ExpectMarkers(const Recording& r, int fit, int validation, const std::string& plan_name) {
  ASSERT_EQ(r.markers.size(), static_cast<std::size_t>(2 * (fit + validation)));
  for (int k = 0; k < fit + validation; ++k) {
    const auto& begin = r.markers[static_cast<std::size_t>(2 * k)];
    const auto& end = r.markers[static_cast<std::size_t>(2 * k + 1)];
    EXPECT_EQ(begin.event, selfcal::scan_marker_t::BEGIN);
    EXPECT_EQ(end.event, selfcal::scan_marker_t::END);
    EXPECT_EQ(begin.scan_index, k);
    EXPECT_EQ(end.scan_index, k);
    EXPECT_LT(begin.utime, end.utime);
    const auto purpose = k < fit ? selfcal::scan_marker_t::FIT : selfcal::scan_marker_t::VALIDATION;
    EXPECT_EQ(begin.purpose, purpose);
    EXPECT_EQ(end.purpose, purpose);
    EXPECT_EQ(begin.plan_name, plan_name);
    EXPECT_FALSE(begin.session_id.empty());
  }
}

// Distance from p to triangle abc (Ericson, Real-Time Collision Detection 5.1.5).
double TriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  }
  const double denominator = 1 / (va + vb + vc);
  return (p - (a + ab * vb * denominator + ac * vc * denominator)).norm();
}

double SceneDistance(const sim::Scene& scene, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : scene.mesh.triangles) {
    best = std::min(best, TriangleDistance(
                              p, scene.mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>(),
                              scene.mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>(),
                              scene.mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>()));
  }
  return best;
}

RobotModel Model(const std::string& path) {
  auto file = ReadModelFile(path);
  EXPECT_TRUE(file.ok()) << (file.ok() ? "" : file.error().message);
  return file.ok() ? file->model : RobotModel{};
}

TEST(Recording, LidarRaysHaveTheirOwnTimesAndLandOnTheScene) {
  const std::string out = Simulate("tests/sim/data/lidar-corner.yaml", "lidar", "--threads 1");
  const RemoveOnExit cleanup{out};
  const Recording r = Load(out + "/recording.lcmlog");
  ExpectMarkers(r, 2, 1, "lidar-corner");
  ASSERT_GT(r.range_scans.size(), 20u);
  const RobotModel truth = Model(out + "/truth.yaml");
  const RobotModel nominal = Model(out + "/nominal.yaml");
  EXPECT_EQ(r.joint_names, std::vector<std::string>({"A1", "A2", "A3", "A4", "A5", "A6", "A7"}));
  const sim::Scene scene = sim::MakeCornerScene();
  const double latency_us = 12000;  // the scenario's sensor_latency
  std::size_t checked = 0, on_surface_truth = 0, on_surface_nominal = 0;
  for (std::size_t s = 0; s < r.range_scans.size(); ++s) {
    const auto& scan = r.range_scans[s];
    EXPECT_GE(ScanOf(r, scan.utime), 0) << "rotation outside every scan";
    EXPECT_EQ(scan.num_ranges, 1081);
    EXPECT_DOUBLE_EQ(scan.time_per_ray, 1.0 / (40 * 1440));
    EXPECT_NEAR(scan.angle_first, -2.356194490192345, 1e-15);
    EXPECT_NEAR(scan.angle_increment, 2 * M_PI / 1440, 1e-15);
    if (s > 0 && ScanOf(r, scan.utime) == ScanOf(r, r.range_scans[s - 1].utime)) {
      EXPECT_EQ(scan.utime - r.range_scans[s - 1].utime, 25000);
    }
    for (int i = 0; i < scan.num_ranges; i += 5) {
      const float range = scan.ranges[static_cast<std::size_t>(i)];
      if (std::isnan(range)) continue;
      // Measurement time of ray i per docs/recording.md, plus the latency.
      const double t = static_cast<double>(scan.utime) + 1e6 * i * scan.time_per_ray + latency_us;
      const auto q = Interpolate(r, t);
      const double angle = scan.angle_first + i * scan.angle_increment;
      const Eigen::Vector3d p_sensor(range * std::cos(angle), range * std::sin(angle), 0);
      ++checked;
      if (SceneDistance(scene, ForwardKinematics(truth, q) * p_sensor) < 0.002) ++on_surface_truth;
      if (SceneDistance(scene, ForwardKinematics(nominal, q) * p_sensor) < 0.002)
        ++on_surface_nominal;
    }
  }
  ASSERT_GT(checked, 3000u);
  EXPECT_GT(static_cast<double>(on_surface_truth), 0.99 * static_cast<double>(checked));
  EXPECT_LT(static_cast<double>(on_surface_nominal), 0.5 * static_cast<double>(checked));
}

TEST(Recording, CameraFramesFollowTheContractAndLandOnTheScene) {
  const std::string out = Simulate("tests/sim/data/camera-corner.yaml", "camera", "--threads 1");
  const RemoveOnExit cleanup{out};
  const Recording r = Load(out + "/recording.lcmlog");
  ExpectMarkers(r, 3, 2, "camera-corner");
  EXPECT_EQ(r.channel_counts.size(), 3u);
  ASSERT_EQ(r.depth_images.size(), 5u);  // exactly one frame per scan
  const RobotModel truth = Model(out + "/truth.yaml");
  const RobotModel nominal = Model(out + "/nominal.yaml");
  const sim::Scene scene = sim::MakeCornerScene();
  std::size_t checked = 0, on_surface_truth = 0, on_surface_nominal = 0;
  for (std::size_t f = 0; f < r.depth_images.size(); ++f) {
    const auto& image = r.depth_images[f];
    EXPECT_EQ(ScanOf(r, image.utime), static_cast<int>(f));
    EXPECT_EQ(image.width, 80);
    EXPECT_EQ(image.height, 72);
    EXPECT_EQ(image.num_pixels, 80 * 72);
    EXPECT_DOUBLE_EQ(image.depth_unit_m, 0.001);
    const auto q = Interpolate(r, static_cast<double>(image.utime) - 20000);  // latency -0.02 s
    for (int v = 0; v < image.height; v += 2) {
      for (int u = 0; u < image.width; u += 2) {
        const auto counts =
            static_cast<std::uint16_t>(image.depth[static_cast<std::size_t>(v * image.width + u)]);
        if (counts == 0) continue;
        const double z = counts * image.depth_unit_m;
        const Eigen::Vector3d p_sensor =
            PinholeIntrinsics{image.fx, image.fy, image.cx, image.cy}.Unproject(u, v, z);
        ++checked;
        // Depth is quantized to 1 mm: the point is within 0.5 mm along its ray.
        if (SceneDistance(scene, ForwardKinematics(truth, q) * p_sensor) < 0.0015)
          ++on_surface_truth;
        if (SceneDistance(scene, ForwardKinematics(nominal, q) * p_sensor) < 0.0015)
          ++on_surface_nominal;
      }
    }
  }
  ASSERT_GT(checked, 2000u);
  EXPECT_GT(static_cast<double>(on_surface_truth), 0.99 * static_cast<double>(checked));
  EXPECT_LT(static_cast<double>(on_surface_nominal), 0.5 * static_cast<double>(checked));
}

TEST(Recording, SameSeedSameBytesWhateverTheThreadCount) {
  const std::string a = Simulate("config/scenarios/small.yaml", "det_a", "--threads 1");
  const std::string b = Simulate("config/scenarios/small.yaml", "det_b", "--threads 2");
  const std::string c = Simulate("config/scenarios/small.yaml", "det_c", "--threads 1 --seed 99");
  const RemoveOnExit cleanup_a{a}, cleanup_b{b}, cleanup_c{c};
  for (const char* file : {"/recording.lcmlog", "/truth.yaml", "/nominal.yaml", "/scenario.yaml"}) {
    const auto bytes_a = ReadFile(a + file);
    const auto bytes_b = ReadFile(b + file);
    ASSERT_TRUE(bytes_a.ok() && bytes_b.ok()) << file;
    EXPECT_TRUE(*bytes_a == *bytes_b) << file << " differs between 1 and 2 threads";
  }
  EXPECT_FALSE(*ReadFile(a + "/recording.lcmlog") == *ReadFile(c + "/recording.lcmlog"));
  EXPECT_FALSE(*ReadFile(a + "/truth.yaml") == *ReadFile(c + "/truth.yaml"));
  // The resolved scenario records the seed it ran with.
  EXPECT_NE(ReadFile(c + "/scenario.yaml")->find("seed: 99"), std::string::npos);
  // The small scenario: 14 fit + 7 validation scans, one depth image each.
  const Recording r = Load(a + "/recording.lcmlog");
  ExpectMarkers(r, 14, 7, "small");
  EXPECT_EQ(r.depth_images.size(), 21u);
}

TEST(Recording, BadInputIsAnErrorThatSaysWhere) {
  const std::string suffix = std::to_string(getpid());
  const std::string out = testing::TempDir() + "selfcal_sim_bad_" + suffix;
  const std::string scenario = testing::TempDir() + "selfcal_sim_bad_" + suffix + ".yaml";
  const RemoveOnExit cleanup_out{out}, cleanup_scenario{scenario};
  ASSERT_TRUE(WriteFileAtomically(scenario, "name: x\nseed: 1\nrobot: r.yaml\nbogus: 1\n").ok());
  const std::string command = std::string(SELFCAL_BINARY) + " simulate " + scenario + " --out " +
                              out + " 2>&1 | grep -q \"error: .*selfcal_sim_bad_" + suffix +
                              ".yaml\"";
  EXPECT_EQ(std::system(command.c_str()), 0);
  EXPECT_NE(std::system((std::string(SELFCAL_BINARY) + " simulate /nonexistent.yaml --out " + out +
                         " 2>/dev/null")
                            .c_str()),
            0);
  EXPECT_FALSE(std::filesystem::exists(out + "/recording.lcmlog"));
}

}  // namespace
}  // namespace selfcal
