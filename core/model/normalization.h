// The paper's "Normalization": translations divided by a scale s so that angular and
// translational parameters weigh alike in the optimization.
//
//   k^ = (alpha_0, beta_0, x_0 / s, y_0 / s, ..., alpha_n, beta_n, gamma, x_n / s, y_n / s, z / s)
//   j^ = j with prismatic joint positions divided by s,  D^ = D / s
//
// With both applied, tr(k^, j^) has the rotation of tr(k, j) and its translation divided by s,
// so tr(k^, j^) * (p / s) = tr(k, j) * p / s: the optimization runs in units of s. The one
// normalization: the engine (core/calib/calibrate.cc, chain.h) uses exactly these functions.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <span>

#include "core/model/robot_model.h"

namespace selfcal {

// The paper's s: the mean distance of base-frame points from the base origin (points of the first
// dataset projected with k_init). Non-finite points are skipped; 0 when none is finite.
double NormalizationScale(std::span<const Eigen::Vector3d> points_base);

// k -> k^ (divide translations by s) and back, in place. s must be positive and finite (abort
// otherwise).
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
