// The smoothing of the surface map (map_smoothing.h): on a flat square whose
// map is deliberately tangled, it must untangle it and reach the mean-value
// parametrization, which for a planar mesh with its boundary fixed is the
// mesh itself (mean-value weights reproduce linear functions: Floater 2003);
// on simplified meshes it must keep every vertex in the base mesh, not add
// inverted triangles, and give the same map for any thread count.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "isowave/core/mesh_io.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/fit/map_smoothing.h"
#include "isowave/simplify/simplify.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

using Triangle = std::array<std::uint32_t, 3>;
// Inverted input triangles a smoothed map may keep (their share of all).
constexpr double kMaxInvertedShare = 0.01;
// On a mesh with many holes whose boundary vertices stay (elephant: 106).
constexpr double kMaxInvertedShareManyHoles = 0.11;

// A point of the base mesh from a map entry.
Vec3 mapped_point(const simplify::SurfaceMap& map, const std::vector<Vec3>& base, std::size_t v) {
  const Triangle& t = map.triangles[map.vertex_triangle[v]];
  const auto [u, w] = map.vertex_uv[v];
  return (1 - u - w) * base[t[0]] + u * base[t[1]] + w * base[t[2]];
}

void expect_in_domain(const simplify::SurfaceMap& map) {
  for (std::size_t v = 0; v < map.vertex_count(); ++v) {
    const auto [u, w] = map.vertex_uv[v];
    ASSERT_LT(map.vertex_triangle[v], map.triangle_count()) << v;
    ASSERT_TRUE(u >= 0 && w >= 0 && u + w <= 1 + 1e-12) << v << ": " << u << ", " << w;
  }
}

// The flat case: the square [0, n]^2 of an n x n grid (quads split from
// their first corner), on the base mesh of its four corners (2 triangles).
struct FlatSquare {
  int n;
  PolygonMesh surface;
  std::vector<Vec3> base;
  simplify::SurfaceMap map;

  explicit FlatSquare(int size) : n(size), surface(test::quad_grid(size, size)) {
    base = {{0, 0, 0}, {double(n), 0, 0}, {double(n), double(n), 0}, {0, double(n), 0}};
    map.triangles = {{0, 1, 2}, {0, 2, 3}};
    map.triangle_face = {0, 0};
    for (const Vec3& p : surface.positions) place(p);
  }
  bool on_boundary(const Vec3& p) const { return p.x == 0 || p.y == 0 || p.x == n || p.y == n; }
  // Maps point p of the square into the base triangle holding it.
  void place(const Vec3& p) {
    const bool lower = p.x >= p.y;  // triangle (0, 1, 2) below the diagonal
    const Triangle& t = map.triangles[lower ? 0 : 1];
    // Barycentric weights in the right triangles of the square.
    const Vec3 a = base[t[0]], b = base[t[1]], c = base[t[2]];
    const double det = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    const double u = ((p.x - a.x) * (c.y - a.y) - (p.y - a.y) * (c.x - a.x)) / det;
    const double w = ((b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)) / det;
    map.vertex_triangle.push_back(lower ? 0 : 1);
    map.vertex_uv.push_back({u, w});
  }
  // Moves every inner vertex's map point by up to `amount` cells each way.
  void tangle(double amount, std::uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> offset(-amount, amount);
    map.vertex_triangle.clear();
    map.vertex_uv.clear();
    for (const Vec3& p : surface.positions) {
      Vec3 q = p;
      if (!on_boundary(p)) {
        q.x = std::clamp(p.x + offset(random), 0.05, n - 0.05);
        q.y = std::clamp(p.y + offset(random), 0.05, n - 0.05);
      }
      place(q);
    }
  }
  // Input triangles (faces fanned from their first corner) whose map images
  // in the plane are not positively oriented.
  std::size_t inverted() const {
    std::size_t count = 0;
    for (std::size_t f = 0; f < surface.face_count(); ++f) {
      const std::uint32_t* v = surface.face_begin(f);
      for (std::uint32_t k = 1; k + 1 < surface.face_size(f); ++k) {
        const Vec3 a = mapped_point(map, base, v[0]), b = mapped_point(map, base, v[k]),
                   c = mapped_point(map, base, v[k + 1]);
        if (!((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) > 0)) ++count;
      }
    }
    return count;
  }
};

TEST(MapSmoothingTest, UntanglesAFlatSquareAndReachesItsMeanValuePositions) {
  FlatSquare square(8);
  square.tangle(0.8, 7);
  const std::size_t tangled = square.inverted();
  ASSERT_GT(tangled, 0u) << "the distortion must turn triangles over";
  SmoothingOptions options;
  options.mode = SmoothingMode::Relax;
  options.max_rounds = 1000;
  options.min_move = 1e-12;
  const SmoothingStatistics s = smooth_surface_map(square.map, square.surface, square.base, options);
  EXPECT_EQ(s.inverted_before, tangled);
  EXPECT_EQ(s.inverted_after, 0u);
  EXPECT_EQ(square.inverted(), 0u);
  EXPECT_EQ(s.free_vertices, 7u * 7u);
  expect_in_domain(square.map);
  for (std::size_t v = 0; v < square.surface.vertex_count(); ++v) {
    const Vec3 p = mapped_point(square.map, square.base, v);
    EXPECT_NEAR(p.x, square.surface.positions[v].x, 1e-6) << v;
    EXPECT_NEAR(p.y, square.surface.positions[v].y, 1e-6) << v;
  }
}

TEST(MapSmoothingTest, KeepsBoundaryVerticesAndAnUntangledMapStaysPut) {
  FlatSquare square(6);
  const simplify::SurfaceMap exact = square.map;
  const SmoothingStatistics s = smooth_surface_map(square.map, square.surface, square.base);
  EXPECT_EQ(s.inverted_before, 0u);
  EXPECT_EQ(s.inverted_after, 0u);
  EXPECT_EQ(s.rounds, 1);  // nothing moves: the exact map is its own mean-value map
  for (std::size_t v = 0; v < square.surface.vertex_count(); ++v) {
    const Vec3 p = mapped_point(square.map, square.base, v), q = mapped_point(exact, square.base, v);
    EXPECT_NEAR(norm(p - q), 0.0, 1e-9) << v;
  }
}

TEST(MapSmoothingTest, ZeroRoundsLeaveTheMap) {
  FlatSquare square(4);
  square.tangle(0.8, 3);
  const simplify::SurfaceMap before = square.map;
  SmoothingOptions options;
  options.max_rounds = 0;
  const SmoothingStatistics s = smooth_surface_map(square.map, square.surface, square.base, options);
  EXPECT_EQ(s.rounds, 0);
  EXPECT_EQ(s.inverted_before, 0u);  // not counted
  EXPECT_EQ(square.map.vertex_uv, before.vertex_uv);
  EXPECT_EQ(square.map.vertex_triangle, before.vertex_triangle);
}

simplify::SimplifyResult simplified_with_map(const PolygonMesh& input, std::size_t target) {
  simplify::SimplifyOptions options;
  options.target_vertices = target;
  options.surface_map = simplify::SurfaceMapping::Build;
  options.compute_distance = false;
  return simplify::simplify(input, options);
}

PolygonMesh mixing_isosurface(std::size_t samples) {
  IsosurfaceOptions extract;
  extract.iso = 0;
  return extract_isosurface(make_builtin_field("mixing", samples), extract).mesh;
}

TEST(MapSmoothingTest, SameMapForOneAndTwoThreads) {
  const PolygonMesh input = mixing_isosurface(40);
  const simplify::SimplifyResult simplified = simplified_with_map(input, input.vertex_count() / 20);
  simplify::SurfaceMap one = simplified.map, two = simplified.map;
  SmoothingOptions relax;
  relax.mode = SmoothingMode::Relax;
  {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 1);
    smooth_surface_map(one, input, simplified.base.positions, relax);
  }
  {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
    smooth_surface_map(two, input, simplified.base.positions, relax);
  }
  EXPECT_NE(one.vertex_uv, simplified.map.vertex_uv);
  EXPECT_EQ(one.vertex_triangle, two.vertex_triangle);
  EXPECT_EQ(one.vertex_uv, two.vertex_uv);
}

// Input triangles with all three corners mapped into one base triangle and
// turned over there.
std::size_t same_triangle_inverted(const PolygonMesh& input, const simplify::SurfaceMap& map) {
  std::size_t count = 0;
  for (std::size_t f = 0; f < input.face_count(); ++f) {
    const std::uint32_t* v = input.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < input.face_size(f); ++k) {
      const std::uint32_t t = map.vertex_triangle[v[0]];
      if (map.vertex_triangle[v[k]] != t || map.vertex_triangle[v[k + 1]] != t) continue;
      const auto &a = map.vertex_uv[v[0]], &b = map.vertex_uv[v[k]], &c = map.vertex_uv[v[k + 1]];
      count += (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0;
    }
  }
  return count;
}

void check_smoothing(const PolygonMesh& input, const simplify::SimplifyResult& simplified, SmoothingMode mode,
                     double max_inverted_share, const std::string& name) {
  const char* mode_name = mode == SmoothingMode::Relax ? "relax" : "untangle";
  SCOPED_TRACE(name + ", " + mode_name);
  const simplify::SurfaceMap& before = simplified.map;
  simplify::SurfaceMap map = before;
  SmoothingOptions options;
  options.mode = mode;
  const SmoothingStatistics s = smooth_surface_map(map, input, simplified.base.positions, options);
  std::size_t triangles = 0;
  for (std::size_t f = 0; f < input.face_count(); ++f) triangles += input.face_size(f) - 2;
  std::printf("%s, %s: %zu input triangles, inverted %zu -> %zu (%.3f%% -> %.3f%%), %d rounds, mean move %.3g, "
              "%.2f s\n",
              name.c_str(), mode_name, triangles, s.inverted_before, s.inverted_after,
              100.0 * double(s.inverted_before) / double(triangles), 100.0 * double(s.inverted_after) / double(triangles),
              s.rounds, s.mean_move, s.seconds);
  expect_in_domain(map);
  EXPECT_LE(s.inverted_after, s.inverted_before);
  std::size_t moved = 0;
  for (std::size_t v = 0; v < input.vertex_count(); ++v) {
    const bool same = map.vertex_triangle[v] == before.vertex_triangle[v] && map.vertex_uv[v] == before.vertex_uv[v];
    const auto [u, w] = before.vertex_uv[v];
    if (u == 1 || w == 1 || (u == 0 && w == 0)) {
      EXPECT_TRUE(same) << "base vertex survivor " << v << " moved";
    }
    moved += !same;
  }
  if (mode == SmoothingMode::Relax || s.inverted_before > 0) {
    EXPECT_GT(moved, 0u);
  }
  EXPECT_LE(moved, s.free_vertices);
  EXPECT_LE(double(s.inverted_after) / double(triangles), max_inverted_share);
  // Independently of the unfoldings: triangles with all corners in one base
  // triangle, turned over in its (u, v) coordinates (as the simplifier's test counts).
  const std::size_t same_before = same_triangle_inverted(input, before), same_after = same_triangle_inverted(input, map);
  std::printf("  inverted within one base triangle: %zu -> %zu\n", same_before, same_after);
  EXPECT_LE(same_after, same_before);
}

// On simplified meshes, in both modes: every vertex stays in the base mesh,
// the base vertices' survivors keep their points, and the inverted input
// triangles do not grow in number and end below a share of all (the
// simplifier's map has about 1%, the mixing isosurface 2.6%).
void check_smoothing(const PolygonMesh& input, std::size_t target, const std::string& name,
                     double max_inverted_share = kMaxInvertedShare) {
  const simplify::SimplifyResult simplified = simplified_with_map(input, target);
  for (const SmoothingMode mode : {SmoothingMode::Untangle, SmoothingMode::Relax})
    check_smoothing(input, simplified, mode, max_inverted_share, name);
}

TEST(MapSmoothingTest, SmoothsTheMapsOfGeneratedMeshes) {
  for (const test::NamedMesh& named : test::generated_corpus()) {
    if (named.mesh.vertex_count() < 200) continue;
    check_smoothing(named.mesh, named.mesh.vertex_count() / 8, named.name);
  }
  const PolygonMesh mixing = mixing_isosurface(48);
  check_smoothing(mixing, mixing.vertex_count() / 20, "mixing 48");
}

TEST(MapSmoothingTest, SmoothsTheMapsOfTheMeshCorpus) {
  struct CorpusMesh {
    const char* file;
    double max_inverted_share;
  };
  const CorpusMesh corpus[] = {
      {"fertility_genus4.off", kMaxInvertedShare},  {"casting_genus9.off", kMaxInvertedShare},
      {"knot_genus1.off", kMaxInvertedShare},       {"mushroom_disk.off", kMaxInvertedShare},
      {"mech_4holes.off", kMaxInvertedShare},       {"elephant_106holes.off", kMaxInvertedShareManyHoles},
      {"fandisk_sharp.obj", kMaxInvertedShare},     {"rocker_arm_genus1.obj", kMaxInvertedShare},
  };
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "shared data absent";
  for (const CorpusMesh& mesh : corpus) {
    const PolygonMesh input = read_mesh(test::shared_data_file(std::string("meshes/") + mesh.file));
    check_smoothing(input, input.vertex_count() / 30, mesh.file, mesh.max_inverted_share);
  }
}

}  // namespace
}  // namespace isowave
