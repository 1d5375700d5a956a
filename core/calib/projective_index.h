// Projective data association for a scan taken in one pose (a depth camera's image): a query
// point in the scan's sensor frame is projected into its image, and its nearest neighbour is
// looked for among the kept points of a small window of pixels around where it lands, the window
// following the nearest point while that lies on its edge. O(1) per query where a k-d tree
// search is O(log n): KinectFusion's association (Newcombe et al. 2011), with a local nearest-
// point search instead of the one pixel. Not the paper's (docs/engine.md, deviation 25): where
// the nearest point in 3D lies farther than the window from the query's pixel (across a depth
// step, on a surface seen at a grazing angle), the two differ.
//
// The projection needs no intrinsics: a pinhole camera's ray through pixel (row, column) has x/z
// a function of the column and y/z of the row alone, and noise along the ray keeps both, so the
// index takes each column's and row's median of the scan's own points.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace selfcal::calib {

class ProjectiveIndex {
 public:
  // Over the grid points with keep[i] != 0 (rows x cols, row-major, sensor frame, any unit).
  // Usable() says whether the points showed a pinhole image (rays strictly ordered along rows
  // and columns); if not, the caller searches otherwise.
  ProjectiveIndex(std::size_t rows, std::size_t cols, const std::vector<float>& x,
                  const std::vector<float>& y, const std::vector<float>& z,
                  const std::vector<std::uint8_t>& keep);

  bool Usable() const { return usable_; }
  // The grid index of the nearest kept point to `query` in the window around its pixel, strictly
  // closer than `max_distance`, or -1 (behind the camera, outside the image by more than the
  // window, or none close enough). `distance_squared` receives its squared distance.
  long Nearest(const Eigen::Vector3f& query, float max_distance, float& distance_squared) const;
  // Where `query` lands in the image (fractional row and column; may lie outside). False behind
  // the camera or when not Usable().
  bool Pixel(const Eigen::Vector3f& query, double& row, double& column) const;

  // Pixels on each side of the centre that a window covers, and how often it may follow the
  // nearest point off its edge.
  static constexpr int kWindowRadius = 2;
  static constexpr int kMaxMoves = 4;

 private:
  // The fractional index along `slopes` (one per column or row, strictly monotonic) of `slope`.
  double IndexOf(const std::vector<double>& slopes, bool increasing, double slope) const;

  std::size_t rows_ = 0, cols_ = 0;
  std::vector<float> x_, y_, z_;  // kept points, NaN elsewhere
  std::vector<double> column_slope_, row_slope_;
  bool columns_increasing_ = true, rows_increasing_ = true;
  bool usable_ = false;
};

}  // namespace selfcal::calib
