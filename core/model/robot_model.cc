#include "core/model/robot_model.h"

#include <array>

namespace selfcal {
namespace {

constexpr std::array<const char*, 6> kFullNames = {"alpha", "beta", "gamma", "x", "y", "z"};
constexpr std::array<const char*, 4> kSegmentNames = {"alpha", "beta", "x", "y"};

void PutFull(const FullTransformParams& p, std::vector<double>& out) {
  out.insert(out.end(), {p.alpha, p.beta, p.gamma, p.x, p.y, p.z});
}

FullTransformParams GetFull(const std::vector<double>& v, std::size_t offset) {
  return {v[offset], v[offset + 1], v[offset + 2], v[offset + 3], v[offset + 4], v[offset + 5]};
}

}  // namespace

std::vector<double> ToParameterVector(const RobotModel& model) {
  std::vector<double> out;
  out.reserve(model.ParameterCount());
  PutFull(model.base, out);
  for (const auto& s : model.segments) out.insert(out.end(), {s.alpha, s.beta, s.x, s.y});
  PutFull(model.tool, out);
  return out;
}

void FromParameterVector(const std::vector<double>& parameters, RobotModel& model) {
  model.base = GetFull(parameters, kBaseOffset);
  for (std::size_t i = 0; i < model.segments.size(); ++i) {
    const std::size_t o = SegmentOffset(i);
    model.segments[i] = {parameters[o], parameters[o + 1], parameters[o + 2], parameters[o + 3]};
  }
  model.tool = GetFull(parameters, ToolOffset(model.JointCount()));
}

std::string ParameterName(const RobotModel& model, std::size_t index) {
  const std::size_t tool_offset = ToolOffset(model.JointCount());
  if (index < kFullTransformParamCount) return std::string("base.") + kFullNames[index];
  if (index >= tool_offset) {
    const std::string last = model.joints.empty() ? "J?" : model.joints.back().name;
    return last + "->tool." + kFullNames[index - tool_offset];
  }
  const std::size_t segment = (index - kFullTransformParamCount) / kSegmentParamCount;
  const std::size_t field = (index - kFullTransformParamCount) % kSegmentParamCount;
  return model.joints[segment].name + "->" + model.joints[segment + 1].name + "." +
         kSegmentNames[field];
}

bool IsTranslationParameter(const RobotModel& model, std::size_t index) {
  return IsTranslationIndex(index, model.JointCount());
}

bool IsTranslationIndex(std::size_t index, std::size_t joint_count) {
  const std::size_t tool_offset = ToolOffset(joint_count);
  if (index < kFullTransformParamCount) return index >= 3;
  if (index >= tool_offset) return index - tool_offset >= 3;
  return (index - kFullTransformParamCount) % kSegmentParamCount >= 2;
}

std::vector<bool> DefaultMask(const RobotModel& model) {
  std::vector<bool> mask(model.ParameterCount(), false);
  for (std::size_t i = 0; i < model.segments.size(); ++i) {
    const std::size_t o = SegmentOffset(i);
    // Segment i connects joint i and joint i + 1; x and y only exist for revolute successors.
    const bool prismatic = model.joints[i + 1].type == JointType::kPrismatic;
    mask[o + 0] = true;                 // alpha
    mask[o + 1] = i > 0;                // beta: not observable on the first segment
    mask[o + 2] = !prismatic;           // x
    mask[o + 3] = i > 0 && !prismatic;  // y: not observable on the first segment
  }
  const std::size_t t = ToolOffset(model.JointCount());
  for (std::size_t i = 0; i < kFullTransformParamCount; ++i) mask[t + i] = true;
  return mask;
}

std::string CheckConsistency(const RobotModel& model) {
  if (model.joints.empty()) return "a robot needs at least one joint";
  if (model.segments.size() + 1 != model.joints.size()) {
    return "expected " + std::to_string(model.joints.size() - 1) + " segments for " +
           std::to_string(model.joints.size()) + " joints, got " +
           std::to_string(model.segments.size());
  }
  if (model.mask.size() != model.ParameterCount()) {
    return "mask has " + std::to_string(model.mask.size()) + " entries, expected " +
           std::to_string(model.ParameterCount());
  }
  for (const auto& joint : model.joints) {
    if (!(joint.lower < joint.upper))
      return "joint " + joint.name + ": lower limit not below upper";
    if (!(joint.max_velocity > 0) || !(joint.max_acceleration > 0)) {
      return "joint " + joint.name + ": velocity and acceleration limits must be positive";
    }
  }
  if (model.gravity.Present() && model.gravity.link_masses.size() != model.joints.size()) {
    return "gravity: " + std::to_string(model.gravity.link_masses.size()) + " link masses for " +
           std::to_string(model.joints.size()) + " joints";
  }
  if (!model.compliance.empty() && model.compliance.size() != model.joints.size()) {
    return "gravity: " + std::to_string(model.compliance.size()) + " compliances for " +
           std::to_string(model.joints.size()) + " joints";
  }
  if (!(model.link_radius >= 0 && model.link_radius <= RobotModel::kMaxLinkRadius)) {
    return "links: radius_m must be within 0 .. 0.5 m";
  }
  return {};
}

}  // namespace selfcal
