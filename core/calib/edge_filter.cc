#include "core/calib/edge_filter.h"

#include <cmath>

namespace selfcal::calib {

void FilterNoiseAndEdges(ProjectedCloud& cloud, int n, int m, double g_min) {
  const long rows = static_cast<long>(cloud.rows);
  const long cols = static_cast<long>(cloud.cols);
  const double window = static_cast<double>((2 * n + 1) * (2 * m + 1));
  for (long r = 0; r < rows; ++r) {
    for (long c = 0; c < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r * cols + c);
      cloud.keep[i] = 0;
      if (!cloud.HasNormal(i)) continue;
      const Eigen::Vector3f v = cloud.Normal(i);
      double overlap = 0.0;
      for (long a = -n; a <= n; ++a) {
        const long rr = r + a;
        if (rr < 0 || rr >= rows) continue;
        for (long b = -m; b <= m; ++b) {
          const long cc = c + b;
          if (cc < 0 || cc >= cols) continue;
          const std::size_t k = static_cast<std::size_t>(rr * cols + cc);
          if (!cloud.HasNormal(k)) continue;
          overlap += std::abs(static_cast<double>(v.dot(cloud.Normal(k))));
        }
      }
      cloud.keep[i] = overlap / window >= g_min ? 1 : 0;
    }
  }
  MarkCoverageBoundary(cloud);
}

void MarkCoverageBoundary(ProjectedCloud& cloud) {
  const long rows = static_cast<long>(cloud.rows);
  const long cols = static_cast<long>(cloud.cols);
  cloud.boundary.assign(cloud.keep.size(), 0);
  for (long r = 0; r < rows; ++r) {
    for (long c = 0; c < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r * cols + c);
      if (!cloud.keep[i]) continue;
      bool border = false;
      for (long a = -1; a <= 1 && !border; ++a) {
        for (long b = -1; b <= 1 && !border; ++b) {
          const long rr = r + a, cc = c + b;
          border = rr < 0 || rr >= rows || cc < 0 || cc >= cols ||
                   !cloud.keep[static_cast<std::size_t>(rr * cols + cc)];
        }
      }
      cloud.boundary[i] = border ? 1 : 0;
    }
  }
}

}  // namespace selfcal::calib
