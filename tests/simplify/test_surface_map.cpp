// The MAPS map simplify() builds (surface_map.h): every input vertex in
// exactly one base triangle with valid barycentric coordinates, no two at
// one parameter point, and the base triangles tiling the base faces. The map
// is bijective on vertices; the straight-line image of an input triangle is
// not guaranteed to keep its orientation (each collapse's chart map is
// piecewise affine, and a thin triangle across one of its kinks can turn
// over, as in MAPS), so the tests bound the share of input triangles
// mapped into one base triangle that turn over: kMaxInvertedShare. The
// history (SurfaceMapHistory), which the fit inverts exactly, is checked for
// what makes that inverse a bijection: every operation's consumed triangles
// tile the same chart polygon as the triangles it made, and every triangle
// ever made is consumed exactly once or is a base triangle.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "isowave/core/mesh_io.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/simplify/simplify.h"
#include "simplify_test_meshes.h"

namespace isowave::simplify {
namespace {

constexpr double kMaxInvertedShare = 0.06;

struct MapCheck {
  std::size_t same_triangle = 0;  // input triangles with all three vertices in one base triangle
  std::size_t inverted = 0;       // of those, mapped with the opposite orientation
  std::size_t duplicates = 0;     // input vertices sharing a parameter point
  double inverted_share() const { return same_triangle ? double(inverted) / double(same_triangle) : 0.0; }
};

// Checks the history's invariants (see the top of the file).
void check_history(const PolygonMesh& input, const SurfaceMap& map) {
  const SurfaceMapHistory& h = map.history;
  ASSERT_EQ(h.input_corners.size(), input.face_count());
  ASSERT_EQ(h.base_version.size(), map.triangle_count());
  const std::size_t versions = h.made_begin.back();
  std::vector<int> uses(versions, 0);
  for (const std::uint32_t v : h.base_version) ++uses.at(v);
  for (const std::uint32_t v : h.consumed) ++uses.at(v);
  EXPECT_EQ(std::count(uses.begin(), uses.end(), 1), std::ptrdiff_t(versions)) << "a triangle used twice or never";
  // The input triangles, as oriented triangles of input vertices (any order).
  const auto canonical = [](std::array<std::uint32_t, 3> t) {
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
  };
  std::vector<std::array<std::uint32_t, 3>> expected, recorded;
  for (std::size_t t = 0; t < input.face_count(); ++t) {
    const std::uint32_t* f = input.face_begin(t);
    expected.push_back(canonical({f[0], f[1], f[2]}));
    recorded.push_back(canonical(h.input_corners[t]));
  }
  std::sort(expected.begin(), expected.end());
  std::sort(recorded.begin(), recorded.end());
  EXPECT_EQ(expected, recorded) << "the history's input triangles are not the input's";
  std::size_t untiled = 0, flat_made = 0, turned = 0;
  const auto area = [&](std::size_t r, const std::array<std::uint8_t, 3>& c) {
    const auto* p = h.chart.data() + h.chart_begin[r];
    return 0.5 * ((double(p[c[1]][0]) - p[c[0]][0]) * (double(p[c[2]][1]) - p[c[0]][1]) -
                  (double(p[c[1]][1]) - p[c[0]][1]) * (double(p[c[2]][0]) - p[c[0]][0]));
  };
  for (std::size_t r = 0; r < h.operation_count(); ++r) {
    double before = 0, after = 0;
    for (std::uint32_t c = h.consumed_begin[r]; c < h.consumed_begin[r + 1]; ++c) {
      const double a = area(r, h.consumed_corners[c]);
      turned += a < -1e-7;
      before += a;
    }
    for (std::uint32_t v = h.made_begin[r]; v < h.made_begin[r + 1]; ++v) {
      const double a = area(r, h.made_corners[v - input.face_count()]);
      flat_made += !(a > 0);
      after += a;
    }
    untiled += std::abs(before - after) > 1e-5 * std::max(1.0, after);
  }
  EXPECT_EQ(untiled, 0u) << "operations whose triangles before and after cover different areas";
  EXPECT_EQ(flat_made, 0u) << "made triangles without area";
  EXPECT_EQ(turned, 0u) << "consumed triangles turned over in their chart";
}

// Checks the map's structure against the base mesh and counts folds.
MapCheck check_map(const PolygonMesh& input, const SimplifyResult& result, const std::string& name) {
  SCOPED_TRACE(name);
  const SurfaceMap& map = result.map;
  const PolygonMesh& base = result.base;
  MapCheck check;
  EXPECT_EQ(map.vertex_count(), input.vertex_count());
  EXPECT_EQ(map.vertex_uv.size(), input.vertex_count());
  EXPECT_EQ(map.triangle_face.size(), map.triangle_count());
  // Each base face of n sides is n - 2 triangles on its own corners.
  std::vector<std::size_t> triangles_of(base.face_count(), 0);
  for (std::size_t t = 0; t < map.triangle_count(); ++t) {
    const std::uint32_t f = map.triangle_face[t];
    if (f >= base.face_count()) {
      ADD_FAILURE() << "triangle " << t << " has face " << f;
      return check;
    }
    ++triangles_of[f];
    const std::uint32_t* corners = base.face_begin(f);
    for (const std::uint32_t v : map.triangles[t])
      EXPECT_NE(std::find(corners, corners + base.face_size(f), v), corners + base.face_size(f))
          << "triangle " << t << " uses vertex " << v << ", not a corner of face " << f;
  }
  for (std::size_t f = 0; f < base.face_count(); ++f) EXPECT_EQ(triangles_of[f], base.face_size(f) - 2) << "face " << f;
  // Every input vertex in exactly one triangle, at valid barycentric coordinates.
  std::map<std::tuple<std::uint32_t, double, double>, int> seen;
  for (std::size_t v = 0; v < map.vertex_count(); ++v) {
    const auto [u, w] = map.vertex_uv[v];
    EXPECT_LT(map.vertex_triangle[v], map.triangle_count());
    EXPECT_TRUE(u >= 0 && w >= 0 && u + w <= 1 + 1e-12) << "vertex " << v << ": " << u << ", " << w;
    if (++seen[{map.vertex_triangle[v], u, w}] > 1) ++check.duplicates;
  }
  check_history(input, map);
  for (std::size_t f = 0; f < input.face_count(); ++f) {
    const std::uint32_t* corner = input.face_begin(f);
    const std::uint32_t t = map.vertex_triangle[corner[0]];
    if (map.vertex_triangle[corner[1]] != t || map.vertex_triangle[corner[2]] != t) continue;
    ++check.same_triangle;
    const auto& a = map.vertex_uv[corner[0]];
    const auto& b = map.vertex_uv[corner[1]];
    const auto& c = map.vertex_uv[corner[2]];
    const double area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if (area < 0) ++check.inverted;
  }
  return check;
}

SimplifyOptions mapped(std::size_t target) {
  SimplifyOptions options;
  options.target_vertices = target;
  options.surface_map = SurfaceMapping::Build;
  options.compute_distance = false;
  return options;
}

TEST(SurfaceMapTest, WithoutCollapsesEveryVertexSitsAtItsOwnCorner) {
  const PolygonMesh input = test::icosphere(2);
  SimplifyOptions options = mapped(input.vertex_count());
  options.edge_removal = false;
  options.valence_flips = false;
  const SimplifyResult result = simplify(input, options);
  ASSERT_EQ(result.base.vertex_count(), input.vertex_count());
  const SurfaceMap& map = result.map;
  for (std::size_t v = 0; v < input.vertex_count(); ++v) {
    const auto& corners = map.triangles[map.vertex_triangle[v]];
    const auto [u, w] = map.vertex_uv[v];
    const int corner = u == 1 ? 1 : w == 1 ? 2 : 0;
    ASSERT_TRUE((u == 0 || u == 1) && (w == 0 || w == 1) && u + w <= 1) << v;
    // Base vertices keep positions: the corner's vertex is this one.
    EXPECT_EQ(result.base.positions[corners[corner]], input.positions[v]) << v;
  }
}

TEST(SurfaceMapTest, MapIsBijectiveOnGeneratedMeshes) {
  for (const test::NamedMesh& named : test::generated_corpus()) {
    const PolygonMesh input = test::fan_triangulate(named.mesh);
    SimplifyOptions options = mapped(std::max<std::size_t>(4, input.vertex_count() / 8));
    options.validate_every_collapse = input.vertex_count() < 3000;
    const SimplifyResult result = simplify(input, options);
    const MapCheck check = check_map(input, result, named.name);
    // A handful of triangles: one may turn over.
    EXPECT_LE(double(check.inverted), std::max(1.0, kMaxInvertedShare * double(check.same_triangle)))
        << named.name << ": " << check.inverted << " of " << check.same_triangle;
    EXPECT_EQ(check.duplicates, 0u) << named.name;
  }
}

TEST(SurfaceMapTest, MapIsBijectiveOnTheMeshCorpus) {
  const std::vector<std::string> files = {"fertility_genus4.off", "casting_genus9.off", "knot_genus1.off",
                                          "mushroom_disk.off",    "mech_4holes.off",    "elephant_106holes.off",
                                          "fandisk_sharp.obj",    "rocker_arm_genus1.obj"};
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "shared data absent";
  for (const std::string& file : files) {
    const PolygonMesh input = read_mesh(test::shared_data_file("meshes/" + file));
    const SimplifyResult result = simplify(input, mapped(input.vertex_count() / 30));
    const MapCheck check = check_map(input, result, file);
    std::printf("%s: %zu base vertices, %zu of %zu same-triangle input triangles inverted\n", file.c_str(),
                result.base.vertex_count(), check.inverted, check.same_triangle);
    EXPECT_LE(check.inverted_share(), kMaxInvertedShare) << file;
    EXPECT_EQ(check.duplicates, 0u) << file;
  }
}

TEST(SurfaceMapTest, MapIsBijectiveOnAnExtractedIsosurface) {
  IsosurfaceOptions extract;
  extract.iso = 0;
  const Volume field = make_builtin_field("mixing", 48);
  const PolygonMesh input = extract_isosurface(field, extract).mesh;
  const SimplifyResult result = simplify(input, mapped(input.vertex_count() / 20));
  const MapCheck check = check_map(input, result, "mixing 48");
  std::printf("mixing 48: %zu input, %zu base vertices, %zu of %zu inverted\n", input.vertex_count(),
              result.base.vertex_count(), check.inverted, check.same_triangle);
  EXPECT_LE(check.inverted_share(), kMaxInvertedShare);
  EXPECT_EQ(check.duplicates, 0u);
}

}  // namespace
}  // namespace isowave::simplify
