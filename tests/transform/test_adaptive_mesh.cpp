// The adaptive control mesh (transform/adaptive_mesh.h, issue #48 item 4)
// against the invariants of a crack-free mesh, counted on the output itself:
// on a closed base every directed edge has exactly one reverse (watertight,
// manifold, consistently oriented: a T-junction or a crack leaves an edge
// without one); with a boundary, the edges without a reverse lie on the full
// decode's boundary; one level everywhere gives that level's control mesh.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>
#include <utility>

#include "isowave/core/error.h"
#include "isowave/transform/adaptive_mesh.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

using Edges = std::map<std::pair<std::uint32_t, std::uint32_t>, int>;

Edges directed_edges(const PolygonMesh& mesh) {
  Edges edges;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* c = mesh.face_begin(f);
    const std::uint32_t n = mesh.face_size(f);
    for (std::uint32_t k = 0; k < n; ++k) ++edges[{c[k], c[(k + 1) % n]}];
  }
  return edges;
}

// Distinct positions per fine vertex, so that the output's positions name
// the fine vertex they came from.
std::vector<Vec3> numbered_points(std::size_t n) {
  std::vector<Vec3> p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = {double(i), 0.5 * double(i), 0.25 * double(i)};
  return p;
}

TEST(AdaptiveMesh, RandomLevelsGiveAWatertightMeshOnClosedBases) {
  std::mt19937 rng(5);
  for (const test::NamedMesh& named : test::generated_corpus()) {
    const SubdivisionHierarchy h(named.mesh, 3);
    const Edges base_edges = directed_edges(named.mesh);
    const bool closed = std::all_of(base_edges.begin(), base_edges.end(), [&](const auto& e) {
      return base_edges.count({e.first.second, e.first.first}) == 1;
    });
    const std::vector<Vec3> fine = numbered_points(h.fine_vertex_count());
    const PolygonMesh full = h.control_mesh(3, fine);
    const Edges full_edges = directed_edges(full);
    for (int trial = 0; trial < 4; ++trial) {
      std::vector<int> levels(named.mesh.face_count());
      for (int& l : levels) l = std::uniform_int_distribution<int>(0, 3)(rng);
      const PolygonMesh mesh = adaptive_control_mesh(h, levels, fine);
      const Edges edges = directed_edges(mesh);
      for (const auto& [edge, count] : edges) {
        ASSERT_EQ(count, 1) << named.name << ": a directed edge used twice";
        const bool reversed = edges.count({edge.second, edge.first}) == 1;
        if (closed) {
          EXPECT_TRUE(reversed) << named.name << ": an edge without its reverse (a crack or a T-junction)";
        } else if (!reversed) {
          // A boundary edge of the output joins two vertices of the full decode's boundary.
          const auto on_boundary = [&](const Vec3& p) {
            const std::uint32_t v = static_cast<std::uint32_t>(p.x);
            for (const auto& [e, c] : full_edges)
              if ((e.first == v || e.second == v) && full_edges.count({e.second, e.first}) == 0) return true;
            return false;
          };
          EXPECT_TRUE(on_boundary(mesh.positions[edge.first]) && on_boundary(mesh.positions[edge.second]))
              << named.name << ": a boundary edge inside the surface";
        }
      }
    }
  }
}

TEST(AdaptiveMesh, OneLevelEverywhereIsThatLevelsControlMesh) {
  const PolygonMesh base = test::genus_slab(2);
  const SubdivisionHierarchy h(base, 2);
  const std::vector<Vec3> fine = numbered_points(h.fine_vertex_count());
  for (int level = 0; level <= 2; ++level) {
    const PolygonMesh mesh = adaptive_control_mesh(h, std::vector<int>(base.face_count(), level), fine);
    const PolygonMesh reference = h.control_mesh(level, fine);
    ASSERT_EQ(mesh.face_count(), reference.face_count()) << level;
    ASSERT_EQ(mesh.vertex_count(), reference.vertex_count()) << level;
    // Every vertex of the level is used, so the ascending renumbering is the identity.
    EXPECT_EQ(mesh.face_vertices, reference.face_vertices) << level;
    EXPECT_EQ(mesh.positions, reference.positions) << level;
  }
}

TEST(AdaptiveMesh, ACoarseFaceNextToAFineOneTakesItsEdgeVertices) {
  // Two quads side by side, one at level 0 and one at level 2: the coarse quad
  // becomes a polygon with the fine side's 3 vertices on the shared edge.
  const PolygonMesh base = test::quad_grid(2, 1);
  const SubdivisionHierarchy h(base, 2);
  const PolygonMesh mesh = adaptive_control_mesh(h, {0, 2}, numbered_points(h.fine_vertex_count()));
  std::size_t heptagons = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) heptagons += mesh.face_size(f) == 7;
  EXPECT_EQ(heptagons, 1u);
  EXPECT_EQ(mesh.face_count(), 1u + 16u);
}

TEST(AdaptiveMesh, RefusesLevelsOutOfRange) {
  const PolygonMesh base = test::cube();
  const SubdivisionHierarchy h(base, 1);
  const std::vector<Vec3> fine = numbered_points(h.fine_vertex_count());
  EXPECT_THROW(adaptive_control_mesh(h, std::vector<int>(6, 2), fine), Error);
  EXPECT_THROW(adaptive_control_mesh(h, std::vector<int>(6, -1), fine), Error);
  EXPECT_THROW(adaptive_control_mesh(h, std::vector<int>(5, 0), fine), Error);
  EXPECT_THROW(adaptive_control_mesh(h, std::vector<int>(6, 0), std::vector<Vec3>(3)), Error);
}

}  // namespace
}  // namespace isowave
