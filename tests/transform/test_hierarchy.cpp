// The subdivision hierarchy: counts follow Catmull-Clark, every level's
// control mesh is a manifold of the base's topology, and bad base meshes are
// rejected with a clear error.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/transform/hierarchy.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

TEST(Hierarchy, LevelsKeepTopologyAndFollowCatmullClarkCounts) {
  for (const auto& [name, mesh] : test::generated_corpus()) {
    SCOPED_TRACE(name);
    const SubdivisionHierarchy hierarchy(mesh, 3);
    const TopologySummary base = summarize_topology(mesh);
    ASSERT_EQ(hierarchy.vertex_count(0), base.vertices);
    for (int level = 1; level <= 3; ++level) {
      const PolygonMesh control = hierarchy.control_mesh(level, std::vector<Vec3>(hierarchy.vertex_count(level)));
      ASSERT_NO_THROW(require_manifold(control, name));
      const TopologySummary s = summarize_topology(control);
      const TopologySummary parent =
          summarize_topology(hierarchy.control_mesh(level - 1, std::vector<Vec3>(hierarchy.vertex_count(level - 1))));
      // One vertex per parent vertex, face and edge; one quad per parent corner.
      EXPECT_EQ(s.vertices, parent.vertices + parent.faces + parent.edges);
      const PolygonMesh parent_mesh =
          hierarchy.control_mesh(level - 1, std::vector<Vec3>(hierarchy.vertex_count(level - 1)));
      EXPECT_EQ(s.faces, parent_mesh.face_vertices.size());
      EXPECT_EQ(hierarchy.vertex_count(level), s.vertices);
      EXPECT_EQ(s.genus, base.genus);
      EXPECT_EQ(s.components, base.components);
      EXPECT_EQ(s.boundary_loops, base.boundary_loops);
      EXPECT_EQ(s.boundary_edges, base.boundary_edges << level);
      for (std::size_t f = 0; f < control.face_count(); ++f) ASSERT_EQ(control.face_size(f), 4u);
    }
  }
}

// The closed-form counts every size check relies on, against the counts of
// the refined control meshes themselves.
TEST(Hierarchy, RefinementCountsEqualTheRefinedMeshes) {
  for (const auto& [name, mesh] : test::generated_corpus()) {
    SCOPED_TRACE(name);
    const SubdivisionHierarchy hierarchy(mesh, 3);
    const TopologySummary base = summarize_topology(mesh);
    const std::vector<LevelCounts> counts =
        refinement_counts({double(base.vertices), double(base.faces), double(base.edges),
                           double(mesh.face_vertices.size())}, 3);
    ASSERT_EQ(counts.size(), 4u);
    for (int level = 0; level <= 3; ++level) {
      const PolygonMesh control = hierarchy.control_mesh(level, std::vector<Vec3>(hierarchy.vertex_count(level)));
      const TopologySummary s = summarize_topology(control);
      EXPECT_EQ(counts[level].vertices, double(s.vertices)) << level;
      EXPECT_EQ(counts[level].faces, double(s.faces)) << level;
      EXPECT_EQ(counts[level].edges, double(s.edges)) << level;
      EXPECT_EQ(counts[level].corners, double(control.face_vertices.size())) << level;
    }
  }
}

TEST(Hierarchy, IndexLevelsFollowTheCoarseToFineLayout) {
  const SubdivisionHierarchy hierarchy(test::cube(), 2);
  EXPECT_EQ(hierarchy.vertex_count(0), 8u);
  EXPECT_EQ(hierarchy.vertex_count(1), 8u + 6u + 12u);
  EXPECT_EQ(hierarchy.level_of_index(0), 0);
  EXPECT_EQ(hierarchy.level_of_index(7), 0);
  EXPECT_EQ(hierarchy.level_of_index(8), 1);
  EXPECT_EQ(hierarchy.level_of_index(25), 1);
  EXPECT_EQ(hierarchy.level_of_index(26), 2);
  // The f vertex of base face 0 at level 1 sits between the v and e ranges.
  EXPECT_EQ(hierarchy.step(1).first_face_vertex(), 8u);
  EXPECT_EQ(hierarchy.step(1).first_edge_vertex(), 14u);
}

// The faces descending from a base face tile the level in base-face order,
// and the only base vertices they touch are that face's corners (base
// vertices keep their indices on every level).
TEST(Hierarchy, DescendantFacesOfABaseFaceFormItsPatch) {
  const PolygonMesh base = test::mixed_disk();
  const SubdivisionHierarchy hierarchy(base, 3);
  for (int level = 0; level <= 3; ++level) {
    const PolygonMesh mesh = hierarchy.control_mesh(level, std::vector<Vec3>(hierarchy.vertex_count(level)));
    std::size_t next = 0;
    for (std::size_t b = 0; b < base.face_count(); ++b) {
      const auto [first, last] = hierarchy.descendant_faces(b, level);
      ASSERT_EQ(first, next) << "level " << level << " base face " << b;
      ASSERT_LT(first, last);
      ASSERT_LE(last, mesh.face_count());
      next = last;
      const std::uint32_t* corners = base.face_begin(b);
      std::vector<std::uint32_t> touched;
      for (std::size_t g = first; g < last; ++g)
        for (std::uint32_t k = 0; k < mesh.face_size(g); ++k)
          if (mesh.face_begin(g)[k] < base.vertex_count()) touched.push_back(mesh.face_begin(g)[k]);
      std::sort(touched.begin(), touched.end());
      touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
      std::vector<std::uint32_t> expected(corners, corners + base.face_size(b));
      std::sort(expected.begin(), expected.end());
      EXPECT_EQ(touched, expected) << "level " << level << " base face " << b;
    }
    EXPECT_EQ(next, mesh.face_count()) << "level " << level;
  }
}

TEST(Hierarchy, SharpFlagsAndRules) {
  PolygonMesh disk = test::mixed_disk();
  disk.sharp.assign(disk.vertex_count(), 0);
  disk.sharp[5] = 1;  // interior
  const SubdivisionHierarchy hierarchy(disk, 2);
  const RefinementStep& s = hierarchy.step(1);
  EXPECT_EQ(s.vertex_rule[5], VertexRule::Sharp);
  // Boundary vertices follow the crease rules, interior ones the smooth rules.
  const TopologySummary t = summarize_topology(disk);
  EXPECT_EQ(s.crease_vertices.size(), t.boundary_edges);  // one boundary loop: as many vertices as edges
  EXPECT_EQ(s.vertex_rule[6], VertexRule::Smooth);
  // Edges touching the sharp vertex, and boundary edges, skip rules 1 and 5.
  for (std::uint32_t e = 0; e < s.parent_edge_count; ++e) {
    const bool touches_sharp = s.edge_vertices[2 * e] == 5 || s.edge_vertices[2 * e + 1] == 5;
    const bool boundary = s.edge_faces[2 * e] == s.edge_faces[2 * e + 1];
    EXPECT_EQ(s.edge_smooth[e] == 0, touches_sharp || boundary);
  }
  EXPECT_EQ(hierarchy.sharp_flags(2)[5], 1);
  EXPECT_EQ(hierarchy.control_mesh(2, std::vector<Vec3>(hierarchy.vertex_count(2))).sharp_count(), 1u);
}

TEST(Hierarchy, ControlMeshTakingThePositionsEqualsTheCopyingOne) {
  for (const auto& [name, mesh] : test::generated_corpus()) {
    SCOPED_TRACE(name);
    const SubdivisionHierarchy hierarchy(mesh, 2);
    for (int level = 0; level <= 2; ++level)
      for (std::size_t extra : {0, 3}) {
        // Fewer positions than vertices (the rest are zero) and more (ignored).
        const std::size_t count = level == 0 ? hierarchy.vertex_count(level) - 1 : hierarchy.vertex_count(level) + extra;
        std::vector<Vec3> positions(count);
        for (std::size_t v = 0; v < count; ++v) positions[v] = {double(v), 0.5 * double(v), -1.0};
        const PolygonMesh copied = hierarchy.control_mesh(level, positions);
        const PolygonMesh taken = hierarchy.control_mesh(level, std::move(positions));
        EXPECT_TRUE(taken.positions == copied.positions);
        EXPECT_EQ(taken.face_offsets, copied.face_offsets);
        EXPECT_EQ(taken.face_vertices, copied.face_vertices);
        EXPECT_EQ(taken.sharp, copied.sharp);
        ASSERT_EQ(copied.vertex_count(), hierarchy.vertex_count(level));
        if (level > 0) {
          EXPECT_EQ(copied.face_count(), hierarchy.step(level).face_offsets.back());
        }
      }
  }
}

TEST(Hierarchy, RejectsBadBaseMeshes) {
  const auto kind_of = [](const PolygonMesh& mesh, int levels) {
    try {
      SubdivisionHierarchy hierarchy(mesh, levels);
    } catch (const Error& error) {
      EXPECT_GT(std::string(error.what()).size(), 10u);
      return error.kind();
    }
    return ErrorKind::Unsupported;  // marker: no error
  };
  PolygonMesh non_manifold;
  non_manifold.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  non_manifold.add_face({0, 1, 2});
  non_manifold.add_face({1, 0, 3});
  non_manifold.add_face({0, 1, 4});
  EXPECT_EQ(kind_of(non_manifold, 1), ErrorKind::Topology);

  PolygonMesh repeated = test::cube();
  repeated.face_vertices[1] = repeated.face_vertices[0];
  EXPECT_EQ(kind_of(repeated, 1), ErrorKind::Topology);

  EXPECT_EQ(kind_of(PolygonMesh{}, 1), ErrorKind::Topology);
  EXPECT_EQ(kind_of(test::cube(), -1), ErrorKind::InvalidArgument);
  EXPECT_EQ(kind_of(test::cube(), SubdivisionHierarchy::kMaxLevels + 1), ErrorKind::InvalidArgument);
  // 8 * 4^16 vertices would overflow 32-bit indices; rejected before refining.
  EXPECT_EQ(kind_of(test::quad_grid(200, 200), 10), ErrorKind::InvalidArgument);
}

}  // namespace
}  // namespace isowave
