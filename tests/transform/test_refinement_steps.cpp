// The hierarchy's own refinement against OpenSubdiv's: the .isw coefficient
// order follows OpenSubdiv's numbering, so every array of every refinement
// step must be identical, on closed meshes, meshes with boundary, polygons of
// 3 to 6 sides, sharp vertices, shuffled vertex and corner orders, and a mesh
// large enough that the parallel loops split.
#include <algorithm>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/refinement_steps.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

// The same surface with vertices renumbered at random and every face starting
// at a random corner: other edge numberings and orientations.
PolygonMesh shuffled(const PolygonMesh& mesh, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<std::uint32_t> new_index(mesh.vertex_count());
  std::iota(new_index.begin(), new_index.end(), 0u);
  std::shuffle(new_index.begin(), new_index.end(), rng);
  PolygonMesh result;
  result.positions.resize(mesh.vertex_count());
  if (!mesh.sharp.empty()) result.sharp.resize(mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    result.positions[new_index[v]] = mesh.positions[v];
    if (!mesh.sharp.empty()) result.sharp[new_index[v]] = mesh.sharp[v];
  }
  std::vector<std::size_t> face_order(mesh.face_count());
  std::iota(face_order.begin(), face_order.end(), std::size_t{0});
  std::shuffle(face_order.begin(), face_order.end(), rng);
  for (std::size_t f : face_order) {
    const std::uint32_t n = mesh.face_size(f);
    const std::uint32_t start = rng() % n;
    std::vector<std::uint32_t> face;
    for (std::uint32_t k = 0; k < n; ++k) face.push_back(new_index[mesh.face_begin(f)[(start + k) % n]]);
    result.add_face(face.data(), face.size());
  }
  return result;
}

// A grid of nx * ny cells with a rectangular hole; some cells split into two
// triangles, some pairs of cells merged into hexagons, some vertices sharp.
PolygonMesh mixed_grid(int nx, int ny, std::uint32_t seed) {
  std::mt19937 rng(seed);
  PolygonMesh mesh;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) mesh.positions.push_back({double(i), double(j), 0.0});
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  const auto in_hole = [&](int i, int j) { return i >= nx / 3 && i < nx / 2 && j >= ny / 3 && j < ny / 2; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (in_hole(i, j)) continue;
      const int kind = static_cast<int>(rng() % 8);
      if (kind == 0) {
        mesh.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        mesh.add_face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      } else if (kind == 1 && i + 1 < nx && !in_hole(i + 1, j)) {
        mesh.add_face({id(i, j), id(i + 1, j), id(i + 2, j), id(i + 2, j + 1), id(i + 1, j + 1), id(i, j + 1)});
        ++i;
      } else {
        mesh.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      }
    }
  remove_unreferenced_vertices(mesh);
  mesh.sharp.assign(mesh.vertex_count(), 0);
  for (std::size_t v = 0; v < mesh.vertex_count(); v += 37) mesh.sharp[v] = 1;
  return mesh;
}

void expect_identical(const RefinementStep& own, const RefinementStep& reference, int level) {
  SCOPED_TRACE("step to level " + std::to_string(level));
  EXPECT_EQ(own.parent_vertex_count, reference.parent_vertex_count);
  EXPECT_EQ(own.parent_face_count, reference.parent_face_count);
  EXPECT_EQ(own.parent_edge_count, reference.parent_edge_count);
  EXPECT_TRUE(own.edge_vertices == reference.edge_vertices) << "edge_vertices";
  EXPECT_TRUE(own.edge_faces == reference.edge_faces) << "edge_faces";
  EXPECT_TRUE(own.edge_smooth == reference.edge_smooth) << "edge_smooth";
  EXPECT_TRUE(own.face_offsets == reference.face_offsets) << "face_offsets";
  EXPECT_TRUE(own.face_vertices == reference.face_vertices) << "face_vertices";
  EXPECT_TRUE(own.face_edges == reference.face_edges) << "face_edges";
  EXPECT_TRUE(own.vertex_edge_offsets == reference.vertex_edge_offsets) << "vertex_edge_offsets";
  EXPECT_TRUE(own.vertex_edges == reference.vertex_edges) << "vertex_edges";
  EXPECT_TRUE(own.vertex_face_offsets == reference.vertex_face_offsets) << "vertex_face_offsets";
  EXPECT_TRUE(own.vertex_faces == reference.vertex_faces) << "vertex_faces";
  EXPECT_TRUE(own.vertex_rule == reference.vertex_rule) << "vertex_rule";
  EXPECT_TRUE(own.crease_vertices == reference.crease_vertices) << "crease_vertices";
  EXPECT_TRUE(own.crease_edges == reference.crease_edges) << "crease_edges";
}

void expect_same_steps(const PolygonMesh& mesh, int levels) {
  const std::vector<RefinementStep> own = detail::build_refinement_steps(mesh, levels);
  const std::vector<RefinementStep> reference = detail::build_refinement_steps_with_opensubdiv(mesh, levels);
  ASSERT_EQ(own.size(), static_cast<std::size_t>(levels));
  ASSERT_EQ(reference.size(), static_cast<std::size_t>(levels));
  for (int l = 0; l < levels; ++l) expect_identical(own[l], reference[l], l + 1);
}

TEST(RefinementSteps, OwnRefinementEqualsOpenSubdivOnTheGeneratedCorpus) {
  for (const auto& [name, mesh] : test::generated_corpus()) {
    SCOPED_TRACE(name);
    expect_same_steps(mesh, 4);
    SCOPED_TRACE("shuffled");
    expect_same_steps(shuffled(mesh, 7), 3);
  }
}

TEST(RefinementSteps, OwnRefinementEqualsOpenSubdivOnALargeMixedMeshSplitAcrossThreads) {
  // 150 x 120 cells: the finer levels have far more elements than one
  // parallel chunk (16384), so the split loops are compared too.
  const PolygonMesh grid = mixed_grid(150, 120, 3);
  ASSERT_NO_THROW(require_manifold(grid, "mixed grid"));
  ASSERT_GT(summarize_topology(grid).boundary_edges, 0u);
  expect_same_steps(grid, 3);
  expect_same_steps(shuffled(grid, 11), 2);
}

TEST(RefinementSteps, OwnRefinementEqualsOpenSubdivOnRealMeshes) {
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "../shared/data absent";
  int compared = 0;
  for (const char* name : {"meshes/fandisk_sharp.obj", "meshes/bunny_holes.obj", "meshes/double_torus_quads.off",
                           "meshes/elephant_106holes.off", "meshes/mushroom_disk.off"}) {
    const std::string path = test::shared_data_file(name);
    if (path.empty()) continue;
    SCOPED_TRACE(name);
    const PolygonMesh mesh = read_mesh(path);
    try {
      require_manifold(mesh, name);
    } catch (const Error&) {
      continue;  // the hierarchy takes only manifold meshes
    }
    expect_same_steps(mesh, 2);
    ++compared;
  }
  EXPECT_GT(compared, 0);
}

TEST(RefinementSteps, ZeroLevelsGiveNoSteps) {
  EXPECT_TRUE(detail::build_refinement_steps(test::cube(), 0).empty());
  EXPECT_TRUE(detail::build_refinement_steps_with_opensubdiv(test::cube(), 0).empty());
}

}  // namespace
}  // namespace isowave
