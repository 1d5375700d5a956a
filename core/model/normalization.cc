#include "core/model/normalization.h"

#include <cmath>
#include <cstdlib>
#include <iostream>

namespace selfcal {
namespace {

void CheckScale(double s, const char* caller) {
  if (!(s > 0) || !std::isfinite(s)) {
    std::cerr << "selfcal: " << caller << ": scale must be positive and finite, got " << s << "\n";
    std::abort();
  }
}

void ScaleJoints(std::span<double> joint_positions, std::span<const JointType> joint_types,
                 double factor) {
  if (joint_positions.size() != joint_types.size()) {
    std::cerr << "selfcal: joint normalization: " << joint_positions.size() << " positions for "
              << joint_types.size() << " joints\n";
    std::abort();
  }
  for (std::size_t i = 0; i < joint_positions.size(); ++i) {
    if (joint_types[i] == JointType::kPrismatic) joint_positions[i] *= factor;
  }
}

}  // namespace

bool IsTranslationIndex(std::size_t index, std::size_t joint_count) {
  const std::size_t tool_offset = ToolOffset(joint_count);
  if (index < kFullTransformParamCount) return index >= 3;
  if (index >= tool_offset) return index - tool_offset >= 3;
  return (index - kFullTransformParamCount) % kSegmentParamCount >= 2;
}

double NormalizationScale(std::span<const Eigen::Vector3d> points_base) {
  // A fixed-order sum: the same input gives the same s, bit for bit.
  double sum = 0;
  std::size_t count = 0;
  for (const auto& p : points_base) {
    if (!p.allFinite()) continue;
    sum += p.norm();
    ++count;
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

void ScaleTranslationParameters(std::span<double> parameters, std::size_t joint_count,
                                double factor) {
  const std::size_t expected =
      2 * kFullTransformParamCount + kSegmentParamCount * (joint_count - 1);
  if (joint_count == 0 || parameters.size() != expected) {
    std::cerr << "selfcal: ScaleTranslationParameters: " << parameters.size() << " parameters for "
              << joint_count << " joints\n";
    std::abort();
  }
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    if (IsTranslationIndex(i, joint_count)) parameters[i] *= factor;
  }
}

void NormalizeTranslationParameters(std::span<double> parameters, std::size_t joint_count,
                                    double s) {
  CheckScale(s, "NormalizeTranslationParameters");
  ScaleTranslationParameters(parameters, joint_count, 1.0 / s);
}

void DenormalizeTranslationParameters(std::span<double> parameters, std::size_t joint_count,
                                      double s) {
  CheckScale(s, "DenormalizeTranslationParameters");
  ScaleTranslationParameters(parameters, joint_count, s);
}

void NormalizeJointPositions(std::span<double> joint_positions,
                             std::span<const JointType> joint_types, double s) {
  CheckScale(s, "NormalizeJointPositions");
  ScaleJoints(joint_positions, joint_types, 1.0 / s);
}

void DenormalizeJointPositions(std::span<double> joint_positions,
                               std::span<const JointType> joint_types, double s) {
  CheckScale(s, "DenormalizeJointPositions");
  ScaleJoints(joint_positions, joint_types, s);
}

}  // namespace selfcal
