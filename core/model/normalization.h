// The paper's "Normalization": translations divided by a scale s so that angular and
// translational parameters weigh alike in the optimization.
//
//   k^ = (alpha_0, beta_0, x_0 / s, y_0 / s, ..., alpha_n, beta_n, gamma, x_n / s, y_n / s, z / s)
//   j^ = j with prismatic joint positions divided by s,  D^ = D / s
//
// With both applied, tr(k^, j^) has the rotation of tr(k, j) and its translation divided by s,
// so tr(k^, j^) * (p / s) = tr(k, j) * p / s: the optimization runs in units of s.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <span>

#include "core/model/robot_model.h"

namespace selfcal {

// True when flat parameter `index` of a chain with `joint_count` joints is a translation (x, y, z
// of st(s_0) and st(s_n), x and y of the segments). Same answer as IsTranslationParameter().
bool IsTranslationIndex(std::size_t index, std::size_t joint_count);

// The paper's s: the mean distance of base-frame points from the base origin (points of the first
// dataset projected with k_init). Non-finite points are skipped; 0 when none is finite.
double NormalizationScale(std::span<const Eigen::Vector3d> points_base);

// Multiplies every translation parameter by `factor` in place.
void ScaleTranslationParameters(std::span<double> parameters, std::size_t joint_count,
                                double factor);
// k -> k^ (divide translations by s) and back. s must be positive and finite (abort otherwise).
void NormalizeTranslationParameters(std::span<double> parameters, std::size_t joint_count,
                                    double s);
void DenormalizeTranslationParameters(std::span<double> parameters, std::size_t joint_count,
                                      double s);

// j -> j^ (divide prismatic joint positions by s) and back; revolute positions are unchanged.
void NormalizeJointPositions(std::span<double> joint_positions,
                             std::span<const JointType> joint_types, double s);
void DenormalizeJointPositions(std::span<double> joint_positions,
                               std::span<const JointType> joint_types, double s);

}  // namespace selfcal
