#include "core/trajectory/scan_program.h"

namespace selfcal::trajectory {

ScanStep LineSweep(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double speed,
                   int scan_index) {
  return {.kind = ScanStep::Kind::kSweep,
          .target = to,
          .from = from,
          .speed = speed,
          .scan_index = scan_index};
}

ScanStep OneAxisSweep(const Eigen::VectorXd& posture, int joint, double from_angle, double to_angle,
                      double speed, int scan_index) {
  Eigen::VectorXd from = posture;
  Eigen::VectorXd to = posture;
  from[joint] = from_angle;
  to[joint] = to_angle;
  return LineSweep(from, to, speed, scan_index);
}

ScanStep CameraPose(const Eigen::VectorXd& configuration, double settle_time, double dwell,
                    int scan_index) {
  return {.kind = ScanStep::Kind::kMoveTo,
          .target = configuration,
          .from = {},  // a move has no run-up
          .settle_time = settle_time,
          .dwell = dwell,
          .scan_index = scan_index};
}

Expected<PlannedProgram> PlanScanProgram(const ScanProgram& program, const Eigen::VectorXd& start,
                                         const JointLimits& limits) {
  PlannedProgram planned;
  planned.trajectory = Hold(start, 1e-3);
  Eigen::VectorXd current = start;
  auto append = [&](const JointTrajectory& next, std::size_t index) -> Status {
    if (auto s = planned.trajectory.Append(next, 1e-9); !s.ok()) {
      return Error{"scan program '" + program.name + "' step " + std::to_string(index) + ": " +
                   s.error().message};
    }
    current = planned.trajectory.back().position;
    return OkStatus();
  };
  for (std::size_t index = 0; index < program.steps.size(); ++index) {
    const ScanStep& step = program.steps[index];
    const std::string where =
        "scan program '" + program.name + "' step " + std::to_string(index) + ": ";
    if (step.settle_time < 0 || step.dwell < 0) return Error{where + "negative settle or dwell"};
    if (step.kind == ScanStep::Kind::kMoveTo) {
      auto move = PointToPoint(current, step.target, limits);
      if (!move.ok()) return Error{where + move.error().message};
      if (auto s = append(*move, index); !s.ok()) return s.error();
      const double arrival = planned.trajectory.duration();
      const double still = step.settle_time + step.dwell;
      if (still > 0) {
        if (auto s = append(Hold(current, still), index); !s.ok()) return s.error();
      }
      if (step.scan_index >= 0) {
        planned.windows.push_back({step.scan_index, arrival + step.settle_time, arrival + still});
      }
      continue;
    }
    auto sweep = ConstantVelocitySweep(step.from, step.target, step.speed, limits);
    if (!sweep.ok()) return Error{where + sweep.error().message};
    auto approach = PointToPoint(current, sweep->trajectory.front().position, limits);
    if (!approach.ok()) return Error{where + "approach to the run-up: " + approach.error().message};
    if (auto s = append(*approach, index); !s.ok()) return s.error();
    const double begin = planned.trajectory.duration();
    if (auto s = append(sweep->trajectory, index); !s.ok()) return s.error();
    if (step.scan_index >= 0) {
      planned.windows.push_back(
          {step.scan_index, begin + sweep->constant_begin, begin + sweep->constant_end});
    }
  }
  return planned;
}

}  // namespace selfcal::trajectory
