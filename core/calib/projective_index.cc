#include "core/calib/projective_index.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace selfcal::calib {
namespace {

// Fills the entries of `values` that `known` does not mark by linear interpolation between the
// nearest known ones (extrapolation from the two nearest at the ends). False with fewer than two.
bool FillGaps(std::vector<double>& values, const std::vector<bool>& known) {
  std::vector<std::size_t> at;
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (known[k]) at.push_back(k);
  }
  if (at.size() < 2) return false;
  std::size_t segment = 0;  // values between at[segment] and at[segment + 1]
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (known[k]) continue;
    while (segment + 2 < at.size() && at[segment + 1] < k) ++segment;
    const double k0 = static_cast<double>(at[segment]), k1 = static_cast<double>(at[segment + 1]);
    const double v0 = values[at[segment]], v1 = values[at[segment + 1]];
    values[k] = v0 + (v1 - v0) * (static_cast<double>(k) - k0) / (k1 - k0);
  }
  return true;
}

// +1 when `values` rise strictly, -1 when they fall strictly, else 0.
int Direction(const std::vector<double>& values) {
  bool rising = true, falling = true;
  for (std::size_t k = 1; k < values.size(); ++k) {
    rising = rising && values[k] > values[k - 1];
    falling = falling && values[k] < values[k - 1];
  }
  return rising ? 1 : (falling ? -1 : 0);
}

// The median ray slope (lateral / z) of every column (by_row false) or row of the valid points.
// `known` marks the lines that have one.
std::vector<double> MedianSlopes(std::size_t rows, std::size_t cols,
                                 const std::vector<float>& lateral, const std::vector<float>& z,
                                 bool by_row, std::vector<bool>& known) {
  const std::size_t lines = by_row ? rows : cols, along = by_row ? cols : rows;
  std::vector<double> slopes(lines, 0.0);
  known.assign(lines, false);
  std::vector<float> values;
  for (std::size_t line = 0; line < lines; ++line) {
    values.clear();
    for (std::size_t k = 0; k < along; ++k) {
      const std::size_t i = by_row ? line * cols + k : k * cols + line;
      if (z[i] > 0 && std::isfinite(lateral[i])) values.push_back(lateral[i] / z[i]);
    }
    if (values.empty()) continue;
    auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    slopes[line] = *middle;
    known[line] = true;
  }
  return slopes;
}

}  // namespace

ProjectiveIndex::ProjectiveIndex(std::size_t rows, std::size_t cols, const std::vector<float>& x,
                                 const std::vector<float>& y, const std::vector<float>& z,
                                 const std::vector<std::uint8_t>& keep)
    : rows_(rows), cols_(cols) {
  std::vector<bool> known_columns, known_rows;
  column_slope_ = MedianSlopes(rows, cols, x, z, false, known_columns);
  row_slope_ = MedianSlopes(rows, cols, y, z, true, known_rows);
  if (!FillGaps(column_slope_, known_columns) || !FillGaps(row_slope_, known_rows)) return;
  const int column_direction = Direction(column_slope_), row_direction = Direction(row_slope_);
  if (column_direction == 0 || row_direction == 0) return;
  columns_increasing_ = column_direction > 0;
  rows_increasing_ = row_direction > 0;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  x_.assign(rows * cols, nan);
  y_.assign(rows * cols, nan);
  z_.assign(rows * cols, nan);
  for (std::size_t i = 0; i < rows * cols; ++i) {
    if (!keep[i]) continue;
    x_[i] = x[i];
    y_[i] = y[i];
    z_[i] = z[i];
  }
  usable_ = true;
}

double ProjectiveIndex::IndexOf(const std::vector<double>& slopes, bool increasing,
                                double slope) const {
  const double sign = increasing ? 1.0 : -1.0;
  const double s = sign * slope;
  const std::size_t n = slopes.size();
  const auto after = std::lower_bound(slopes.begin(), slopes.end(), s,
                                      [sign](double value, double t) { return sign * value < t; });
  std::size_t k = static_cast<std::size_t>(after - slopes.begin());
  k = std::clamp<std::size_t>(k, 1, n - 1);  // the segment [k - 1, k], extended at the ends
  const double s0 = sign * slopes[k - 1], s1 = sign * slopes[k];
  return static_cast<double>(k - 1) + (s - s0) / (s1 - s0);
}

bool ProjectiveIndex::Pixel(const Eigen::Vector3f& query, double& row, double& column) const {
  if (!usable_ || !(query.z() > 0)) return false;
  column = IndexOf(column_slope_, columns_increasing_, query.x() / query.z());
  row = IndexOf(row_slope_, rows_increasing_, query.y() / query.z());
  return true;
}

long ProjectiveIndex::Nearest(const Eigen::Vector3f& query, float max_distance,
                              float& distance_squared) const {
  double row = 0, column = 0;
  if (!Pixel(query, row, column)) return -1;
  const long last_column = static_cast<long>(cols_) - 1, last_row = static_cast<long>(rows_) - 1;
  constexpr double kOutside = kWindowRadius;  // pixels beyond the image's edge
  if (!(column > -kOutside && column < static_cast<double>(cols_) - 1 + kOutside &&
        row > -kOutside && row < static_cast<double>(rows_) - 1 + kOutside)) {
    return -1;
  }
  long c0 = std::clamp(std::lround(column), 0L, last_column);
  long r0 = std::clamp(std::lround(row), 0L, last_row);
  float best = max_distance * max_distance;
  long found = -1;
  for (int move = 0; move <= kMaxMoves; ++move) {
    for (long r = std::max(r0 - kWindowRadius, 0L); r <= std::min(r0 + kWindowRadius, last_row);
         ++r) {
      for (long c = std::max(c0 - kWindowRadius, 0L);
           c <= std::min(c0 + kWindowRadius, last_column); ++c) {
        const std::size_t i = static_cast<std::size_t>(r) * cols_ + static_cast<std::size_t>(c);
        const float dx = x_[i] - query.x(), dy = y_[i] - query.y(), dz = z_[i] - query.z();
        const float d2 = dx * dx + dy * dy + dz * dz;  // NaN for a point not kept: never <
        if (d2 < best) {
          best = d2;
          found = static_cast<long>(i);
        }
      }
    }
    if (found < 0) return -1;
    const long r = found / static_cast<long>(cols_), c = found % static_cast<long>(cols_);
    // The nearest point on the window's edge (not the image's): a nearer one may lie beyond.
    const bool on_edge = (std::abs(r - r0) == kWindowRadius && r > 0 && r < last_row) ||
                         (std::abs(c - c0) == kWindowRadius && c > 0 && c < last_column);
    if (!on_edge) break;
    r0 = r;
    c0 = c;
  }
  distance_squared = best;
  return found;
}

}  // namespace selfcal::calib
