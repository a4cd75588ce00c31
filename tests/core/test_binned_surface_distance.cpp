// BinnedSurfaceDistance against CGAL's AABB tree (SurfaceDistance), the
// reference: the same exact distances over a corpus of meshes and of query
// points near, on, far from and outside each mesh, and closest points that
// lie on the mesh at that distance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"
#include "isowave/core/surface_distance.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

void expect_same_as_cgal(const PolygonMesh& mesh, double near, const std::string& name) {
  SCOPED_TRACE(name);
  const BinnedSurfaceDistance binned(mesh);
  const SurfaceDistance reference(mesh);
  EXPECT_EQ(binned.triangle_count(), reference.triangle_count());
  const std::vector<Vec3> points = test::points_around(mesh, near, 7);
  const std::vector<double> got = binned.distances(points), expected = reference.distances(points);
  ASSERT_EQ(got.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_NEAR(got[i], expected[i], 1e-9 * (1 + expected[i]))
        << "point " << i << " at (" << points[i].x << ", " << points[i].y << ", " << points[i].z << ")";
    const Vec3 closest = binned.closest_point(points[i]);
    ASSERT_NEAR(norm(closest - points[i]), expected[i], 1e-9 * (1 + expected[i])) << "closest point of point " << i;
    ASSERT_LE(reference.distance(closest), 1e-9 * (1 + expected[i])) << "closest point of point " << i;
  }
}

TEST(BinnedSurfaceDistance, MatchesCgalOnTheGeneratedCorpus) {
  for (test::NamedMesh& named : test::generated_corpus()) {
    test::jitter(named.mesh, 0.1, 3);
    expect_same_as_cgal(named.mesh, 0.5, named.name);
  }
}

TEST(BinnedSurfaceDistance, MatchesCgalOnAFineTorus) {
  // 28,800 triangles: many bins, most queries settled in the first rings.
  PolygonMesh torus = test::quad_grid(120, 120, true, true);
  test::jitter(torus, 0.01, 5);
  expect_same_as_cgal(torus, 0.05, "torus 120 x 120");
}

TEST(BinnedSurfaceDistance, MatchesCgalOnFarApartAndStretchedTriangles) {
  expect_same_as_cgal(test::far_apart_and_stretched(), 1.0, "far apart and stretched");
}

// Marching cubes makes zero-area triangles where samples equal the isovalue.
// CGAL's primitives must not be degenerate (its tree measured such a
// triangle's corners only), so the reference here is the distance to the
// edges, computed directly.
TEST(BinnedSurfaceDistance, ZeroAreaTrianglesCountAsTheirEdges) {
  PolygonMesh mesh;
  mesh.positions = {{1, 1, 1}, {2, 2, 2}, {3, 3, 3}, {7, 7, 7}, {0, 5, 0}};
  mesh.add_face({0, 1, 2});  // collinear corners
  mesh.add_face({3, 3, 1});  // a repeated corner: the segment (7,7,7)-(2,2,2)
  mesh.add_face({4, 4, 4});  // a point
  const auto to_segment = [](const Vec3& p, const Vec3& a, const Vec3& b) {
    const double t = std::clamp(dot(p - a, b - a) / squared_norm(b - a), 0.0, 1.0);
    return norm(p - (a + t * (b - a)));
  };
  const BinnedSurfaceDistance binned(mesh);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> coordinate(-5, 12);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p{coordinate(random), coordinate(random), coordinate(random)};
    const double expected = std::min({to_segment(p, mesh.positions[0], mesh.positions[3]),
                                      norm(p - mesh.positions[4])});
    ASSERT_NEAR(binned.distance(p), expected, 1e-12) << "point " << i;
  }
}

TEST(BinnedSurfaceDistance, OneTriangleAndPointsOnIt) {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}};
  mesh.add_face({0, 1, 2});
  const BinnedSurfaceDistance binned(mesh);
  EXPECT_DOUBLE_EQ(binned.distance({1, 1, 0}), 0.0);
  EXPECT_DOUBLE_EQ(binned.distance({1, 1, -3}), 3.0);
  EXPECT_DOUBLE_EQ(binned.distance({-3, 0, 4}), 5.0);  // nearest: the corner at the origin
  EXPECT_DOUBLE_EQ(binned.distance({3, 3, 0}), std::sqrt(2.0));  // nearest: the hypotenuse's midpoint
  EXPECT_TRUE(std::isnan(binned.distance({std::numeric_limits<double>::quiet_NaN(), 0, 0})));
}

TEST(BinnedSurfaceDistance, RejectsMeshesWithoutFacesOrWithNonFinitePositions) {
  PolygonMesh empty;
  empty.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(BinnedSurfaceDistance{empty}, Error);
  PolygonMesh nan = empty;
  nan.add_face({0, 1, 2});
  nan.positions[1].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(BinnedSurfaceDistance{nan}, Error);
}

}  // namespace
}  // namespace isowave
