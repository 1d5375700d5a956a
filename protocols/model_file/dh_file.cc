#include "protocols/model_file/dh_file.h"

#include <cmath>

#include "core/util/atomic_file.h"
#include "protocols/model_file/model_file.h"
#include "protocols/model_file/yaml_reader.h"

namespace selfcal {
namespace {

using yaml::StrictMap;

Eigen::Vector3d ReadTriple(StrictMap& map, const std::string& key) {
  const auto values = map.Required<std::vector<double>>(key);
  if (values.size() != 3) map.Fail(key, "must have three numbers");
  for (double v : values) {
    if (!std::isfinite(v)) map.Fail(key, "must be finite");
  }
  return {values[0], values[1], values[2]};
}

Eigen::Isometry3d ReadOrigin(StrictMap map) {
  const Eigen::Vector3d xyz = ReadTriple(map, "xyz");
  const Eigen::Vector3d rpy = ReadTriple(map, "rpy");
  map.RejectUnknownKeys();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = xyz;
  T.linear() = (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

DhRow ReadRow(StrictMap map) {
  DhRow row;
  row.joint.name = map.Required<std::string>("name");
  row.joint.type = map.RequiredChoice("type", kJointTypeNames);
  row.d = map.RequiredFinite("d");
  row.theta = map.RequiredFinite("theta");
  row.a = map.RequiredFinite("a");
  row.alpha = map.RequiredFinite("alpha");
  row.joint.lower = map.RequiredFinite("lower");
  row.joint.upper = map.RequiredFinite("upper");
  row.joint.max_velocity = map.RequiredFinite("max_velocity");
  row.joint.max_acceleration = map.RequiredFinite("max_acceleration");
  map.RejectUnknownKeys();
  if (!(row.joint.lower < row.joint.upper)) map.Fail("lower", "must be below 'upper'");
  if (!(row.joint.max_velocity > 0)) map.Fail("max_velocity", "must be positive");
  if (!(row.joint.max_acceleration > 0)) map.Fail("max_acceleration", "must be positive");
  return row;
}

DhTable ReadDocument(StrictMap& map) {
  DhTable table;
  table.name = map.Required<std::string>("name");
  if (map.Has("base")) table.T_base_frame0 = ReadOrigin(map.Map("base"));
  if (map.Has("tool")) table.T_framen_tool = ReadOrigin(map.Map("tool"));
  const auto joints = map.Sequence("joints");
  if (joints.empty()) map.Fail("joints", "must list at least one joint");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    table.rows.push_back(
        ReadRow(StrictMap(joints[i], "joints[" + std::to_string(i) + "]", map.file())));
  }
  return table;
}

}  // namespace

Expected<DhTable> ParseDhFile(const std::string& text, const std::string& name) {
  return yaml::ParseDocument<DhTable>(text, name, ReadDocument);
}

Expected<DhTable> ReadDhFile(const std::string& path) {
  auto text = ReadFile(path);
  if (!text) return text.error();
  return ParseDhFile(*text, path);
}

}  // namespace selfcal
