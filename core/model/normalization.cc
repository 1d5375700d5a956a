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

enum class Direction { kNormalize, kDenormalize };

// Dividing (not multiplying by 1 / s) keeps a normalized value the correctly rounded quotient.
double Apply(double value, double s, Direction direction) {
  return direction == Direction::kNormalize ? value / s : value * s;
}

void ScaleParameters(std::span<double> parameters, std::size_t joint_count, double s,
                     Direction direction, const char* caller) {
  CheckScale(s, caller);
  if (joint_count == 0 || parameters.size() != ParameterCountOf(joint_count)) {
    std::cerr << "selfcal: " << caller << ": " << parameters.size() << " parameters for "
              << joint_count << " joints\n";
    std::abort();
  }
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    if (IsTranslationIndex(i, joint_count)) parameters[i] = Apply(parameters[i], s, direction);
  }
}

void ScaleJoints(std::span<double> joint_positions, std::span<const JointType> joint_types,
                 double s, Direction direction, const char* caller) {
  CheckScale(s, caller);
  if (joint_positions.size() != joint_types.size()) {
    std::cerr << "selfcal: " << caller << ": " << joint_positions.size() << " positions for "
              << joint_types.size() << " joints\n";
    std::abort();
  }
  for (std::size_t i = 0; i < joint_positions.size(); ++i) {
    if (joint_types[i] == JointType::kPrismatic) {
      joint_positions[i] = Apply(joint_positions[i], s, direction);
    }
  }
}

}  // namespace

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

void NormalizeTranslationParameters(std::span<double> parameters, std::size_t joint_count,
                                    double s) {
  ScaleParameters(parameters, joint_count, s, Direction::kNormalize,
                  "NormalizeTranslationParameters");
}

void DenormalizeTranslationParameters(std::span<double> parameters, std::size_t joint_count,
                                      double s) {
  ScaleParameters(parameters, joint_count, s, Direction::kDenormalize,
                  "DenormalizeTranslationParameters");
}

void NormalizeJointPositions(std::span<double> joint_positions,
                             std::span<const JointType> joint_types, double s) {
  ScaleJoints(joint_positions, joint_types, s, Direction::kNormalize, "NormalizeJointPositions");
}

void DenormalizeJointPositions(std::span<double> joint_positions,
                               std::span<const JointType> joint_types, double s) {
  ScaleJoints(joint_positions, joint_types, s, Direction::kDenormalize,
              "DenormalizeJointPositions");
}

}  // namespace selfcal
