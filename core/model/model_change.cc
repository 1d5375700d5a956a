#include "core/model/model_change.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

namespace selfcal {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180;

// How far the fit goes with nothing changed: RMS over draws of the calibrated parameters from
// their covariance, each fitted against the calibrated model itself. Empty when unknown.
struct NullSpread {
  std::vector<double> offsets;  // per joint
  double mount_shift_m = 0, mount_turn_rad = 0, geometry_m = 0;
};

NullSpread NullDistribution(const RobotModel& calibrated, const Eigen::MatrixXd& covariance,
                            const std::vector<std::size_t>& all_free,
                            const ChangeThresholds& thresholds) {
  const auto n = static_cast<Eigen::Index>(all_free.size());
  if (n == 0 || covariance.rows() != n || covariance.cols() != n || thresholds.draws < 1) return {};
  std::vector<std::size_t> free;
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (all_free[static_cast<std::size_t>(i)] >= calibrated.ParameterCount()) continue;
    free.push_back(all_free[static_cast<std::size_t>(i)]);
    rows.push_back(i);
  }
  const auto k = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd kinematic(k, k);
  for (Eigen::Index a = 0; a < k; ++a) {
    for (Eigen::Index b = 0; b < k; ++b) {
      kinematic(a, b) =
          covariance(rows[static_cast<std::size_t>(a)], rows[static_cast<std::size_t>(b)]);
    }
  }
  // A square root of the covariance that tolerates a semi-definite one (unobservable directions).
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(kinematic);
  const Eigen::MatrixXd root =
      eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  std::mt19937_64 random(thresholds.seed);
  std::normal_distribution<double> normal;
  const std::vector<double> parameters = ToParameterVector(calibrated);
  NullSpread spread;
  spread.offsets.assign(calibrated.JointCount(), 0.0);
  for (int d = 0; d < thresholds.draws; ++d) {
    Eigen::VectorXd z(k);
    for (Eigen::Index i = 0; i < k; ++i) z[i] = normal(random);
    const Eigen::VectorXd delta = root * z;
    std::vector<double> drawn = parameters;
    for (Eigen::Index i = 0; i < k; ++i) drawn[free[static_cast<std::size_t>(i)]] += delta[i];
    RobotModel model = calibrated;
    FromParameterVector(drawn, model);
    const JointOffsetFit fit =
        FitJointOffsets(calibrated, model, 100, thresholds.seed + static_cast<std::uint64_t>(d));
    for (std::size_t j = 0; j < fit.offsets.size(); ++j) {
      spread.offsets[j] += fit.offsets[j] * fit.offsets[j];
    }
    spread.mount_shift_m += fit.mount_shift_m * fit.mount_shift_m;
    spread.mount_turn_rad += fit.mount_turn_rad * fit.mount_turn_rad;
    spread.geometry_m += fit.rms_position_m * fit.rms_position_m;
  }
  const auto rms = [&](double sum) { return std::sqrt(sum / thresholds.draws); };
  for (double& offset : spread.offsets) offset = rms(offset);
  spread.mount_shift_m = rms(spread.mount_shift_m);
  spread.mount_turn_rad = rms(spread.mount_turn_rad);
  spread.geometry_m = rms(spread.geometry_m);
  return spread;
}

std::string Format(const char* format, double a, double b = 0, double c = 0) {
  char text[160];
  std::snprintf(text, sizeof(text), format, a, b, c);
  return text;
}

ChangeFinding JointFinding(const JointSpec& joint, double offset, double std_dev) {
  ChangeFinding finding{ChangeKind::kJointZero, joint.name, offset, 0, std_dev, 0, ""};
  const bool prismatic = joint.type == JointType::kPrismatic;
  const double unit = prismatic ? 1e-3 : kDegree;
  finding.text = "joint " + joint.name + " zero offset moved " +
                 Format(prismatic ? "%.3f mm" : "%.3f deg", offset / unit) +
                 (std_dev > 0 ? Format(" (+-%.3f; mastering lost?)", std_dev / unit)
                              : std::string(" (mastering lost?)"));
  return finding;
}

bool Exceeds(double value, double floor, double null_spread, double sigmas) {
  return std::abs(value) > std::max(floor, sigmas * null_spread);
}

}  // namespace

const char* ChangeKindName(ChangeKind kind) { return kChangeKindNames.Name(kind); }

std::string ModelChange::Summary() const {
  if (findings.empty()) return "no significant change";
  // The largest change first; many moved zeros are one phrase (with changed links they are
  // mostly what the fit used to absorb the change, not a lost mastering).
  std::string text;
  const auto add = [&](const std::string& part) { text += (text.empty() ? "" : "; ") + part; };
  for (ChangeKind kind : {ChangeKind::kLinkGeometry, ChangeKind::kSensorMount}) {
    for (const ChangeFinding& finding : findings) {
      if (finding.kind == kind) add(finding.text);
    }
  }
  std::vector<const ChangeFinding*> zeros;
  for (const ChangeFinding& finding : findings) {
    if (finding.kind == ChangeKind::kJointZero) zeros.push_back(&finding);
  }
  if (zeros.size() <= 2) {
    for (const ChangeFinding* zero : zeros) add(zero->text);
    return text;
  }
  const ChangeFinding* largest = *std::max_element(
      zeros.begin(), zeros.end(), [](const ChangeFinding* a, const ChangeFinding* b) {
        return std::abs(a->value) < std::abs(b->value);
      });
  add(Format("zero offsets of %.0f joints moved, up to %.3f deg", static_cast<double>(zeros.size()),
             std::abs(largest->value) / kDegree) +
      " (" + largest->joint + ")");
  return text;
}

ModelChange DescribeModelChange(const RobotModel& installed, const RobotModel& calibrated,
                                const Eigen::MatrixXd& covariance,
                                const std::vector<std::size_t>& free,
                                const ChangeThresholds& thresholds) {
  if (!CheckComparable(installed, calibrated).empty()) std::abort();
  ModelChange change;
  change.fit = FitJointOffsets(installed, calibrated, 200, thresholds.seed);
  change.kept_installed = CompareModels(calibrated, installed, 500, thresholds.seed);
  NullSpread spread = NullDistribution(calibrated, covariance, free, thresholds);
  if (spread.offsets.empty()) spread.offsets.assign(calibrated.JointCount(), 0.0);
  const double sigmas = thresholds.sigmas;
  for (std::size_t j = 0; j < calibrated.JointCount(); ++j) {
    const double offset = change.fit.offsets[j];
    if (Exceeds(offset, thresholds.joint_offset_rad, spread.offsets[j], sigmas)) {
      change.findings.push_back(JointFinding(calibrated.joints[j], offset, spread.offsets[j]));
    }
  }
  const JointOffsetFit& fit = change.fit;
  if (Exceeds(fit.mount_shift_m, thresholds.mount_shift_m, spread.mount_shift_m, sigmas) ||
      Exceeds(fit.mount_turn_rad, thresholds.mount_turn_rad, spread.mount_turn_rad, sigmas)) {
    change.findings.push_back({ChangeKind::kSensorMount, "", fit.mount_shift_m, fit.mount_turn_rad,
                               spread.mount_shift_m, spread.mount_turn_rad,
                               Format("sensor mount moved %.1f mm / %.2f deg (bumped?)",
                                      fit.mount_shift_m * 1e3, fit.mount_turn_rad / kDegree)});
  }
  if (Exceeds(fit.rms_position_m, thresholds.geometry_m, spread.geometry_m, sigmas)) {
    change.findings.push_back(
        {ChangeKind::kLinkGeometry, "", fit.rms_position_m, 0, spread.geometry_m, 0,
         Format("link geometry changed: %.2f mm RMS at the sensor that zero offsets and the mount "
                "do not explain (collision?)",
                fit.rms_position_m * 1e3)});
  }
  return change;
}

}  // namespace selfcal
