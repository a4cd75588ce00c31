// PointSetDistance against CGAL's AABB tree (SurfaceDistance), the
// reference: the same exact distances for points near, on, far from and
// outside each mesh, whatever the first search radius (one sweep or many),
// the face order and the thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <tbb/global_control.h>

#include "isowave/core/error.h"
#include "isowave/core/point_set_distance.h"
#include "isowave/core/surface_distance.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

void expect_same_as_cgal(const PolygonMesh& mesh, double near, double radius, const std::string& name) {
  SCOPED_TRACE(name + ", first radius " + std::to_string(radius));
  const std::vector<Vec3> points = test::points_around(mesh, near, 11);
  const std::vector<double> got = PointSetDistance(points, radius).distances(mesh);
  const std::vector<double> expected = SurfaceDistance(mesh).distances(points);
  ASSERT_EQ(got.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    ASSERT_NEAR(got[i], expected[i], 1e-9 * (1 + expected[i]))
        << "point " << i << " at (" << points[i].x << ", " << points[i].y << ", " << points[i].z << ")";
}

TEST(PointSetDistance, MatchesCgalOnTheGeneratedCorpus) {
  for (test::NamedMesh& named : test::generated_corpus()) {
    test::jitter(named.mesh, 0.1, 3);
    // A radius far below the points' distances (many sweeps) and one above them (one sweep).
    for (const double radius : {0.001, 0.05, 10.0}) expect_same_as_cgal(named.mesh, 0.5, radius, named.name);
  }
}

TEST(PointSetDistance, MatchesCgalOnAFineTorus) {
  // 28,800 triangles in 900 blocks of faces.
  PolygonMesh torus = test::quad_grid(120, 120, true, true);
  test::jitter(torus, 0.01, 5);
  for (const double radius : {0.002, 0.02}) expect_same_as_cgal(torus, 0.05, radius, "torus 120 x 120");
}

TEST(PointSetDistance, MatchesCgalOnFarApartAndStretchedTriangles) {
  for (const double radius : {0.001, 1.0})
    expect_same_as_cgal(test::far_apart_and_stretched(), 1.0, radius, "far apart and stretched");
}

TEST(PointSetDistance, ZeroAreaTrianglesCountAsTheirEdges) {
  PolygonMesh mesh;
  mesh.positions = {{1, 1, 1}, {2, 2, 2}, {3, 3, 3}, {0, 5, 0}};
  mesh.add_face({0, 1, 2});  // collinear corners: the segment (1,1,1)-(3,3,3)
  mesh.add_face({3, 3, 3});  // a point
  const std::vector<Vec3> points = {{2, 2, 2}, {0, 0, 0}, {4, 4, 4}, {2, 3, 2}, {0, 5, 1}};
  const double third = std::sqrt(2.0 / 3.0);  // (2,3,2) from the line x = y = z
  const std::vector<double> expected = {0, std::sqrt(3.0), std::sqrt(3.0), third, 1};
  const std::vector<double> got = PointSetDistance(points, 0.1).distances(mesh);
  for (std::size_t i = 0; i < points.size(); ++i) EXPECT_NEAR(got[i], expected[i], 1e-12) << "point " << i;
}

TEST(PointSetDistance, FaceOrderAndThreadCountDoNotChangeTheDistances) {
  PolygonMesh mesh = test::quad_grid(60, 60, true, true);
  test::jitter(mesh, 0.02, 9);
  const std::vector<Vec3> points = test::points_around(mesh, 0.1, 13);
  const PointSetDistance distance(points, 0.01);
  const std::vector<double> expected = distance.distances(mesh);
  // The faces reversed: other blocks, the same triangles.
  PolygonMesh reversed;
  reversed.positions = mesh.positions;
  for (std::size_t f = mesh.face_count(); f-- > 0;) reversed.add_face(mesh.face_begin(f), mesh.face_size(f));
  EXPECT_EQ(distance.distances(reversed), expected);
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  EXPECT_EQ(distance.distances(mesh), expected);
}

TEST(PointSetDistance, RefusesBadInput) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(PointSetDistance({}, 1.0), Error);
  EXPECT_THROW(PointSetDistance({{0, 0, 0}}, 0.0), Error);
  EXPECT_THROW(PointSetDistance({{0, 0, 0}}, std::numeric_limits<double>::infinity()), Error);
  EXPECT_THROW(PointSetDistance({{0, nan, 0}}, 1.0), Error);
  const PointSetDistance distance({{0, 0, 0}}, 1.0);
  PolygonMesh no_faces;
  no_faces.positions = {{0, 0, 0}};
  EXPECT_THROW(distance.distances(no_faces), Error);
  PolygonMesh not_finite = test::cube();
  not_finite.positions[3].y = nan;
  EXPECT_THROW(distance.distances(not_finite), Error);
}

}  // namespace
}  // namespace isowave
