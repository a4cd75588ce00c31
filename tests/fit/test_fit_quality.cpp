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

// A field with a plateau of samples equal to the isovalue (x <= 4) and a
// flat region off it (x >= 12): a point on the plateau lies on the
// isosurface though the gradient vanishes; one in the flat region off the
// isovalue has no first-order distance and is left out.
TEST(FitQuality, IsosurfaceDistanceOnAPlateauAtTheIsovalueIsZero) {
  const Volume field = test::sampled_volume({17, 5, 5}, [](double x, double, double) {
    return x <= 4 ? 1.5 : x >= 12 ? 3.0 : 1.5 + (x - 4) / 8 * 1.5;
  });
  const std::vector<Vec3> points = {Vec3{2.3, 2.1, 1.7}, Vec3{14.2, 2.0, 2.0}, Vec3{8.0, 2.0, 2.0}};
  const IsosurfaceDistance d = isosurface_distance(points, points.size(), field, 1.5, 1.0);
  EXPECT_EQ(d.undefined, 1u);  // the point at x = 14.2
  // Of the two others, the plateau's is at 0 and the ramp's at (8 - 4) cells.
  EXPECT_NEAR(d.max, 4.0, 1e-12);
  EXPECT_NEAR(d.rms, std::sqrt(16.0 / 2.0), 1e-12);
  EXPECT_EQ(d.far, 1u);
}

// The same linear field: its isosurface is the plane x = 26, and the
// first-order distance of any point is its exact distance to that plane. Two
// triangles parallel to it, areas 2 and 8 (world units squared) at 1 and 4
// world units (0.5 and 2 cells) from it, and a quad (two triangles, area 1)
// on it: area-weighted RMS sqrt((2 * 0.25 + 8 * 4 + 1 * 0) / 11) cells,
// maximum 2 cells.
TEST(FitQuality, ExtractedSurfaceDeviationWeighsTrianglesByArea) {
  Volume field = test::sampled_volume({33, 17, 17}, [](double x, double, double) { return 26.0 - 2.0 * x; });
  field.spacing = Vec3{2.0, 2.0, 2.0};
  PolygonMesh mesh;
  const auto add = [&mesh](std::initializer_list<Vec3> corners) {
    std::vector<std::uint32_t> face;
    for (const Vec3& p : corners) {
      face.push_back(static_cast<std::uint32_t>(mesh.positions.size()));
      mesh.positions.push_back(p);
    }
    mesh.add_face(face.data(), face.size());
  };
  add({Vec3{27, 2, 2}, Vec3{27, 4, 2}, Vec3{27, 2, 4}});  // area 2, 1 unit off
  add({Vec3{22, 2, 2}, Vec3{22, 6, 2}, Vec3{22, 2, 6}});  // area 8, 4 units off
  add({Vec3{26, 10, 10}, Vec3{26, 11, 10}, Vec3{26, 11, 11}, Vec3{26, 10, 11}});  // area 1, on it
  const SurfaceDeviation d = extracted_surface_deviation(mesh, field, 0.0);
  EXPECT_NEAR(d.rms, std::sqrt((2 * 0.25 + 8 * 4.0) / 11.0), 1e-12);
  EXPECT_NEAR(d.max, 2.0, 1e-12);

  // A tilted triangle: its 7 samples lie at known offsets, the mean of their
  // squares over its area (the same weight for each) is the rule's value.
  PolygonMesh tilted;
  tilted.positions = {Vec3{26, 2, 2}, Vec3{30, 2, 2}, Vec3{26, 6, 2}};  // offsets 0, 4, 0 world units
  tilted.add_face({0, 1, 2});
  const SurfaceDeviation t = extracted_surface_deviation(tilted, field, 0.0);
  // Offsets in cells at the barycentric weight of corner 1: 1/3, 1/2, 1/2, 0, 1/6, 2/3, 1/6 of 2 cells.
  const double squares = (4.0 / 9 + 1 + 1 + 0 + 1.0 / 9 + 16.0 / 9 + 1.0 / 9) / 7.0;
  EXPECT_NEAR(t.rms, std::sqrt(squares), 1e-12);
  EXPECT_NEAR(t.max, 4.0 / 3.0, 1e-12);
}

}  // namespace
}  // namespace isowave
