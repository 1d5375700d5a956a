#include "protocols/model_file/model_file.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/util/atomic_file.h"
#include "protocols/model_file/yaml_reader.h"
#include "protocols/model_file/yaml_writer.h"

namespace selfcal {
namespace {

using yaml::Number;
using yaml::NumberList;
using yaml::ParseError;
using yaml::StrictMap;
using yaml::Text;

constexpr std::array<const char*, 6> kFullKeys = {"alpha", "beta", "gamma", "x", "y", "z"};
constexpr std::array<const char*, 4> kSegmentKeys = {"alpha", "beta", "x", "y"};

JointSpec ReadJoint(StrictMap map) {
  JointSpec joint;
  joint.name = map.Required<std::string>("name");
  joint.type = map.RequiredChoice("type", kJointTypeNames);
  joint.lower = map.Required<double>("lower");
  joint.upper = map.Required<double>("upper");
  joint.max_velocity = map.Required<double>("max_velocity");
  joint.max_acceleration = map.Required<double>("max_acceleration");
  map.RejectUnknownKeys();
  if (!(joint.lower < joint.upper)) map.Fail("lower", "must be below 'upper'");
  if (!(joint.max_velocity > 0)) map.Fail("max_velocity", "must be positive");
  if (!(joint.max_acceleration > 0)) map.Fail("max_acceleration", "must be positive");
  return joint;
}

FullTransformParams ReadFull(StrictMap map) {
  FullTransformParams p;
  double* fields[] = {&p.alpha, &p.beta, &p.gamma, &p.x, &p.y, &p.z};
  for (std::size_t i = 0; i < kFullKeys.size(); ++i)
    *fields[i] = map.Required<double>(kFullKeys[i]);
  map.RejectUnknownKeys();
  return p;
}

SegmentParams ReadSegment(StrictMap map) {
  SegmentParams p;
  double* fields[] = {&p.alpha, &p.beta, &p.x, &p.y};
  for (std::size_t i = 0; i < kSegmentKeys.size(); ++i) {
    *fields[i] = map.Required<double>(kSegmentKeys[i]);
  }
  map.RejectUnknownKeys();
  return p;
}

// Sets the mask entries of one transform from a list of parameter names.
template <std::size_t N>
void ReadMaskList(const YAML::Node& list, const std::array<const char*, N>& keys,
                  std::size_t offset, const std::string& path, const std::string& file,
                  std::vector<bool>& mask) {
  if (!list.IsSequence()) throw ParseError(file + ": key '" + path + "' must be a list of names");
  for (const auto& item : list) {
    const auto name = item.as<std::string>();
    bool found = false;
    for (std::size_t i = 0; i < N; ++i) {
      if (name == keys[i]) {
        mask[offset + i] = true;
        found = true;
      }
    }
    if (!found) {
      throw ParseError(file + ": key '" + path + "' names unknown parameter '" + name + "'");
    }
  }
}

void ReadMask(StrictMap map, RobotModel& model) {
  const std::string& file = map.file();
  model.mask.assign(model.ParameterCount(), false);
  const auto segments = map.Sequence("segments");
  if (segments.size() != model.segments.size()) {
    map.Fail("segments", "has " + std::to_string(segments.size()) + " entries, expected " +
                             std::to_string(model.segments.size()) + " (one per segment)");
  }
  for (std::size_t i = 0; i < segments.size(); ++i) {
    ReadMaskList(segments[i], kSegmentKeys, SegmentOffset(i),
                 map.PathOf("segments") + "[" + std::to_string(i) + "]", file, model.mask);
  }
  ReadMaskList(map.Raw("tool"), kFullKeys, ToolOffset(model.JointCount()), map.PathOf("tool"), file,
               model.mask);
  if (!map.Has("tool")) map.Fail("tool", "is missing");
  map.RejectUnknownKeys();
}

// The optional `gravity:` block (docs/formats.md): masses for joint elasticity and, after a
// calibration with it, the compliance per joint.
void ReadGravity(StrictMap map, RobotModel& model) {
  const std::size_t n = model.JointCount();
  auto values = [&](const std::string& key, bool required, bool positive) {
    const auto list = required ? map.Required<std::vector<double>>(key)
                               : map.Optional<std::vector<double>>(key, {});
    if (!list.empty() && list.size() != n)
      map.Fail(key, "has " + std::to_string(list.size()) + " entries, expected one per joint (" +
                        std::to_string(n) + ")");
    for (double v : list) {  // a calibrated compliance may come out negative on noisy data
      if (!std::isfinite(v) || (positive && !(v > 0)))
        map.Fail(key, positive ? "must hold finite numbers > 0" : "must hold finite numbers");
    }
    return list;
  };
  model.gravity.link_masses = values("link_masses_kg", true, true);
  model.gravity.sensor_mass = map.Optional<double>("sensor_mass_kg", 0.0);
  if (!std::isfinite(model.gravity.sensor_mass) || model.gravity.sensor_mass < 0)
    map.Fail("sensor_mass_kg", "must be a finite number >= 0");
  model.compliance = values("compliance_rad_per_nm", false, false);
  model.gravity.compliance_sd = values("compliance_uncertainty_rad_per_nm", false, false);
  for (double v : model.gravity.compliance_sd) {
    if (v < 0) map.Fail("compliance_uncertainty_rad_per_nm", "must hold numbers >= 0");
  }
  map.RejectUnknownKeys();
}

// The optional `links:` block (docs/formats.md): the links' radius as capsules.
void ReadLinks(StrictMap map, RobotModel& model) {
  model.link_radius = map.Required<double>("radius_m");
  if (!(model.link_radius > 0 && model.link_radius <= RobotModel::kMaxLinkRadius))
    map.Fail("radius_m", "must be a number in (0, " + Number(RobotModel::kMaxLinkRadius) + "] m");
  map.RejectUnknownKeys();
}

ModelFile ReadDocument(StrictMap& map) {
  ModelFile out;
  RobotModel& model = out.model;
  model.name = map.Required<std::string>("name");
  const auto joints = map.Sequence("joints");
  if (joints.empty()) map.Fail("joints", "must list at least one joint");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    model.joints.push_back(
        ReadJoint(StrictMap(joints[i], "joints[" + std::to_string(i) + "]", map.file())));
  }
  model.base = ReadFull(map.Map("base"));
  const auto segments = map.Sequence("segments", /*required=*/joints.size() > 1);
  if (segments.size() + 1 != joints.size()) {
    map.Fail("segments", "has " + std::to_string(segments.size()) + " entries, expected " +
                             std::to_string(joints.size() - 1) + " for " +
                             std::to_string(joints.size()) + " joints");
  }
  for (std::size_t i = 0; i < segments.size(); ++i) {
    model.segments.push_back(
        ReadSegment(StrictMap(segments[i], "segments[" + std::to_string(i) + "]", map.file())));
  }
  model.tool = ReadFull(map.Map("tool"));
  if (map.Has("gravity")) ReadGravity(map.Map("gravity"), model);
  if (map.Has("links")) ReadLinks(map.Map("links"), model);
  if (map.Has("calibrate")) {
    ReadMask(map.Map("calibrate"), model);
    out.mask_given = true;
  } else {
    model.mask = DefaultMask(model);
  }
  if (const YAML::Node calibration = map.Raw("calibration"); calibration) {
    YAML::Emitter emitter;
    emitter << calibration;
    out.calibration_yaml = emitter.c_str();
  }
  return out;
}

std::string FullLine(const FullTransformParams& p) {
  return "{alpha: " + Number(p.alpha) + ", beta: " + Number(p.beta) +
         ", gamma: " + Number(p.gamma) + ", x: " + Number(p.x) + ", y: " + Number(p.y) +
         ", z: " + Number(p.z) + "}";
}

template <std::size_t N>
std::string MaskList(const std::vector<bool>& mask, std::size_t offset,
                     const std::array<const char*, N>& keys) {
  std::string out = "[";
  bool first = true;
  for (std::size_t i = 0; i < N; ++i) {
    if (!mask[offset + i]) continue;
    out += (first ? "" : ", ") + std::string(keys[i]);
    first = false;
  }
  return out + "]";
}

}  // namespace

Expected<ModelFile> ParseModelFile(const std::string& text, const std::string& name) {
  return yaml::ParseDocument<ModelFile>(text, name, ReadDocument);
}

Expected<ModelFile> ReadModelFile(const std::string& path) {
  return yaml::ReadDocumentFile<ModelFile>(path, ReadDocument);
}

std::string FormatModelFile(const RobotModel& model, const std::string& calibration_yaml) {
  std::ostringstream out;
  out << "name: " << Text(model.name) << "\n";
  out << "joints:            # base to tip; limits in rad, rad/s, rad/s^2 (m for prismatic)\n";
  for (const auto& j : model.joints) {
    out << "  - {name: " << Text(j.name) << ", type: " << kJointTypeNames.Name(j.type)
        << ", lower: " << Number(j.lower) << ", upper: " << Number(j.upper)
        << ", max_velocity: " << Number(j.max_velocity)
        << ", max_acceleration: " << Number(j.max_acceleration) << "}\n";
  }
  out << "base: " << FullLine(model.base) << "   # st(s_0), m and rad\n";
  if (!model.segments.empty()) {
    out << "segments:          # st(s_1) .. st(s_{n-1})\n";
    for (const auto& s : model.segments) {
      out << "  - {alpha: " << Number(s.alpha) << ", beta: " << Number(s.beta)
          << ", x: " << Number(s.x) << ", y: " << Number(s.y) << "}\n";
    }
  }
  out << "tool: " << FullLine(model.tool) << "   # st(s_n), last joint to sensor\n";
  if (model.gravity.Present()) {
    out << "gravity:           # joint elasticity (docs/formats.md)\n  link_masses_kg: "
        << NumberList(model.gravity.link_masses)
        << "\n  sensor_mass_kg: " << Number(model.gravity.sensor_mass) << "\n";
    if (!model.compliance.empty())
      out << "  compliance_rad_per_nm: " << NumberList(model.compliance) << "\n";
    if (!model.gravity.compliance_sd.empty()) {
      out << "  compliance_uncertainty_rad_per_nm: " << NumberList(model.gravity.compliance_sd)
          << "\n";
    }
  }
  if (model.link_radius > 0) {
    out << "links: {radius_m: " << Number(model.link_radius)
        << "}   # the links as capsules (docs/formats.md)\n";
  }
  if (model.mask.size() == model.ParameterCount()) {
    out << "calibrate:\n  segments: [";
    for (std::size_t i = 0; i < model.segments.size(); ++i) {
      out << (i ? ", " : "") << MaskList(model.mask, SegmentOffset(i), kSegmentKeys);
    }
    out << "]\n  tool: " << MaskList(model.mask, ToolOffset(model.JointCount()), kFullKeys) << "\n";
  }
  if (!calibration_yaml.empty()) {
    out << "calibration:\n";
    std::istringstream lines(calibration_yaml);
    for (std::string line; std::getline(lines, line);) out << "  " << line << "\n";
  }
  return out.str();
}

Status WriteModelFile(const std::string& path, const RobotModel& model,
                      const std::string& calibration_yaml) {
  if (const std::string problem = CheckConsistency(model); !problem.empty()) {
    return Error{path + ": refusing to write an inconsistent model: " + problem};
  }
  return WriteFileAtomically(path, FormatModelFile(model, calibration_yaml));
}

}  // namespace selfcal
