// The lifted wavelet transform (Bertram et al. 2000, Sec. 3.3-3.4):
// perfect reconstruction, zero detail for subdivided data, bicubic precision,
// agreement with a naive transcription of rules (3.8) and sharp rules (3.4),
// and identical results for any thread count.
#include <map>
#include <random>
#include <set>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "isowave/core/mesh_io.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/wavelet_transform.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

std::vector<Vec3> random_points(std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> points(count);
  for (Vec3& p : points) p = {u(rng), u(rng), u(rng)};
  return points;
}

double max_abs(const std::vector<Vec3>& points, std::size_t begin = 0, std::size_t end = SIZE_MAX) {
  double m = 0;
  for (std::size_t i = begin; i < std::min(end, points.size()); ++i)
    m = std::max({m, std::abs(points[i].x), std::abs(points[i].y), std::abs(points[i].z)});
  return m;
}

double max_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b, std::size_t count) {
  double m = 0;
  for (std::size_t i = 0; i < count; ++i) m = std::max(m, norm(a[i] - b[i]));
  return m;
}

// Maximum subdivision level for which a mesh stays under ~1.5 M fine vertices.
int affordable_levels(const PolygonMesh& mesh, int wanted) {
  int levels = wanted;
  while (levels > 1 && mesh.vertex_count() * (std::size_t{1} << (2 * levels)) > 1'500'000) --levels;
  return levels;
}

void check_perfect_reconstruction(const std::string& name, const PolygonMesh& mesh, int levels, std::uint32_t seed) {
  SCOPED_TRACE(name + " L=" + std::to_string(levels));
  const SubdivisionHierarchy hierarchy(mesh, levels);
  const std::vector<Vec3> fine = random_points(hierarchy.fine_vertex_count(), seed);
  std::vector<Vec3> data = fine;
  analyze(hierarchy, data);
  synthesize(hierarchy, data);
  EXPECT_LE(max_difference(data, fine, fine.size()), 1e-12 * max_abs(fine));
}

TEST(WaveletTransform, PerfectReconstructionOnGeneratedMeshes) {
  std::uint32_t seed = 1;
  for (const auto& [name, mesh] : test::generated_corpus())
    for (int levels = 1; levels <= 4; ++levels) check_perfect_reconstruction(name, mesh, levels, seed++);
}

TEST(WaveletTransform, PerfectReconstructionOnSharedMeshes) {
  const char* names[] = {"meshes/double_torus_quads.off", "meshes/elephant_106holes.off", "meshes/casting_genus9.off",
                         "meshes/mushroom_disk.off",      "meshes/fandisk_sharp.obj",     "meshes/bunny_holes.obj"};
  for (const char* name : names) {
    ISOWAVE_REQUIRE_SHARED_FILE(file, name);
    PolygonMesh mesh = read_mesh(file);
    remove_unreferenced_vertices(mesh);
    // Flag a few vertices sharp so the sharp rules run on real topology.
    mesh.sharp.assign(mesh.vertex_count(), 0);
    for (std::size_t v = 0; v < mesh.vertex_count(); v += 97) mesh.sharp[v] = 1;
    for (int levels = 1; levels <= affordable_levels(mesh, 4); ++levels)
      check_perfect_reconstruction(name, mesh, levels, 100 + static_cast<std::uint32_t>(levels));
  }
}

TEST(WaveletTransform, AnalysisOfSubdividedDataHasZeroDetail) {
  for (const auto& [name, mesh] : test::generated_corpus())
    for (int levels = 1; levels <= 4; ++levels) {
      SCOPED_TRACE(name + " L=" + std::to_string(levels));
      const SubdivisionHierarchy hierarchy(mesh, levels);
      const std::vector<Vec3> base = random_points(hierarchy.vertex_count(0), 17);
      std::vector<Vec3> data = subdivide(hierarchy, base);
      const double scale = max_abs(data);
      analyze(hierarchy, data);
      EXPECT_LE(max_difference(data, base, base.size()), 1e-12 * scale);
      EXPECT_LE(max_abs(data, base.size()), 1e-12 * scale);
    }
}

TEST(WaveletTransform, CoarserHierarchiesShareTheLayout) {
  // Synthesizing to level l and analysing with an l-level hierarchy returns the
  // first vertex_count(l) entries: the layout is a prefix at every level.
  const PolygonMesh mesh = test::genus_slab(2);
  const SubdivisionHierarchy fine(mesh, 3);
  const std::vector<Vec3> coefficients = random_points(fine.fine_vertex_count(), 5);
  for (int level = 0; level <= 3; ++level) {
    std::vector<Vec3> data = coefficients;
    synthesize(fine, data, level);
    const SubdivisionHierarchy coarse(mesh, level);
    data.resize(coarse.fine_vertex_count());
    analyze(coarse, data);
    EXPECT_LE(max_difference(data, coefficients, data.size()), 1e-12 * max_abs(coefficients)) << "level " << level;
  }
}

TEST(WaveletTransform, ResultsAreIdenticalForAnyThreadCount) {
  const PolygonMesh mesh = test::quad_grid(60, 50, true, true);  // large enough to split across threads
  const SubdivisionHierarchy hierarchy(mesh, 3);
  const std::vector<Vec3> fine = random_points(hierarchy.fine_vertex_count(), 3);
  std::vector<Vec3> one_thread = fine, two_threads = fine;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    analyze(hierarchy, one_thread);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    analyze(hierarchy, two_threads);
  }
  ASSERT_EQ(one_thread.size(), two_threads.size());
  for (std::size_t i = 0; i < one_thread.size(); ++i) ASSERT_TRUE(one_thread[i] == two_threads[i]) << i;
}

TEST(WaveletTransform, BicubicPrecisionAwayFromTheBoundary) {
  // Fine control points sampled from a bicubic polynomial lie in the span of
  // the coarse scaling functions: all interior wavelet coefficients vanish.
  const int n = 16, levels = 2, margin = 4;
  PolygonMesh grid = test::quad_grid(n, n);
  const SubdivisionHierarchy hierarchy(grid, levels);
  // S reproduces linear functions, so subdividing the flat grid gives every
  // fine vertex its dyadic (x, y) parameter.
  std::vector<Vec3> fine = subdivide(hierarchy, grid.positions);
  const auto p = [](double x, double y) {
    return 0.3 + 0.2 * x - 0.1 * y + 0.05 * x * y + 0.01 * x * x * x - 0.02 * y * y * y + 0.003 * x * x * y * y * y -
           0.001 * x * x * x * y * y * y + 0.004 * x * x * x * y;
  };
  std::vector<Vec3> data = fine;
  for (Vec3& v : data) v.z = p(v.x, v.y);
  const double scale = max_abs(data);
  const std::vector<Vec3> positions = data;
  analyze(hierarchy, data);
  std::size_t checked = 0;
  for (std::size_t i = hierarchy.vertex_count(0); i < data.size(); ++i) {
    const Vec3& where = positions[i];  // the fine position of the vertex at this index
    if (std::min({where.x, where.y, n - where.x, n - where.y}) < margin) continue;
    ++checked;
    ASSERT_LE(norm(data[i]), 1e-11 * scale) << "coefficient " << i << " at (" << where.x << ", " << where.y << ")";
  }
  EXPECT_GT(checked, 100u);

  // A quartic term is not in the span: the same interior coefficients do not vanish.
  std::vector<Vec3> quartic = positions;
  for (Vec3& v : quartic) v.z += 0.01 * v.x * v.x * v.x * v.x;
  analyze(hierarchy, quartic);
  double largest_interior = 0;
  for (std::size_t i = hierarchy.vertex_count(0); i < quartic.size(); ++i)
    if (std::min({positions[i].x, positions[i].y, n - positions[i].x, n - positions[i].y}) >= margin)
      largest_interior = std::max(largest_interior, norm(quartic[i]));
  EXPECT_GT(largest_interior, 1e-4);
}

// ---------------------------------------------------------------------------
// A naive transcription of the reconstruction rules (3.8) and the sharp rules
// of Sec. 3.4, computed from adjacency the test derives itself from the base
// mesh and the level-1 quads, to check the library's index arrays and kernels.
struct NaiveLevel {
  std::size_t vertices = 0;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edge_vertex;  // (a < b) -> e vertex
  std::vector<std::uint32_t> face_vertex;                                          // per base face
};

NaiveLevel identify_children(const PolygonMesh& base, const PolygonMesh& level1) {
  // In level 1, the e vertex of base edge (a, b) is the only common neighbour
  // of a and b; the f vertex of a face is opposite its corners in the quads.
  NaiveLevel level;
  level.vertices = base.vertex_count();
  std::vector<std::set<std::uint32_t>> neighbours(level1.vertex_count());
  for (std::size_t f = 0; f < level1.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      const std::uint32_t a = level1.face_begin(f)[k], b = level1.face_begin(f)[(k + 1) % 4];
      neighbours[a].insert(b);
      neighbours[b].insert(a);
    }
  level.face_vertex.resize(base.face_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t n = base.face_size(f);
    for (std::uint32_t k = 0; k < n; ++k) {
      std::uint32_t a = base.face_begin(f)[k], b = base.face_begin(f)[(k + 1) % n];
      std::vector<std::uint32_t> common;
      std::set_intersection(neighbours[a].begin(), neighbours[a].end(), neighbours[b].begin(), neighbours[b].end(),
                            std::back_inserter(common));
      EXPECT_EQ(common.size(), 1u);
      level.edge_vertex[{std::min(a, b), std::max(a, b)}] = common.at(0);
    }
    // f vertex: the level-1 quad at corner 0 is (corner, e, f, e').
    const std::uint32_t corner = base.face_begin(f)[0];
    const std::uint32_t e = level.edge_vertex[{std::min(corner, base.face_begin(f)[1]), std::max(corner, base.face_begin(f)[1])}];
    for (std::uint32_t candidate : neighbours[e])
      if (candidate >= base.vertex_count() && neighbours[candidate].count(level.edge_vertex[{std::min(corner, base.face_begin(f)[n - 1]), std::max(corner, base.face_begin(f)[n - 1])}]))
        level.face_vertex[f] = candidate;
  }
  return level;
}

std::vector<Vec3> naive_synthesis(const PolygonMesh& base, const NaiveLevel& level, std::vector<Vec3> p) {
  using Edge = std::pair<std::uint32_t, std::uint32_t>;
  std::map<Edge, std::vector<std::uint32_t>> edge_faces;  // base faces per edge
  std::vector<std::vector<std::uint32_t>> vertex_faces(base.vertex_count());
  std::vector<std::set<std::uint32_t>> vertex_neighbours(base.vertex_count());
  for (std::uint32_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t n = base.face_size(f);
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t a = base.face_begin(f)[k], b = base.face_begin(f)[(k + 1) % n];
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
      vertex_faces[a].push_back(f);
      vertex_neighbours[a].insert(b);
      vertex_neighbours[b].insert(a);
    }
  }
  const auto is_boundary = [&](std::uint32_t a, std::uint32_t b) { return edge_faces[{std::min(a, b), std::max(a, b)}].size() == 1; };
  const auto e_of = [&](std::uint32_t a, std::uint32_t b) { return level.edge_vertex.at({std::min(a, b), std::max(a, b)}); };
  const auto sharp_edges_at = [&](std::uint32_t v) {
    std::vector<std::uint32_t> result;
    for (std::uint32_t w : vertex_neighbours[v])
      if (is_boundary(v, w)) result.push_back(w);
    return result;
  };
  const auto kind = [&](std::uint32_t v) {  // 0 smooth, 1 crease, 2 sharp
    const std::size_t sharp_edges = sharp_edges_at(v).size();
    if (base.is_sharp(v) || sharp_edges >= 3) return 2;
    return sharp_edges == 2 ? 1 : 0;
  };
  const auto f_bar_e = [&](const Edge& e) {
    Vec3 s;
    for (std::uint32_t f : edge_faces[e]) s += p[level.face_vertex[f]];
    return s * (1.0 / double(edge_faces[e].size()));
  };
  const auto f_bar_v = [&](std::uint32_t v) {
    Vec3 s;
    for (std::uint32_t f : vertex_faces[v]) s += p[level.face_vertex[f]];
    return s * (1.0 / double(vertex_faces[v].size()));
  };
  const auto e_bar_v = [&](std::uint32_t v, bool sharp_only) {
    Vec3 s;
    int count = 0;
    for (std::uint32_t w : vertex_neighbours[v])
      if (!sharp_only || is_boundary(v, w)) {
        s += p[e_of(v, w)];
        ++count;
      }
    return s * (1.0 / count);
  };
  const auto smooth_edge = [&](const Edge& e) {
    return edge_faces[e].size() == 2 && kind(e.first) != 2 && kind(e.second) != 2;
  };
  // Rule 1: e <- e - 3/4 f̄_e (smooth edges only)
  for (const auto& [e, faces] : edge_faces)
    if (smooth_edge(e)) p[level.edge_vertex.at(e)] -= 0.75 * f_bar_e(e);
  // Rule 2: v <- v - 9/16 f̄_v - 3/2 ē_v ; crease: v <- v - 3/4 ē_v(sharp)
  std::vector<Vec3> next = p;
  for (std::uint32_t v = 0; v < base.vertex_count(); ++v) {
    if (kind(v) == 0) next[v] = p[v] - (9.0 / 16.0) * f_bar_v(v) - 1.5 * e_bar_v(v, false);
    if (kind(v) == 1) next[v] = p[v] - 0.75 * e_bar_v(v, true);
  }
  p = next;
  // Rule 3: e <- e + v̄_e
  for (const auto& [e, faces] : edge_faces) p[level.edge_vertex.at(e)] += 0.5 * (p[e.first] + p[e.second]);
  // Rule 4: f <- f - v̄_f + 2 ē_f
  for (std::uint32_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t n = base.face_size(f);
    Vec3 v_bar, e_bar;
    for (std::uint32_t k = 0; k < n; ++k) {
      v_bar += p[base.face_begin(f)[k]] * (1.0 / n);
      e_bar += p[e_of(base.face_begin(f)[k], base.face_begin(f)[(k + 1) % n])] * (1.0 / n);
    }
    p[level.face_vertex[f]] += -1.0 * v_bar + 2.0 * e_bar;
  }
  // Rule 5: e <- 1/2 e + 1/2 f̄_e (smooth edges only)
  for (const auto& [e, faces] : edge_faces)
    if (smooth_edge(e)) p[level.edge_vertex.at(e)] = 0.5 * p[level.edge_vertex.at(e)] + 0.5 * f_bar_e(e);
  // Rule 6: v <- 1/4 v - 1/4 f̄_v + ē_v ; crease: v <- 1/2 v + 1/2 ē_v(sharp)
  next = p;
  for (std::uint32_t v = 0; v < base.vertex_count(); ++v) {
    if (kind(v) == 0) next[v] = 0.25 * p[v] - 0.25 * f_bar_v(v) + e_bar_v(v, false);
    if (kind(v) == 1) next[v] = 0.5 * p[v] + 0.5 * e_bar_v(v, true);
  }
  return next;
}

TEST(WaveletTransform, SynthesisMatchesANaiveTranscriptionOfTheRules) {
  for (const auto& [name, mesh] : test::generated_corpus()) {
    SCOPED_TRACE(name);
    const SubdivisionHierarchy hierarchy(mesh, 1);
    const NaiveLevel level = identify_children(mesh, hierarchy.control_mesh(1, std::vector<Vec3>(hierarchy.vertex_count(1))));
    const std::vector<Vec3> coefficients = random_points(hierarchy.fine_vertex_count(), 11);
    std::vector<Vec3> data = coefficients;
    synthesize(hierarchy, data);
    const std::vector<Vec3> expected = naive_synthesis(mesh, level, coefficients);
    EXPECT_LE(max_difference(data, expected, data.size()), 1e-12 * max_abs(expected));
  }
}

// wavelet_squared_norms() against the definition: the dense synthesis of
// every coefficient's unit vector, its squared norm over the fine control
// points, on the generated corpus (boundaries, creases, sharp vertices,
// polygons), with and without sharp vertices.
TEST(WaveletTransform, WaveletSquaredNormsAreThoseOfTheSynthesizedUnitVectors) {
  for (const auto& [name, mesh] : test::generated_corpus()) {
    for (const bool sharp : {false, true}) {
      PolygonMesh base = mesh;
      if (sharp) {
        base.sharp.assign(base.vertex_count(), 0);
        for (std::size_t v = 0; v < base.vertex_count(); v += 4) base.sharp[v] = 1;
      }
      const SubdivisionHierarchy h(base, 2);
      const std::vector<double> norms = wavelet_squared_norms(h);
      ASSERT_EQ(norms.size(), h.fine_vertex_count());
      for (std::size_t i = 0; i < h.vertex_count(0); ++i) ASSERT_EQ(norms[i], 0.0);
      for (std::size_t i = h.vertex_count(0); i < h.fine_vertex_count(); ++i) {
        std::vector<Vec3> unit(h.fine_vertex_count());
        unit[i].x = 1;
        synthesize(h, unit);
        double expected = 0;
        for (const Vec3& p : unit) expected += p.x * p.x;
        ASSERT_NEAR(norms[i], expected, 1e-12 * expected) << name << (sharp ? " with sharp vertices" : "") << " entry " << i;
      }
    }
  }
}

}  // namespace
}  // namespace isowave
