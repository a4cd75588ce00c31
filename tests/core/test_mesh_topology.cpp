// Topology checks: require_manifold accepts exactly the consistently oriented
// 2-manifolds, and summarize_topology's counts satisfy Euler's formula on
// meshes whose genus and boundary are known by construction.
#include <gtest/gtest.h>

#include <set>
#include <utility>

#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

TEST(MeshTopology, GeneratedCorpusIsManifoldWithKnownCounts) {
  struct Expected {
    const char* name;
    long long genus;
    std::size_t boundary_loops;
    std::size_t components;
  };
  const Expected expected[] = {{"cube", 0, 0, 1},           {"octahedron", 0, 0, 1},
                               {"pentagonal_prism", 0, 0, 1}, {"mixed_disk", 0, 1, 1},
                               {"grid_with_boundary", 0, 1, 1}, {"cylinder", 0, 2, 1},
                               {"torus", 1, 0, 1},           {"genus2_slab", 2, 0, 1},
                               {"genus3_slab", 3, 0, 1},     {"two_components", 0, 0, 2}};
  const auto corpus = test::generated_corpus();
  for (const Expected& e : expected) {
    const auto it = std::find_if(corpus.begin(), corpus.end(), [&](const auto& m) { return m.name == e.name; });
    ASSERT_NE(it, corpus.end()) << e.name;
    EXPECT_NO_THROW(require_manifold(it->mesh, e.name));
    const TopologySummary s = summarize_topology(it->mesh);
    EXPECT_EQ(s.genus, e.genus) << e.name;
    EXPECT_EQ(s.boundary_loops, e.boundary_loops) << e.name;
    EXPECT_EQ(s.components, e.components) << e.name;
    // Euler: V - E + F = sum over components (2 - 2g - b).
    EXPECT_EQ(s.euler_characteristic,
              2 * static_cast<long long>(s.components) - 2 * s.genus - static_cast<long long>(s.boundary_loops))
        << e.name;
    // Every edge counted once: 2E = corners + boundary edges.
    EXPECT_EQ(2 * s.edges, it->mesh.face_vertices.size() + s.boundary_edges) << e.name;
  }
}

TEST(MeshTopology, ComponentCountsAddUpToTheWholeMeshCounts) {
  // Every corpus mesh, and all of them as one mesh of many components.
  PolygonMesh all;
  std::vector<std::pair<std::string, PolygonMesh>> meshes;
  for (const auto& generated : test::generated_corpus()) {
    meshes.emplace_back(generated.name, generated.mesh);
    const auto offset = static_cast<std::uint32_t>(all.vertex_count());
    all.positions.insert(all.positions.end(), generated.mesh.positions.begin(), generated.mesh.positions.end());
    for (std::size_t f = 0; f < generated.mesh.face_count(); ++f) {
      std::vector<std::uint32_t> face(generated.mesh.face_begin(f), generated.mesh.face_begin(f) + generated.mesh.face_size(f));
      for (std::uint32_t& v : face) v += offset;
      all.add_face(face.data(), face.size());
    }
  }
  meshes.emplace_back("all", all);
  for (const auto& [name, mesh] : meshes) {
    SCOPED_TRACE(name);
    std::vector<std::uint32_t> face_component;
    const std::vector<TopologySummary> parts = summarize_components(mesh, &face_component);
    EXPECT_EQ(face_component, face_components(mesh, nullptr));
    const TopologySummary whole = summarize_topology(mesh);
    TopologySummary sum;
    for (const TopologySummary& part : parts) {
      EXPECT_EQ(part.components, 1u);
      EXPECT_GE(part.genus, 0);
      sum += part;
    }
    EXPECT_EQ(sum.vertices, whole.vertices);
    EXPECT_EQ(sum.edges, whole.edges);
    EXPECT_EQ(sum.faces, whole.faces);
    EXPECT_EQ(sum.boundary_edges, whole.boundary_edges);
    EXPECT_EQ(sum.boundary_loops, whole.boundary_loops);
    EXPECT_EQ(sum.components, whole.components);
    EXPECT_EQ(sum.euler_characteristic, whole.euler_characteristic);
    EXPECT_EQ(sum.genus, whole.genus);
  }
}

std::string topology_error(const PolygonMesh& mesh) {
  try {
    require_manifold(mesh, "test mesh");
  } catch (const Error& error) {
    EXPECT_TRUE(error.kind() == ErrorKind::Topology || error.kind() == ErrorKind::Format);
    return error.what();
  }
  return {};
}

// triangulate() on every face size of the corpus: the same surface (vector
// area per original face kept), orientation kept, and the triangulated mesh
// still a manifold with the same Euler characteristic (a centroid vertex per
// polygon of 5 or more corners adds one vertex and as many edges as faces).
TEST(MeshTopology, TriangulateKeepsTheSurfaceAndItsTopology) {
  for (const test::NamedMesh& named : test::generated_corpus()) {
    const PolygonMesh triangles = triangulate(named.mesh);
    const TopologySummary before = summarize_topology(named.mesh), after = summarize_topology(triangles);
    EXPECT_EQ(after.euler_characteristic, before.euler_characteristic) << named.name;
    EXPECT_EQ(after.genus, before.genus) << named.name;
    // Triangles come in face order: 1 for a triangle, 2 for a quad, n for an n-gon.
    const auto vector_area = [](const PolygonMesh& m, std::size_t f) {
      const std::uint32_t* v = m.face_begin(f);
      Vec3 a;
      for (std::uint32_t k = 0; k < m.face_size(f); ++k) a += cross(m.positions[v[k]], m.positions[v[(k + 1) % m.face_size(f)]]);
      return a;
    };
    std::size_t t = 0;
    for (std::size_t f = 0; f < named.mesh.face_count(); ++f) {
      const std::uint32_t n = named.mesh.face_size(f);
      Vec3 parts;
      for (std::uint32_t k = 0; k < (n == 3 ? 1u : n == 4 ? 2u : n); ++k, ++t) {
        ASSERT_EQ(triangles.face_size(t), 3u);
        parts += vector_area(triangles, t);
      }
      const Vec3 whole = vector_area(named.mesh, f);
      EXPECT_LT(norm(parts - whole), 1e-9 * (1 + norm(whole))) << named.name << " face " << f;
    }
    EXPECT_EQ(t, triangles.face_count()) << named.name;
  }
}

// Two faces sharing two corners: the quad's shorter diagonal 0-2 is the
// triangle's edge, so the plain split repeats the directed edge 2 -> 0 and the
// careful one takes the diagonal 1-3.
TEST(MeshTopology, TriangulateAvoidsADiagonalThatIsAnotherFacesEdge) {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, -2, 0}, {1, 0, 0}, {0, 2, 0}, {0.5, 1, 1}};
  mesh.add_face({0, 1, 2, 3});
  mesh.add_face({2, 0, 4});
  const auto repeated = [](const PolygonMesh& m) {
    std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
    int count = 0;
    for (std::size_t f = 0; f < m.face_count(); ++f)
      for (std::uint32_t k = 0; k < 3; ++k)
        count += !seen.insert({m.face_begin(f)[k], m.face_begin(f)[(k + 1) % 3]}).second;
    return count;
  };
  EXPECT_EQ(repeated(triangulate(mesh, QuadSplit::Shorter)), 1);
  const PolygonMesh careful = triangulate(mesh, QuadSplit::ShorterAvoidingEdges);
  EXPECT_EQ(repeated(careful), 0);
  EXPECT_EQ(careful.face_count(), 3u);
  EXPECT_EQ(careful.vertex_count(), 5u);
}

TEST(MeshTopology, RejectsNonManifoldEdge) {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  mesh.add_face({0, 1, 2});
  mesh.add_face({1, 0, 3});
  mesh.add_face({0, 1, 4});  // third face on edge (0, 1)
  EXPECT_NE(topology_error(mesh).find("non-manifold edge"), std::string::npos) << topology_error(mesh);
}

TEST(MeshTopology, RejectsInconsistentOrientation) {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  mesh.add_face({0, 1, 2});
  mesh.add_face({0, 1, 3});  // same direction on edge (0, 1)
  EXPECT_NE(topology_error(mesh).find("orientation"), std::string::npos) << topology_error(mesh);
}

TEST(MeshTopology, RejectsNonManifoldVertex) {
  // Two triangles touching at vertex 0 only: a bow tie.
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  mesh.add_face({0, 1, 2});
  mesh.add_face({0, 3, 4});
  EXPECT_NE(topology_error(mesh).find("non-manifold vertex"), std::string::npos) << topology_error(mesh);
}

TEST(MeshTopology, RejectsRepeatedVertexEmptyMeshAndUnusedVertex) {
  PolygonMesh repeated;
  repeated.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  repeated.add_face({0, 1, 1, 2});
  EXPECT_NE(topology_error(repeated).find("twice"), std::string::npos);

  PolygonMesh empty;
  EXPECT_NE(topology_error(empty).find("no faces"), std::string::npos);

  PolygonMesh unused = test::cube();
  unused.positions.push_back({5, 5, 5});
  EXPECT_NE(topology_error(unused).find("used by no face"), std::string::npos);
  EXPECT_EQ(remove_unreferenced_vertices(unused), 1u);
  EXPECT_EQ(topology_error(unused), "");
}

TEST(MeshTopology, RejectsBadIndicesAndNonFinitePositions) {
  PolygonMesh out_of_range = test::cube();
  out_of_range.face_vertices[3] = 99;
  EXPECT_NE(topology_error(out_of_range).find("out of range"), std::string::npos);
  PolygonMesh not_finite = test::cube();
  not_finite.positions[2].y = std::nan("");
  EXPECT_NE(topology_error(not_finite).find("non-finite"), std::string::npos);
}

}  // namespace
}  // namespace isowave
