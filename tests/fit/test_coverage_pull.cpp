// The coverage pull (fit/src/coverage_pull.h) against a brute-force
// reference: every sample against every control point and every face, with
// its own point-to-triangle distance. The pull's binned, row-by-row search
// and its hints from the previous call must pick exactly the same control
// points and move them to the same places.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <vector>

#include "coverage_pull.h"
#include "isowave/fit/shrink_wrap.h"
#include "isowave/transform/hierarchy.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

double squared_distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double length = squared_norm(ab);
  const double t = length > 0 ? std::clamp(dot(p - a, ab) / length, 0.0, 1.0) : 0.0;
  return squared_norm(p - (a + t * ab));
}

// The plane's distance when p projects inside the triangle (barycentric
// coordinates from the normal equations), else the nearest edge's.
double squared_distance_to_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 u = b - a, v = c - a, w = p - a;
  const double uu = dot(u, u), uv = dot(u, v), vv = dot(v, v), wu = dot(w, u), wv = dot(w, v);
  const double determinant = uu * vv - uv * uv;
  if (determinant > 0) {
    const double s = (vv * wu - uv * wv) / determinant, t = (uu * wv - uv * wu) / determinant;
    if (s >= 0 && t >= 0 && s + t <= 1) return squared_norm(p - (a + s * u + t * v));
  }
  return std::min({squared_distance_to_segment(p, a, b), squared_distance_to_segment(p, b, c),
                   squared_distance_to_segment(p, c, a)});
}

// Where CoveragePull::apply() should leave the positions, by brute force.
std::vector<Vec3> reference_pull(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions,
                                 const std::vector<Vec3>& samples, double covered, double reach,
                                 std::size_t& uncovered) {
  const auto near_face = [&](std::uint32_t f, const Vec3& p) {
    const std::uint32_t* face = mesh.face_vertices.data() + mesh.face_offsets[f];
    const std::uint32_t size = mesh.face_offsets[f + 1] - mesh.face_offsets[f];
    for (std::uint32_t j = 1; j + 1 < size; ++j)
      if (squared_distance_to_triangle(p, positions[face[0]], positions[face[j]], positions[face[j + 1]]) <=
          covered * covered)
        return true;
    return false;
  };
  const auto near_fan = [&](std::uint32_t u, const Vec3& p) {
    for (std::uint32_t k = mesh.vertex_face_offsets[u]; k < mesh.vertex_face_offsets[u + 1]; ++k)
      if (near_face(mesh.vertex_faces[k], p)) return true;
    return false;
  };
  std::map<std::uint32_t, std::vector<Vec3>> picked;
  uncovered = 0;
  for (const Vec3& p : samples) {
    std::uint32_t nearest = WrapLevelMesh::kNone;
    double best = reach * reach;
    bool covered_by_point = false;
    for (std::uint32_t v = 0; v < mesh.vertex_count; ++v) {
      const double d = squared_norm(positions[v] - p);
      covered_by_point = covered_by_point || d <= covered * covered;
      if (d < best) best = d, nearest = v;
    }
    if (covered_by_point || nearest == WrapLevelMesh::kNone) continue;
    bool near = near_fan(nearest, p);
    for (std::uint32_t k = mesh.neighbour_offsets[nearest]; k < mesh.neighbour_offsets[nearest + 1] && !near; ++k)
      near = near_fan(mesh.neighbours[k], p);
    if (near) continue;
    ++uncovered;
    picked[nearest].push_back(p);
  }
  std::vector<Vec3> result = positions;
  for (const auto& [v, points] : picked) {
    if (mesh.role[v] == WrapRole::Fixed) continue;
    Vec3 sum;
    for (const Vec3& q : points) sum += q;
    result[v] = (1.0 / double(points.size())) * sum;
  }
  return result;
}

// A jittered torus of 1,152 control points in a 32^3 box, and samples
// scattered up to 5 cells off it: covered ones, ones covered only by a face,
// uncovered ones within reach and ones beyond it. Two calls on one
// CoveragePull, the second after the points moved (its hints then come from
// the first).
TEST(CoveragePull, PicksTheSamePointsAsABruteForceSearch) {
  PolygonMesh base = test::quad_grid(48, 24, true, true);
  for (Vec3& p : base.positions) p = Vec3{16, 16, 16} + 3.0 * p;
  test::jitter(base, 0.2, 7);
  const SubdivisionHierarchy hierarchy(base, 1);
  Volume box;
  box.dims = {33, 33, 33};
  box.values.assign(box.sample_count(), 0.0f);
  const WrapLevelMesh mesh = make_wrap_level_mesh(hierarchy, 0, base.positions, box);

  std::mt19937 random(11);
  std::uniform_real_distribution<double> angle(0, 2 * std::acos(-1.0)), offset(-5, 5);
  std::vector<Vec3> samples;
  for (int i = 0; i < 4000; ++i) {
    const double a = angle(random), b = angle(random), r = 3.0 + offset(random) / 3.0;
    samples.push_back(Vec3{16, 16, 16} + 3.0 * Vec3{(3 + r * std::cos(b)) * std::cos(a),
                                                      (3 + r * std::cos(b)) * std::sin(a), r * std::sin(b)});
  }
  const double covered = 1.0, reach = 4.0;
  CoveragePull pull(samples, box, covered);
  std::vector<Vec3> positions = base.positions;
  for (int call = 0; call < 2; ++call) {
    SCOPED_TRACE(call);
    std::size_t uncovered = 0;
    const std::vector<Vec3> expected = reference_pull(mesh, positions, samples, covered, reach, uncovered);
    ASSERT_GT(uncovered, 200u);  // the case is not trivial
    const std::vector<Vec3> before = positions;
    const CoveragePullStatistics stats = pull.apply(mesh, positions, reach);
    EXPECT_EQ(stats.uncovered_samples, uncovered);
    std::size_t moved = 0;
    for (std::size_t v = 0; v < positions.size(); ++v) {
      EXPECT_LE(norm(positions[v] - expected[v]), 1e-9) << "vertex " << v;
      moved += positions[v] == before[v] ? 0 : 1;
    }
    EXPECT_EQ(stats.pulled_vertices, moved);
    EXPECT_GT(moved, 50u);
    // Move every point a little for the second call.
    for (std::size_t v = 0; v < positions.size(); ++v)
      positions[v] += Vec3{0.3 * std::sin(double(v)), 0.3 * std::cos(double(v)), 0.1};
  }
}

}  // namespace
}  // namespace isowave
