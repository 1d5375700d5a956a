// The one pinhole model: unprojection at a depth, projection back, binning and field of view.
#include "core/camera/pinhole_intrinsics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace selfcal {
namespace {

TEST(PinholeIntrinsics, UnprojectsAtDepthAlongTheOpticalAxis) {
  const PinholeIntrinsics k{200.0, 250.0, 159.5, 119.5};
  const Eigen::Vector3d p = k.Unproject(259.5, 69.5, 2.0);
  EXPECT_DOUBLE_EQ(p.x(), 2.0 * 100.0 / 200.0);
  EXPECT_DOUBLE_EQ(p.y(), 2.0 * -50.0 / 250.0);
  EXPECT_DOUBLE_EQ(p.z(), 2.0);
  // The principal point looks straight ahead; z = 1 is the ray at unit depth.
  EXPECT_EQ(k.Unproject(159.5, 119.5, 1.0), Eigen::Vector3d(0, 0, 1));
}

TEST(PinholeIntrinsics, ProjectInvertsUnprojectAtEveryDepth) {
  const PinholeIntrinsics k{523.1, 517.9, 318.2, 241.7};
  for (const double u : {0.0, 17.25, 318.2, 639.0}) {
    for (const double v : {0.0, 100.5, 479.0}) {
      for (const double z : {0.3, 1.0, 7.5}) {
        const Eigen::Vector2d pixel = k.Project(k.Unproject(u, v, z));
        EXPECT_NEAR(pixel.x(), u, 1e-9);
        EXPECT_NEAR(pixel.y(), v, 1e-9);
      }
    }
  }
  // And the other way: a point projects to a pixel whose ray passes through it.
  const Eigen::Vector3d p(0.4, -0.2, 1.6);
  const Eigen::Vector2d pixel = k.Project(p);
  EXPECT_LT((k.Unproject(pixel.x(), pixel.y(), p.z()) - p).norm(), 1e-12);
}

TEST(PinholeIntrinsics, BinningKeepsTheFieldOfViewAndPixelCentres) {
  const PinholeIntrinsics k{400.0, 420.0, 319.5, 239.5};
  const PinholeIntrinsics b = k.Binned(4);
  EXPECT_DOUBLE_EQ(b.fx, 100.0);
  EXPECT_DOUBLE_EQ(b.fy, 105.0);
  EXPECT_DOUBLE_EQ(b.cx, 79.5);  // the centre of 640 px is the centre of 160 px
  EXPECT_DOUBLE_EQ(b.cy, 59.5);
  // The binned pixel (0, 0) covers original pixels 0..3, centred at 1.5: the same ray.
  EXPECT_LT((b.Unproject(0, 0, 1) - k.Unproject(1.5, 1.5, 1)).norm(), 1e-12);
  const PinholeIntrinsics same = k.Binned(1);
  EXPECT_EQ(same.fx, k.fx);
  EXPECT_EQ(same.cy, k.cy);
}

TEST(PinholeIntrinsics, FieldOfViewReachesTheImageEdges) {
  const double hfov = 1.0, vfov = 0.8;
  const PinholeIntrinsics k = PinholeIntrinsics::FromFieldOfView(640, 480, hfov, vfov);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);
  // The outer edge of the last pixel (u = 639.5) is half the field of view off the axis.
  const Eigen::Vector3d right = k.Unproject(639.5, 239.5, 1.0);
  EXPECT_NEAR(std::atan2(right.x(), right.z()), hfov / 2, 1e-12);
  const Eigen::Vector3d top = k.Unproject(319.5, -0.5, 1.0);
  EXPECT_NEAR(std::atan2(-top.y(), top.z()), vfov / 2, 1e-12);
}

TEST(PinholeIntrinsics, ValidOnlyWithPositiveFiniteFocalLengths) {
  EXPECT_TRUE((PinholeIntrinsics{1, 1, 0, 0}.IsValid()));
  EXPECT_FALSE(PinholeIntrinsics{}.IsValid());
  EXPECT_FALSE((PinholeIntrinsics{-1, 1, 0, 0}.IsValid()));
  EXPECT_FALSE((PinholeIntrinsics{1, std::numeric_limits<double>::infinity(), 0, 0}.IsValid()));
  EXPECT_FALSE((PinholeIntrinsics{1, 1, std::nan(""), 0}.IsValid()));
}

}  // namespace
}  // namespace selfcal
