// The export formats beside the URDF: PLY clouds (header and bytes as CloudCompare and MeshLab
// read them) and the ROS 2 parameter file of joint offsets (read back with yaml-cpp, exactly).
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstring>
#include <filesystem>

#include "core/util/atomic_file.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/ply.h"
#include "protocols/model_file/ros2_control_offsets.h"

namespace selfcal {
namespace {

TEST(Ply, HeaderNamesEveryPropertyAndTheBytesFollowIt) {
  const std::vector<PlyPoint> points{{1.5f, -2.25f, 0.125f, 10, 20, 30, 7},
                                     {0.f, 1e-3f, -4.f, 255, 0, 1, -1}};
  const std::string ply = FormatPly(points, "two\npoints");
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment two points\nelement vertex 2\n"
      "property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
      "property uchar green\nproperty uchar blue\nproperty int scan\nend_header\n";
  ASSERT_EQ(ply.substr(0, header.size()), header);
  ASSERT_EQ(ply.size(), header.size() + 2 * 19);
  const char* body = ply.data() + header.size();
  for (const PlyPoint& expected : points) {
    float xyz[3];
    std::int32_t scan;
    std::memcpy(xyz, body, 12);
    std::memcpy(&scan, body + 15, 4);
    EXPECT_EQ(xyz[0], expected.x);
    EXPECT_EQ(xyz[1], expected.y);
    EXPECT_EQ(xyz[2], expected.z);
    EXPECT_EQ(static_cast<unsigned char>(body[12]), expected.red);
    EXPECT_EQ(static_cast<unsigned char>(body[13]), expected.green);
    EXPECT_EQ(static_cast<unsigned char>(body[14]), expected.blue);
    EXPECT_EQ(scan, expected.scan);
    body += 19;
  }
}

TEST(Ply, IsWrittenAtomically) {
  const std::string folder = ::testing::TempDir() + "ply_" + std::to_string(getpid());
  std::filesystem::create_directories(folder);
  const std::string path = folder + "/cloud.ply";
  ASSERT_TRUE(WritePlyFile(path, {{1, 2, 3, 4, 5, 6, 7}}, "one"));
  const auto read = ReadFile(path);
  ASSERT_TRUE(read);
  EXPECT_EQ(*read, FormatPly({{1, 2, 3, 4, 5, 6, 7}}, "one"));
  EXPECT_FALSE(WritePlyFile(folder + "/missing/cloud.ply", {}, "none"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(folder), {}), 1);
  std::filesystem::remove_all(folder);
}

TEST(Ros2ControlOffsets, ReadsBackAsRos2ParametersExactly) {
  const auto file =
      ReadModelFile(std::string(SELFCAL_SOURCE_DIR) + "/config/robots/kuka_lbr_iiwa_r840.yaml");
  ASSERT_TRUE(file) << file.error().message;
  JointOffsetFit fit;
  fit.offsets = {0.1, -0.0087266462599716477, 0, 1e-9, 0, 0, 0};
  fit.samples = 200;
  const YAML::Node yaml = YAML::Load(FormatRos2ControlOffsets(file->model, fit, "result.yaml"));
  const YAML::Node offsets = yaml["/**"]["ros__parameters"]["joint_offsets"];
  ASSERT_TRUE(offsets.IsMap());
  ASSERT_EQ(offsets.size(), 7u);
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(offsets[file->model.joints[i].name].as<double>(), fit.offsets[i])
        << file->model.joints[i].name;
  }
}

}  // namespace
}  // namespace selfcal
