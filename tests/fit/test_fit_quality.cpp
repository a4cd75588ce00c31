// The cheap fit checks of fit_quality.h against cases with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "isowave/fit/fit_quality.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

// Fitted points on the plane z = 0 (spacing 0.25 over [0, 10]^2); reference
// points above its middle at heights 0.5 .. 3.5: those above 2 are farther
// than 2 from every fitted point, those below are not.
TEST(FitQuality, ShareFartherThanCountsThePointsBeyondTheDistance) {
  std::vector<Vec3> fitted;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j) fitted.push_back(Vec3{0.25 * i, 0.25 * j, 0.0});
  std::vector<Vec3> reference;
  for (double z : {0.5, 1.5, 1.9, 2.1, 2.5, 3.5}) reference.push_back(Vec3{5.1, 4.9, z});
  EXPECT_DOUBLE_EQ(share_farther_than(reference, 1, fitted, fitted.size(), 2.0), 0.5);
  // Every second sample: heights 0.5, 1.9, 2.5.
  EXPECT_DOUBLE_EQ(share_farther_than(reference, 2, fitted, fitted.size(), 2.0), 1.0 / 3.0);
  // Below the fitted points' lower corner, and far outside: still measured.
  EXPECT_DOUBLE_EQ(share_farther_than({Vec3{-1.0, -1.0, 0.0}, Vec3{1e30, 0, 0}}, 1, fitted, fitted.size(), 2.0), 0.5);
  // A non-finite sample is farther than any distance; only `count` fitted points count.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_DOUBLE_EQ(share_farther_than({Vec3{nan, 0, 0}}, 1, fitted, fitted.size(), 2.0), 1.0);
  EXPECT_DOUBLE_EQ(share_farther_than({Vec3{10.0, 10.0, 0.0}}, 1, fitted, 1, 2.0), 1.0);
}

// A linear field f = 26 - x with spacing 2 (unit gradient in world units,
// half a unit per cell): the trilinear interpolant is exact, so points at
// known offsets from the plane x = 26 give known distances in cells.
TEST(FitQuality, IsosurfaceDistanceOfPointsAtKnownOffsets) {
  Volume field = test::sampled_volume({33, 17, 17}, [](double x, double, double) { return 26.0 - 2.0 * x; });
  field.spacing = Vec3{2.0, 2.0, 2.0};
  std::vector<Vec3> points;
  for (double offset : {0.0, 1.0, -3.0, 6.0}) points.push_back(Vec3{26.0 + offset, 7.3, 12.1});
  points.push_back(Vec3{1e6, 0, 0});  // outside the box: clamped, not counted (only `count` points are)
  const IsosurfaceDistance d = isosurface_distance(points, 4, field, 0.0, 1.0);
  EXPECT_NEAR(d.max, 3.0, 1e-9);  // 6 world units = 3 cells
  EXPECT_NEAR(d.rms, std::sqrt((0.25 + 2.25 + 9.0) / 4.0), 1e-9);
  EXPECT_EQ(d.far, 2u);  // 1.5 and 3 cells
  EXPECT_EQ(d.undefined, 0u);
}

}  // namespace
}  // namespace isowave
