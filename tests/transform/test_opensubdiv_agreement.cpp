// The subdivision operator S against OpenSubdiv's Catmull-Clark refinement
// (CATMARK, VTX_BOUNDARY_EDGE_ONLY): equal on regular meshes at every level;
// at extraordinary vertices and interior sharp vertices S follows the paper's
// closed forms instead, and the test reports how far it lies from OpenSubdiv.
#include <cstdio>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "isowave/transform/hierarchy.h"
#include "isowave/transform/limit_surface.h"
#include "isowave/transform/wavelet_transform.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

double max_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b, std::size_t count) {
  double m = 0;
  for (std::size_t i = 0; i < count; ++i) m = std::max(m, norm(a[i] - b[i]));
  return m;
}

double extent(const std::vector<Vec3>& points) {
  double m = 0;
  for (const Vec3& p : points) m = std::max({m, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  return m;
}

void expect_equal_to_opensubdiv(const std::string& name, const PolygonMesh& mesh, int levels) {
  SCOPED_TRACE(name);
  const SubdivisionHierarchy hierarchy(mesh, levels);
  const auto reference = opensubdiv_refine(mesh, levels);
  for (int level = 1; level <= levels; ++level) {
    const std::vector<Vec3> ours = subdivide(hierarchy, mesh.positions, level);
    ASSERT_EQ(ours.size(), reference[level].size());
    EXPECT_LE(max_difference(ours, reference[level], ours.size()), 1e-12 * extent(reference[level])) << "level " << level;
  }
}

TEST(OpenSubdivAgreement, RegularClosedMesh) {
  PolygonMesh torus = test::quad_grid(12, 8, true, true);
  test::jitter(torus, 0.2, 1);
  expect_equal_to_opensubdiv("torus", torus, 4);
}

TEST(OpenSubdivAgreement, RegularMeshesWithBoundary) {
  PolygonMesh cylinder = test::quad_grid(10, 5, true, false);
  test::jitter(cylinder, 0.2, 2);
  expect_equal_to_opensubdiv("cylinder", cylinder, 4);

  // A planar grid (boundary vertices valence 3, corners valence 2), warped.
  PolygonMesh grid = test::quad_grid(9, 7);
  test::jitter(grid, 0.3, 3);
  expect_equal_to_opensubdiv("grid", grid, 4);

  // The same grid with its four corners flagged sharp: OpenSubdiv's
  // infinitely sharp corners.
  grid.sharp.assign(grid.vertex_count(), 0);
  for (std::uint32_t corner : {0u, 9u, 10u * 7u, 10u * 8u - 1u}) grid.sharp[corner] = 1;
  expect_equal_to_opensubdiv("grid with sharp corners", grid, 4);
}

Vec3 centroid(const PolygonMesh& mesh, std::size_t f) {
  Vec3 c;
  for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) c += mesh.positions[mesh.face_begin(f)[k]];
  return c * (1.0 / mesh.face_size(f));
}

struct BaseAdjacency {
  std::vector<std::set<std::uint32_t>> neighbours;
  std::vector<std::vector<std::uint32_t>> faces;
  explicit BaseAdjacency(const PolygonMesh& mesh) : neighbours(mesh.vertex_count()), faces(mesh.vertex_count()) {
    for (std::uint32_t f = 0; f < mesh.face_count(); ++f)
      for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) {
        const std::uint32_t a = mesh.face_begin(f)[k], b = mesh.face_begin(f)[(k + 1) % mesh.face_size(f)];
        neighbours[a].insert(b);
        neighbours[b].insert(a);
        faces[a].push_back(f);
      }
  }
};

TEST(OpenSubdivAgreement, ExtraordinaryVerticesFollowThePaperClosedForm) {
  // Closed meshes with valence 3, 5 and 6 vertices: S moves a vertex to
  // v/2 + v̄_v/4 + f̄_v/4 for every valence, where Catmull-Clark uses
  // ((n-2) v + v̄_v + f̄_v) / n. Face and edge points agree with Catmull-Clark.
  for (const auto& [name, mesh0] : std::vector<std::pair<std::string, PolygonMesh>>{
           {"cube", test::cube()}, {"genus3_slab", test::genus_slab(3)}, {"pentagonal_prism", test::pentagonal_prism()}}) {
    SCOPED_TRACE(name);
    PolygonMesh mesh = mesh0;
    test::jitter(mesh, 0.1, 4);
    const SubdivisionHierarchy hierarchy(mesh, 1);
    const std::vector<Vec3> ours = subdivide(hierarchy, mesh.positions, 1);
    const auto reference = opensubdiv_refine(mesh, 1)[1];
    const BaseAdjacency adjacency(mesh);
    double worst_closed_form = 0, distance_at_extraordinary = 0, distance_elsewhere = 0;
    for (std::uint32_t v = 0; v < mesh.vertex_count(); ++v) {
      Vec3 v_bar, f_bar;
      for (std::uint32_t w : adjacency.neighbours[v]) v_bar += mesh.positions[w] * (1.0 / adjacency.neighbours[v].size());
      for (std::uint32_t f : adjacency.faces[v]) f_bar += centroid(mesh, f) * (1.0 / adjacency.faces[v].size());
      const Vec3 expected = 0.5 * mesh.positions[v] + 0.25 * v_bar + 0.25 * f_bar;
      worst_closed_form = std::max(worst_closed_form, norm(ours[v] - expected));
      const double distance = norm(ours[v] - reference[v]);
      if (adjacency.neighbours[v].size() != 4) distance_at_extraordinary = std::max(distance_at_extraordinary, distance);
      else distance_elsewhere = std::max(distance_elsewhere, distance);
    }
    EXPECT_LE(worst_closed_form, 1e-12);
    // Face and edge points are Catmull-Clark's.
    for (std::size_t i = mesh.vertex_count(); i < ours.size(); ++i) EXPECT_LE(norm(ours[i] - reference[i]), 1e-12);
    EXPECT_LE(distance_elsewhere, 1e-12);
    EXPECT_GT(distance_at_extraordinary, 1e-6);  // by design: a different rule
    std::printf("[ report ] %s: S vs OpenSubdiv at extraordinary vertices, level 1: max %.4g (mesh extent %.3g)\n",
                name.c_str(), distance_at_extraordinary, extent(mesh.positions));
    ::testing::Test::RecordProperty(name + "_extraordinary_distance", std::to_string(distance_at_extraordinary));
  }
}

TEST(OpenSubdivAgreement, InteriorSharpVerticesFollowThePaperClosedForm) {
  // An interior vertex flagged sharp stays put and the e vertices of its edges
  // sit at the edge midpoints (Sec. 3.4); OpenSubdiv's infinitely sharp corner
  // also stays put but smooths those e vertices.
  PolygonMesh grid = test::quad_grid(6, 6);
  test::jitter(grid, 0.3, 5);
  const std::uint32_t sharp_vertex = 3 * 7 + 3;
  grid.sharp.assign(grid.vertex_count(), 0);
  grid.sharp[sharp_vertex] = 1;
  const SubdivisionHierarchy hierarchy(grid, 1);
  const std::vector<Vec3> ours = subdivide(hierarchy, grid.positions, 1);
  const auto reference = opensubdiv_refine(grid, 1)[1];
  EXPECT_TRUE(ours[sharp_vertex] == grid.positions[sharp_vertex]);
  EXPECT_LE(norm(reference[sharp_vertex] - grid.positions[sharp_vertex]), 1e-12);
  // e vertices: the level-1 neighbours of the sharp vertex.
  const PolygonMesh level1 = hierarchy.control_mesh(1, ours);
  std::set<std::uint32_t> e_vertices;
  for (std::size_t f = 0; f < level1.face_count(); ++f)
    for (int k = 0; k < 4; ++k)
      if (level1.face_begin(f)[k] == sharp_vertex) {
        e_vertices.insert(level1.face_begin(f)[(k + 1) % 4]);
        e_vertices.insert(level1.face_begin(f)[(k + 3) % 4]);
      }
  ASSERT_EQ(e_vertices.size(), 4u);
  const BaseAdjacency adjacency(grid);
  double distance = 0;
  for (std::uint32_t e : e_vertices) {
    // The midpoint of the sharp vertex and exactly one base neighbour.
    double best = 1e300;
    for (std::uint32_t w : adjacency.neighbours[sharp_vertex])
      best = std::min(best, norm(ours[e] - 0.5 * (grid.positions[sharp_vertex] + grid.positions[w])));
    EXPECT_LE(best, 1e-12);
    distance = std::max(distance, norm(ours[e] - reference[e]));
  }
  EXPECT_GT(distance, 1e-6);
  std::printf("[ report ] interior sharp vertex: S vs OpenSubdiv at its edge points, level 1: max %.4g\n", distance);
  ::testing::Test::RecordProperty("interior_sharp_distance", std::to_string(distance));
}

TEST(LimitSurface, LimitPointsOfRegularGridsMatchTheBSplineSurface) {
  // A torus grid is a closed bicubic B-spline surface: the limit point of a
  // control vertex is (v_{-1} + 4 v_0 + v_1)/6 tensored, i.e. the stencil
  // 1/36 [1 4 1; 4 16 4; 1 4 1], and limit points of S^L meshes converge.
  const int nx = 10, ny = 8;
  PolygonMesh torus = test::quad_grid(nx, ny, true, true);
  test::jitter(torus, 0.1, 6);
  const LimitSurface limit = limit_surface(torus);
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>(((j + ny) % ny) * nx + (i + nx) % nx); };
  const double weights[3] = {1, 4, 1};
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      Vec3 expected;
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) expected += (weights[di + 1] * weights[dj + 1] / 36.0) * torus.positions[id(i + di, j + dj)];
      EXPECT_LE(norm(limit.positions[id(i, j)] - expected), 1e-12);
      EXPECT_NEAR(norm(limit.normals[id(i, j)]), 1.0, 1e-9);
    }
  // Limit points of a mixed-polygon mesh (refined once internally) lie on the
  // same surface as the limit points of its Catmull-Clark refinement.
  const PolygonMesh disk = test::mixed_disk();
  const LimitSurface disk_limit = limit_surface(disk);
  PolygonMesh refined = SubdivisionHierarchy(disk, 1).control_mesh(1, opensubdiv_refine(disk, 1)[1]);
  const LimitSurface refined_limit = limit_surface(refined);
  for (std::size_t v = 0; v < disk.vertex_count(); ++v)
    EXPECT_LE(norm(disk_limit.positions[v] - refined_limit.positions[v]), 1e-12);
}

}  // namespace
}  // namespace isowave
