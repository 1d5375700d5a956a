#include "core/calib/edge_filter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace selfcal::calib {

std::vector<double> NormalOverlapSums(const ProjectedCloud& cloud, int n, int m) {
  const long rows = static_cast<long>(cloud.rows);
  const long cols = static_cast<long>(cloud.cols);
  // The normals with 0 where there is none: such a neighbour adds |0| = +0.0, which leaves the
  // sum as it is, and such a cell's own sum stays +0.0. So a row's sums run over contiguous
  // columns (the compiler vectorizes them) and equal, bit for bit, the sums over the window's
  // neighbours with a normal, in the same order (a, then b).
  const std::size_t count = cloud.keep.size();
  std::vector<float> nx(count), ny(count), nz(count);
  for (std::size_t i = 0; i < count; ++i) {
    const bool has = cloud.HasNormal(i);
    nx[i] = has ? cloud.nx[i] : 0.0f;
    ny[i] = has ? cloud.ny[i] : 0.0f;
    nz[i] = has ? cloud.nz[i] : 0.0f;
  }
  std::vector<double> sums(count, 0.0);
  for (long r = 0; r < rows; ++r) {
    const std::size_t row = static_cast<std::size_t>(r * cols);
    const float *vx = nx.data() + row, *vy = ny.data() + row, *vz = nz.data() + row;
    double* overlap = sums.data() + row;
    for (long a = -n; a <= n; ++a) {
      const long rr = r + a;
      if (rr < 0 || rr >= rows) continue;
      for (long b = -m; b <= m; ++b) {
        // The neighbour of column c is column c + b of row rr, within the grid.
        const long offset = rr * cols + b;
        const long first = std::max(0L, -b), last = std::min(cols, cols - b);
        for (long c = first; c < last; ++c) {
          const std::size_t k = static_cast<std::size_t>(offset + c);
          // Eigen's Vector3f::dot, term for term: x x' + (y y' + z z').
          const float dot = vx[c] * nx[k] + (vy[c] * ny[k] + vz[c] * nz[k]);
          overlap[c] += std::abs(static_cast<double>(dot));
        }
      }
    }
  }
  return sums;
}

void FilterNoiseAndEdges(ProjectedCloud& cloud, int n, int m, double g_min) {
  const double window = static_cast<double>((2 * n + 1) * (2 * m + 1));
  const std::vector<double> overlap = NormalOverlapSums(cloud, n, m);
  for (std::size_t i = 0; i < cloud.keep.size(); ++i)
    cloud.keep[i] = cloud.HasNormal(i) && overlap[i] / window >= g_min ? 1 : 0;
  MarkCoverageBoundary(cloud);
}

namespace {

// Per cell, how many cells of `mask` lie in the window of rows r +- a, columns c +- b (cells
// outside the grid count as `outside`): two passes of running sums.
std::vector<int> WindowCounts(const std::vector<std::uint8_t>& mask, long rows, long cols, long a,
                              long b, int outside) {
  std::vector<int> along_cols(mask.size()), counts(mask.size());
  for (long r = 0; r < rows; ++r) {
    for (long c = 0; c < cols; ++c) {
      int sum = 0;
      for (long cc = c - b; cc <= c + b; ++cc)
        sum += (cc < 0 || cc >= cols) ? outside : mask[static_cast<std::size_t>(r * cols + cc)];
      along_cols[static_cast<std::size_t>(r * cols + c)] = sum;
    }
  }
  const int row_outside = outside * static_cast<int>(2 * b + 1);
  for (long r = 0; r < rows; ++r) {
    for (long c = 0; c < cols; ++c) {
      int sum = 0;
      for (long rr = r - a; rr <= r + a; ++rr)
        sum += (rr < 0 || rr >= rows) ? row_outside
                                      : along_cols[static_cast<std::size_t>(rr * cols + c)];
      counts[static_cast<std::size_t>(r * cols + c)] = sum;
    }
  }
  return counts;
}

// The measured surface: cells with a measurement whose measured 4-neighbours lie within the
// step of it (a larger step is a depth discontinuity: the scan sees two surfaces there).
std::vector<std::uint8_t> MeasuredSurface(const Dataset& dataset, const ProjectedCloud& cloud,
                                          const SurfaceStep& step) {
  const long rows = static_cast<long>(cloud.rows);
  const long cols = static_cast<long>(cloud.cols);
  std::vector<float> range(cloud.keep.size(), 0.0f);
  for (std::size_t i = 0; i < range.size(); ++i) {
    if (!cloud.Valid(i)) continue;
    range[i] = (cloud.Point(i) - cloud.Origin(dataset.PoseOf(i))).norm();
  }
  // The scan's angular pitch: the median distance of measured row neighbours over their range.
  std::vector<float> pitches;
  for (long r = 0; r < rows; ++r) {
    for (long c = 0; c + 1 < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r * cols + c);
      if (cloud.Valid(i) && cloud.Valid(i + 1) && range[i] > 0)
        pitches.push_back((cloud.Point(i + 1) - cloud.Point(i)).norm() / range[i]);
    }
  }
  float pitch = 0.0f;
  if (!pitches.empty()) {
    std::nth_element(pitches.begin(), pitches.begin() + pitches.size() / 2, pitches.end());
    pitch = pitches[pitches.size() / 2];
  }
  std::vector<float> limit(range.size(), 0.0f);
  for (std::size_t i = 0; i < limit.size(); ++i)
    limit[i] = step.base + (step.per_range + step.pitches * pitch) * range[i];
  std::vector<std::uint8_t> smooth(cloud.keep.size(), 0);
  for (long r = 0; r < rows; ++r) {
    for (long c = 0; c < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r * cols + c);
      if (!cloud.Valid(i)) continue;
      bool jump = false;
      const long neighbours[4][2] = {{r - 1, c}, {r + 1, c}, {r, c - 1}, {r, c + 1}};
      for (const auto& [rr, cc] : neighbours) {
        if (rr < 0 || rr >= rows || cc < 0 || cc >= cols) continue;
        const std::size_t k = static_cast<std::size_t>(rr * cols + cc);
        if (!cloud.Valid(k)) continue;
        const float allowed = std::max(limit[i], limit[k]);
        jump |= (cloud.Point(k) - cloud.Point(i)).squaredNorm() > allowed * allowed;
      }
      smooth[i] = jump ? 0 : 1;
    }
  }
  return smooth;
}

}  // namespace

void MarkSurfaceBoundary(const Dataset& dataset, ProjectedCloud& cloud, int window_rows,
                         int window_cols, const SurfaceStep& step) {
  const long rows = static_cast<long>(cloud.rows);
  const long cols = static_cast<long>(cloud.cols);
  const std::vector<int> smooth =
      WindowCounts(MeasuredSurface(dataset, cloud, step), rows, cols, window_rows, window_cols, 0);
  const int window = (2 * window_rows + 1) * (2 * window_cols + 1);
  cloud.boundary.assign(cloud.keep.size(), 0);
  for (std::size_t i = 0; i < cloud.keep.size(); ++i)
    cloud.boundary[i] = cloud.keep[i] && smooth[i] < window ? 1 : 0;
}

void MarkCoverageBoundary(ProjectedCloud& cloud) {
  const long rows = static_cast<long>(cloud.rows);
  const long cols = static_cast<long>(cloud.cols);
  cloud.boundary.assign(cloud.keep.size(), 0);
  const std::vector<std::uint8_t>& coverage = cloud.keep;
  for (long r = 0; r < rows; ++r) {
    for (long c = 0; c < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r * cols + c);
      if (!cloud.keep[i]) continue;
      bool border = false;
      for (long a = -1; a <= 1 && !border; ++a) {
        for (long b = -1; b <= 1 && !border; ++b) {
          const long rr = r + a, cc = c + b;
          border = rr < 0 || rr >= rows || cc < 0 || cc >= cols ||
                   !coverage[static_cast<std::size_t>(rr * cols + cc)];
        }
      }
      cloud.boundary[i] = border ? 1 : 0;
    }
  }
}

}  // namespace selfcal::calib
