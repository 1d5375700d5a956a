#include "core/calib/pose_knots.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/calib/parallel.h"

namespace selfcal::calib {

namespace {

// Position of joints `p` on the segment from `a` to `b` (0 at a, 1 at b), and how far it lies
// off that segment (largest joint difference).
struct OnSegment {
  double alpha = 0;
  double deviation = 0;
};

OnSegment Locate(const double* a, const double* b, const double* p, std::size_t joints) {
  double dot = 0, length_squared = 0;
  for (std::size_t j = 0; j < joints; ++j) {
    dot += (p[j] - a[j]) * (b[j] - a[j]);
    length_squared += (b[j] - a[j]) * (b[j] - a[j]);
  }
  OnSegment result;
  result.alpha = length_squared > 0 ? std::clamp(dot / length_squared, 0.0, 1.0) : 0.0;
  for (std::size_t j = 0; j < joints; ++j) {
    const double expected = a[j] + result.alpha * (b[j] - a[j]);
    result.deviation = std::max(result.deviation, std::abs(p[j] - expected));
  }
  return result;
}

double LargestStep(const double* a, const double* b, std::size_t joints) {
  double largest = 0;
  for (std::size_t j = 0; j < joints; ++j) largest = std::max(largest, std::abs(b[j] - a[j]));
  return largest;
}

}  // namespace

std::vector<std::uint32_t> PosesInTimeOrder(const Dataset& dataset) {
  std::vector<std::uint32_t> order;
  order.reserve(dataset.PoseCount());
  switch (dataset.layout) {
    case PoseLayout::kOnePerScan:
      order.push_back(0);
      break;
    case PoseLayout::kOnePerColumn:
      for (std::size_t c = 0; c < dataset.cols; ++c) order.push_back(static_cast<std::uint32_t>(c));
      break;
    case PoseLayout::kOnePerPoint:
      for (std::size_t c = 0; c < dataset.cols; ++c) {
        for (std::size_t r = 0; r < dataset.rows; ++r)
          order.push_back(static_cast<std::uint32_t>(r * dataset.cols + c));
      }
      break;
  }
  return order;
}

PoseKnots BuildPoseKnots(const Dataset& dataset, double tolerance, double max_step) {
  const std::vector<std::uint32_t> order = PosesInTimeOrder(dataset);
  const std::size_t n = order.size();
  const std::size_t joints = dataset.joint_count;
  // The scan's joints in time order, read once: a LiDAR's may be interpolated on every read.
  std::vector<double> in_order(n * joints);
  for (std::size_t position = 0; position < n; ++position) {
    double* into = in_order.data() + position * joints;
    const double* read = dataset.JointsOfPose(order[position], into);
    if (read != into) std::copy_n(read, joints, into);
  }
  auto q = [&](std::size_t position) { return in_order.data() + position * joints; };
  std::vector<std::uint8_t> is_knot(n, 0);
  is_knot.front() = is_knot.back() = 1;

  // 1. No joint turns by more than max_step between knots.
  std::size_t a = 0;
  for (std::size_t b = 1; b < n; ++b) {
    if (LargestStep(q(a), q(b), joints) <= max_step) continue;
    if (b - 1 > a) {
      a = b - 1;
      is_knot[a] = 1;
      --b;  // look at b again from the new knot
    } else {
      a = b;
      is_knot[a] = 1;
    }
  }
  // 2. Douglas-Peucker: split a segment where its poses leave the straight line in joint space.
  std::vector<std::pair<std::size_t, std::size_t>> pending;
  std::size_t previous = 0;
  for (std::size_t p = 1; p < n; ++p) {
    if (is_knot[p]) {
      pending.emplace_back(previous, p);
      previous = p;
    }
  }
  while (!pending.empty()) {
    const auto [first, last] = pending.back();
    pending.pop_back();
    double worst = tolerance;
    std::size_t split = 0;
    for (std::size_t p = first + 1; p < last; ++p) {
      const double deviation = Locate(q(first), q(last), q(p), joints).deviation;
      if (deviation > worst) {
        worst = deviation;
        split = p;
      }
    }
    if (split == 0) continue;
    is_knot[split] = 1;
    pending.emplace_back(first, split);
    pending.emplace_back(split, last);
  }

  // 3. Every pose's segment and weight.
  PoseKnots knots;
  knots.segment.assign(dataset.PoseCount(), 0);
  knots.alpha.assign(dataset.PoseCount(), 0.0f);
  std::size_t knot_position = 0, next_position = 0;
  for (std::size_t p = 0; p < n; ++p) {
    if (is_knot[p]) {
      knots.knot_pose.push_back(order[p]);
      knot_position = p;
      next_position = p + 1;
      while (next_position < n && !is_knot[next_position]) ++next_position;
      knots.segment[order[p]] = static_cast<std::uint32_t>(knots.knot_pose.size() - 1);
      continue;
    }
    knots.segment[order[p]] = static_cast<std::uint32_t>(knots.knot_pose.size() - 1);
    knots.alpha[order[p]] =
        static_cast<float>(Locate(q(knot_position), q(next_position), q(p), joints).alpha);
  }
  return knots;
}

std::vector<PoseKnots> BuildAllPoseKnots(const std::vector<Dataset>& datasets, int threads,
                                         double max_step) {
  std::vector<PoseKnots> knots(datasets.size());
  ParallelFor(datasets.size(), threads, [&](std::size_t d) {
    knots[d] = BuildPoseKnots(datasets[d], kJointTolerance, max_step);
  });
  return knots;
}

}  // namespace selfcal::calib
