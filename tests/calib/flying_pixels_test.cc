// The flying pixel rule (core/calib/flying_pixels.h): what it removes on ideal and noisy grids.
#include "core/calib/flying_pixels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace selfcal::calib {
namespace {

constexpr double kTenDegrees = 10.0 * M_PI / 180.0;

// A pinhole grid (focal length f pixels) seeing depth(row, column) along each pixel's ray.
template <typename Depth>
Dataset PinholeGrid(std::size_t rows, std::size_t cols, double f, PoseLayout layout,
                    const Depth& depth) {
  Dataset dataset;
  dataset.rows = rows;
  dataset.cols = cols;
  dataset.layout = layout;
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cols; ++c) {
      const double z = depth(r, c);
      dataset.x.push_back(
          static_cast<float>(z * (static_cast<double>(c) - 0.5 * static_cast<double>(cols)) / f));
      dataset.y.push_back(
          static_cast<float>(z * (static_cast<double>(r) - 0.5 * static_cast<double>(rows)) / f));
      dataset.z.push_back(static_cast<float>(z));
    }
  }
  return dataset;
}

FlyingPixelRule KinectRule() { return {kTenDegrees, 0.00253, 0.0021}; }

std::size_t Count(const std::vector<std::uint8_t>& flags) {
  std::size_t count = 0;
  for (std::uint8_t flag : flags) count += flag;
  return count;
}

TEST(FlyingPixels, RemovesBothSidesOfAStepAndWhatFloatsBetween) {
  // A near plane at 1 m left of column 20, a far one at 1.5 m from it; on odd rows the last
  // near pixel returned a mix of both (1.2 m), as a footprint straddling the step does.
  const Dataset dataset =
      PinholeGrid(30, 40, 200.0, PoseLayout::kOnePerScan, [](std::size_t r, std::size_t c) {
        if (c == 19 && r % 2 == 1) return 1.2;
        return c < 20 ? 1.0 : 1.5;
      });
  const std::vector<std::uint8_t> flying = FlyingPixels(dataset, KinectRule());
  ASSERT_EQ(flying.size(), dataset.PointCount());
  for (std::size_t r = 0; r < 30; ++r) {
    for (std::size_t c = 0; c < 40; ++c) {
      // Column 18 goes where its neighbour floats; 19 and 20 are the step's sides.
      const bool expected = c == 19 || c == 20 || (c == 18 && r % 2 == 1);
      EXPECT_EQ(flying[r * 40 + c], expected ? 1 : 0) << r << "," << c;
    }
  }
}

TEST(FlyingPixels, KeepsANoisyPlaneSeenHeadOn) {
  // The Kinect's noise (2.53 mm + 0.21 % of the depth) on a plane 1.5 m away, Kinect pixels
  // (7 mm apart there): differences between neighbours of up to a few sigma stay.
  std::mt19937 random(7);
  std::normal_distribution<double> unit(0.0, 1.0);
  const Dataset dataset = PinholeGrid(
      288, 320, 208.5, PoseLayout::kOnePerScan,
      [&](std::size_t, std::size_t) { return 1.5 + (0.00253 + 0.0021 * 1.5) * unit(random); });
  EXPECT_LT(Count(FlyingPixels(dataset, KinectRule())), dataset.PointCount() / 1000);
}

TEST(FlyingPixels, RemovesASurfaceMoreGrazingThanTheAngle) {
  // A noise-free plane through (0, 0, 1.5) tilted about the image's vertical axis.
  const auto tilted = [](double tilt_deg) {
    const double t = tilt_deg * M_PI / 180.0, f = 208.5;
    return PinholeGrid(20, 60, f, PoseLayout::kOnePerScan, [=](std::size_t, std::size_t c) {
      const double x = (static_cast<double>(c) - 30.0) / f;  // x / z of the ray
      return 1.5 * std::cos(t) / (std::cos(t) + std::sin(t) * x);
    });
  };
  const Dataset steep = tilted(60.0), grazing = tilted(85.0);
  EXPECT_EQ(Count(FlyingPixels(steep, KinectRule())), 0u);
  // Near the image's centre the rays meet the grazing plane at about 85 deg: all removed (the
  // rays of the outer columns are up to 8 deg off the axis, so some meet it at less than 80).
  const std::vector<std::uint8_t> flying = FlyingPixels(grazing, KinectRule());
  for (std::size_t r = 0; r < 20; ++r) {
    for (std::size_t c = 25; c <= 35; ++c) EXPECT_EQ(flying[r * 60 + c], 1) << r << "," << c;
  }
}

TEST(FlyingPixels, ALineScannerIsComparedAlongItsLinesOnly) {
  // Each column is a profile taken at its own pose: the columns' depths have nothing to do with
  // each other. Only the step inside a profile (rows 9 and 10 of column 5) counts.
  const Dataset dataset =
      PinholeGrid(20, 10, 500.0, PoseLayout::kOnePerColumn, [](std::size_t r, std::size_t c) {
        return 0.3 + 0.05 * static_cast<double>(c) + (c == 5 && r >= 10 ? 0.05 : 0.0);
      });
  const std::vector<std::uint8_t> flying =
      FlyingPixels(dataset, FlyingPixelRule{kTenDegrees, 0.0001, 0.0});
  EXPECT_EQ(Count(flying), 2u);
  EXPECT_EQ(flying[9 * 10 + 5], 1);
  EXPECT_EQ(flying[10 * 10 + 5], 1);
}

TEST(FlyingPixels, OffRemovesNothingAndPointsWithoutAMeasureAreNoStep) {
  Dataset dataset = PinholeGrid(10, 10, 200.0, PoseLayout::kOnePerScan,
                                [](std::size_t, std::size_t c) { return c < 5 ? 1.0 : 3.0; });
  EXPECT_TRUE(FlyingPixels(dataset, FlyingPixelRule{}).empty());
  for (std::size_t r = 0; r < 10; ++r) dataset.z[r * 10 + 5] = std::nanf("");  // a gap
  const std::vector<std::uint8_t> flying = FlyingPixels(dataset, KinectRule());
  EXPECT_EQ(Count(flying), 0u);
}

}  // namespace
}  // namespace selfcal::calib
