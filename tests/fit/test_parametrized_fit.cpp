// The parametrization-based fit (parametrized_fit.h) against analytic
// answers: flat base faces whose input surface is the face itself (the fine
// points are the images of the chart's dyadic points), and a sphere mapped
// onto an octahedron.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"
#include "isowave/fit/parametrized_fit.h"

namespace isowave {
namespace {

using Point2 = std::array<double, 2>;
using Triangle = std::array<std::uint32_t, 3>;

// Barycentric weights of q in triangle (a, b, c) of the plane.
std::array<double, 3> weights_in(const Point2& a, const Point2& b, const Point2& c, const Point2& q) {
  const double det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  const double wb = ((q[0] - a[0]) * (c[1] - a[1]) - (q[1] - a[1]) * (c[0] - a[0])) / det;
  const double wc = ((b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0])) / det;
  return {1 - wb - wc, wb, wc};
}

// Vertices deduplicated by position (rounded to 1e-9).
struct VertexSet {
  std::map<std::pair<long long, long long>, std::uint32_t> index;
  std::vector<Point2> points;
  std::uint32_t add(const Point2& p) {
    const auto key = std::make_pair(std::llround(p[0] * 1e9), std::llround(p[1] * 1e9));
    const auto [it, added] = index.emplace(key, static_cast<std::uint32_t>(points.size()));
    if (added) points.push_back(p);
    return it->second;
  }
};

// A flat case: a convex polygon in the plane (corners counter-clockwise)
// split into base faces, embedded isometrically in 3D; the input surface a
// triangulation of the polygon; the map the exact barycentric coordinates of
// each input vertex in the first base triangle holding it.
struct FlatCase {
  std::vector<Point2> corners;           // base vertices in the plane
  std::vector<std::vector<std::uint32_t>> faces;
  std::vector<Triangle> base_triangles;  // with their faces:
  std::vector<std::uint32_t> triangle_face;
  std::vector<Point2> input_points;
  std::vector<Triangle> input_triangles;
  Vec3 origin{0, 0, 0}, e1{1, 0, 0}, e2{0, 1, 0};  // orthonormal e1, e2

  Vec3 embed(const Point2& p) const { return origin + p[0] * e1 + p[1] * e2; }
  PolygonMesh base() const {
    PolygonMesh mesh;
    for (const Point2& c : corners) mesh.positions.push_back(embed(c));
    for (const auto& f : faces) mesh.add_face(f.data(), f.size());
    return mesh;
  }
  PolygonMesh surface() const {
    PolygonMesh mesh;
    for (const Point2& p : input_points) mesh.positions.push_back(embed(p));
    for (const Triangle& t : input_triangles) mesh.add_face(t.data(), 3);
    return mesh;
  }
  simplify::SurfaceMap map() const {
    simplify::SurfaceMap m;
    m.triangles = base_triangles;
    m.triangle_face = triangle_face;
    for (const Point2& p : input_points) {
      bool found = false;
      for (std::uint32_t t = 0; t < base_triangles.size() && !found; ++t) {
        const Triangle& b = base_triangles[t];
        auto w = weights_in(corners[b[0]], corners[b[1]], corners[b[2]], p);
        if (std::min({w[0], w[1], w[2]}) < -1e-12) continue;
        for (double& x : w) x = std::max(0.0, x);
        const double sum = w[0] + w[1] + w[2];
        m.vertex_triangle.push_back(t);
        m.vertex_uv.push_back({w[1] / sum, w[2] / sum});
        found = true;
      }
      EXPECT_TRUE(found);
    }
    return m;
  }
  // The point of the base faces at a chart point of face f (the chart
  // triangles' piecewise-affine map onto the face).
  Vec3 chart_to_face(std::size_t f, const Point2& x) const {
    const std::size_t n = faces[f].size();
    for (std::uint32_t t = 0; t < base_triangles.size(); ++t) {
      if (triangle_face[t] != f) continue;
      std::array<Point2, 3> chart;
      for (int c = 0; c < 3; ++c) {
        std::size_t k = 0;
        while (faces[f][k] != base_triangles[t][c]) ++k;
        chart[c] = regular_corner(k, n);
      }
      const auto w = weights_in(chart[0], chart[1], chart[2], x);
      if (std::min({w[0], w[1], w[2]}) < -1e-12) continue;
      Point2 p{0, 0};
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < 2; ++i) p[i] += w[c] * corners[base_triangles[t][c]][i];
      return embed(p);
    }
    ADD_FAILURE() << "chart point outside its face";
    return {};
  }
  static Point2 regular_corner(std::size_t k, std::size_t n) {
    const double pi = std::acos(-1.0);
    const double r = 0.5 / std::sin(pi / static_cast<double>(n));
    return {r * std::cos(2 * pi * static_cast<double>(k) / static_cast<double>(n)),
            r * std::sin(2 * pi * static_cast<double>(k) / static_cast<double>(n))};
  }
};

// A fine irregular triangulation of the convex polygon `corners`: a fan from
// the interior point c, each fan triangle split into k^2, every point then
// moved by a smooth displacement that vanishes on the boundary (small enough
// not to fold a triangle).
void fine_triangulation(FlatCase& flat, const Point2& c, int k) {
  VertexSet set;
  const std::size_t n = flat.corners.size();
  for (std::size_t s = 0; s < n; ++s) {
    const Point2& a = flat.corners[s];
    const Point2& b = flat.corners[(s + 1) % n];
    std::vector<std::vector<std::uint32_t>> id(k + 1);
    for (int i = 0; i <= k; ++i)
      for (int j = 0; i + j <= k; ++j)
        id[i].push_back(set.add({c[0] + (i * (a[0] - c[0]) + j * (b[0] - c[0])) / k,
                                 c[1] + (i * (a[1] - c[1]) + j * (b[1] - c[1])) / k}));
    for (int i = 0; i < k; ++i)
      for (int j = 0; i + j < k; ++j) {
        flat.input_triangles.push_back({id[i][j], id[i + 1][j], id[i][j + 1]});
        if (i + j + 1 < k) flat.input_triangles.push_back({id[i + 1][j], id[i + 1][j + 1], id[i][j + 1]});
      }
  }
  for (Point2 p : set.points) {
    double boundary = std::numeric_limits<double>::infinity();
    for (std::size_t s = 0; s < n; ++s) {
      const Point2& a = flat.corners[s];
      const Point2& b = flat.corners[(s + 1) % n];
      const double inside = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
      boundary = std::min(boundary, inside / std::hypot(b[0] - a[0], b[1] - a[1]));
    }
    boundary = std::max(0.0, boundary);
    p = {p[0] + 0.05 * boundary * std::sin(7 * p[0] + 3 * p[1]), p[1] + 0.05 * boundary * std::cos(5 * p[0] - 4 * p[1])};
    flat.input_points.push_back(p);
  }
}

// The chart positions of every level-L vertex of a hierarchy over one base
// face (base vertex k at the regular polygon's corner k), by the dyadic rule.
std::vector<Point2> chart_points(const SubdivisionHierarchy& h) {
  const PolygonMesh& base = h.base();
  std::vector<Point2> x(base.vertex_count());
  for (std::size_t k = 0; k < base.face_size(0); ++k) x[base.face_begin(0)[k]] = FlatCase::regular_corner(k, base.face_size(0));
  auto mean = [](const Point2& a, const Point2& b) { return Point2{(a[0] + b[0]) / 2, (a[1] + b[1]) / 2}; };
  for (int level = 1; level <= h.levels(); ++level) {
    const RefinementStep& step = h.step(level);
    x.resize(step.child_vertex_count());
    for (std::size_t f = 0; f < step.parent_face_count; ++f) {
      Point2 sum{0, 0};
      const std::uint32_t n = step.face_offsets[f + 1] - step.face_offsets[f];
      for (std::uint32_t i = step.face_offsets[f]; i < step.face_offsets[f + 1]; ++i)
        for (int d = 0; d < 2; ++d) sum[d] += x[step.face_vertices[i]][d] / n;
      x[step.first_face_vertex() + f] = sum;
    }
    for (std::size_t e = 0; e < step.parent_edge_count; ++e)
      x[step.first_edge_vertex() + e] = mean(x[step.edge_vertices[2 * e]], x[step.edge_vertices[2 * e + 1]]);
  }
  return x;
}

ParametrizedFitResult fit(const FlatCase& flat, int levels) {
  const PolygonMesh base = flat.base();
  const SubdivisionHierarchy hierarchy(base, levels);
  return parametrized_fit(hierarchy, base.positions, flat.surface(), flat.map());
}

FlatCase unit_square() {
  FlatCase flat;
  flat.corners = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  flat.faces = {{0, 1, 2, 3}};
  flat.base_triangles = {{0, 1, 2}, {0, 2, 3}};
  flat.triangle_face = {0, 0};
  fine_triangulation(flat, {0.37, 0.58}, 9);
  return flat;
}

// Every coordinate of every point a multiple of 2^-level, and the points
// exactly the (cols 2^level + 1) x (rows 2^level + 1) grid of them.
void expect_dyadic_grid(const std::vector<Vec3>& points, int level, int cols, int rows) {
  const double scale = std::ldexp(1.0, level);
  std::map<std::pair<long long, long long>, int> seen;
  for (const Vec3& p : points) {
    const double x = p.x * scale, y = p.y * scale;
    EXPECT_NEAR(x, std::round(x), 1e-12 * scale);
    EXPECT_NEAR(y, std::round(y), 1e-12 * scale);
    EXPECT_EQ(p.z, 0.0);
    ++seen[{std::llround(x), std::llround(y)}];
  }
  const long long nx = cols * static_cast<long long>(scale), ny = rows * static_cast<long long>(scale);
  EXPECT_EQ(seen.size(), static_cast<std::size_t>((nx + 1) * (ny + 1)));
  for (const auto& [key, count] : seen) {
    EXPECT_EQ(count, 1);
    EXPECT_TRUE(key.first >= 0 && key.first <= nx && key.second >= 0 && key.second <= ny);
  }
}

// The regular 4-gon chart of a unit square is an isometry: at levels 0 to 3
// the fine points are the square's dyadic grid, although the input triangles
// straddle the base diagonal; every fine face has the same area.
TEST(ParametrizedFit, UnitSquareGivesTheDyadicGrid) {
  const FlatCase flat = unit_square();
  for (int level = 0; level <= 3; ++level) {
    const ParametrizedFitResult r = fit(flat, level);
    SCOPED_TRACE(level);
    expect_dyadic_grid(r.positions, level, 1, 1);
    for (std::size_t v = 0; v < 4; ++v) EXPECT_EQ(r.positions[v], flat.embed(flat.corners[v]));
    EXPECT_EQ(r.statistics.fallback_points, 0u);
    EXPECT_EQ(r.statistics.fine_vertices, r.positions.size());
  }
}

// Two unit squares sharing a base edge (split along different diagonals),
// the input a k-fold triangulation of the whole 2 x 1 rectangle.
FlatCase two_squares(int k) {
  FlatCase flat;
  flat.corners = {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {1, 1}, {0, 1}};
  flat.faces = {{0, 1, 4, 5}, {1, 2, 3, 4}};
  flat.base_triangles = {{0, 1, 4}, {0, 4, 5}, {1, 3, 4}, {1, 2, 3}};
  flat.triangle_face = {0, 0, 1, 1};
  fine_triangulation(flat, {1.13, 0.41}, k);
  return flat;
}

// Points on the shared edge are the same from either face, and the fine
// points the rectangle's dyadic grid.
TEST(ParametrizedFit, TwoSquaresAgreeAlongTheirSharedEdge) {
  const ParametrizedFitResult r = fit(two_squares(8), 3);
  expect_dyadic_grid(r.positions, 3, 2, 1);
  EXPECT_EQ(r.statistics.fallback_points, 0u);
}

// One flat face in a tilted plane: the fine points are the images of the
// chart's dyadic points under the chart-to-face map.
void expect_chart_images(const FlatCase& flat, int levels) {
  const PolygonMesh base = flat.base();
  const SubdivisionHierarchy hierarchy(base, levels);
  const ParametrizedFitResult r = parametrized_fit(hierarchy, base.positions, flat.surface(), flat.map());
  const std::vector<Point2> chart = chart_points(hierarchy);
  ASSERT_EQ(r.positions.size(), chart.size());
  for (std::size_t i = 0; i < chart.size(); ++i) {
    const Vec3 expected = flat.chart_to_face(0, chart[i]);
    EXPECT_LT(norm(r.positions[i] - expected), 1e-12) << "vertex " << i;
  }
  EXPECT_EQ(r.statistics.fallback_points, 0u);
}

FlatCase tilted(std::vector<Point2> corners, std::vector<Triangle> triangles) {
  FlatCase flat;
  flat.corners = std::move(corners);
  flat.faces = {{}};
  for (std::uint32_t k = 0; k < flat.corners.size(); ++k) flat.faces[0].push_back(k);
  flat.base_triangles = std::move(triangles);
  flat.triangle_face.assign(flat.base_triangles.size(), 0);
  flat.origin = {0.3, -1.2, 2.0};
  flat.e1 = normalized(Vec3{1, 2, 2});
  flat.e2 = normalized(cross(cross(flat.e1, Vec3{0.2, 1, 0.5}), flat.e1));
  return flat;
}

TEST(ParametrizedFit, TriangleAndPentagonGiveTheChartImages) {
  FlatCase triangle = tilted({{0, 0}, {2.0, 0.3}, {0.7, 1.6}}, {{0, 1, 2}});
  fine_triangulation(triangle, {0.8, 0.5}, 10);
  expect_chart_images(triangle, 3);

  const std::vector<Point2> pentagon = {{0, 0}, {2, 0}, {2.6, 1.3}, {1.1, 2.4}, {-0.4, 1.2}};
  const std::vector<Triangle> fan = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}};
  FlatCase fine = tilted(pentagon, fan);
  fine_triangulation(fine, {1.3, 0.9}, 10);
  expect_chart_images(fine, 3);

  // A coarse input fanned from corner 2: its triangle (2, 4, 0) has vertices
  // in base triangles 0 and 2 only and covers base triangle 1 around corner 0.
  FlatCase coarse = tilted(pentagon, fan);
  coarse.input_points = pentagon;
  coarse.input_triangles = {{2, 3, 4}, {2, 4, 0}, {2, 0, 1}};
  expect_chart_images(coarse, 3);
}

// A sphere over a convex polyhedron with its vertices on the unit sphere
// (octahedron, cube): each map triangle subdivided k times, the vertices
// projected onto the sphere and mapped by their barycentric coordinates in
// the flat triangle. With a twist, each vertex p then moves to
// normalized(p + twist (yz, zx, xy)), which keeps the polyhedron's vertices
// (there the displacement is parallel to p), and is mapped by its central
// projection onto the polyhedron: the input triangles straddle base edges.
struct SphereCase {
  PolygonMesh base, surface;
  simplify::SurfaceMap map;
};

// The first map triangle holding the central projection of p, and the
// barycentric (u, v) there.
void map_centrally(const std::vector<Vec3>& corners, const Vec3& p, simplify::SurfaceMap& map) {
  for (std::uint32_t t = 0; t < map.triangle_count(); ++t) {
    const Vec3 &a = corners[map.triangles[t][0]], &b = corners[map.triangles[t][1]], &c = corners[map.triangles[t][2]];
    const Vec3 n = cross(b - a, c - a);
    if (!(dot(n, p) > 0)) continue;
    const Vec3 q = (dot(n, a) / dot(n, p)) * p;
    const double u = dot(cross(q - a, c - a), n) / dot(n, n), w = dot(cross(b - a, q - a), n) / dot(n, n);
    if (std::min({u, w, 1 - u - w}) < -1e-12) continue;
    map.vertex_triangle.push_back(t);
    map.vertex_uv.push_back({std::max(0.0, u), std::max(0.0, w)});
    return;
  }
  ADD_FAILURE() << "no triangle";
}

SphereCase sphere_over(const PolygonMesh& polyhedron, const std::vector<Triangle>& triangles,
                       const std::vector<std::uint32_t>& triangle_face, int k, double twist) {
  SphereCase s;
  s.base = polyhedron;
  s.map.triangles = triangles;
  s.map.triangle_face = triangle_face;
  std::map<std::array<long long, 3>, std::uint32_t> index;
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    const Vec3 &a = s.base.positions[triangles[t][0]], &b = s.base.positions[triangles[t][1]],
               &c = s.base.positions[triangles[t][2]];
    std::vector<std::vector<std::uint32_t>> id(k + 1);
    for (int i = 0; i <= k; ++i)
      for (int j = 0; i + j <= k; ++j) {
        const Vec3 p = a + (static_cast<double>(i) / k) * (b - a) + (static_cast<double>(j) / k) * (c - a);
        const std::array<long long, 3> key{std::llround(p.x * 1e9), std::llround(p.y * 1e9), std::llround(p.z * 1e9)};
        const auto [it, added] = index.emplace(key, static_cast<std::uint32_t>(s.surface.positions.size()));
        if (added && twist == 0) {
          s.surface.positions.push_back(normalized(p));
          s.map.vertex_triangle.push_back(t);
          s.map.vertex_uv.push_back({static_cast<double>(i) / k, static_cast<double>(j) / k});
        } else if (added) {
          const Vec3 n = normalized(p);
          s.surface.positions.push_back(normalized(n + twist * Vec3{n.y * n.z, n.z * n.x, n.x * n.y}));
          map_centrally(s.base.positions, s.surface.positions.back(), s.map);
        }
        id[i].push_back(it->second);
      }
    for (int i = 0; i < k; ++i)
      for (int j = 0; i + j < k; ++j) {
        s.surface.add_face({id[i][j], id[i + 1][j], id[i][j + 1]});
        if (i + j + 1 < k) s.surface.add_face({id[i + 1][j], id[i + 1][j + 1], id[i][j + 1]});
      }
  }
  return s;
}

SphereCase octahedron_sphere(int k, double twist = 0) {
  PolygonMesh octahedron;
  octahedron.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const std::vector<Triangle> faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                       {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  std::vector<std::uint32_t> triangle_face;
  for (std::uint32_t f = 0; f < faces.size(); ++f) {
    octahedron.add_face(faces[f].data(), 3);
    triangle_face.push_back(f);
  }
  return sphere_over(octahedron, faces, triangle_face, k, twist);
}

// The cube with its vertices on the unit sphere; each face split into two
// map triangles, along either diagonal.
SphereCase cube_sphere(int k, double twist) {
  PolygonMesh cube;
  const double a = 1 / std::sqrt(3.0);
  for (int i = 0; i < 8; ++i) cube.positions.push_back({i & 1 ? a : -a, i & 2 ? a : -a, i & 4 ? a : -a});
  const std::vector<std::array<std::uint32_t, 4>> faces = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<Triangle> triangles;
  std::vector<std::uint32_t> triangle_face;
  for (std::uint32_t f = 0; f < faces.size(); ++f) {
    const auto& q = faces[f];
    cube.add_face(q.data(), 4);
    if (f % 2 == 0) {
      triangles.insert(triangles.end(), {Triangle{q[0], q[1], q[2]}, Triangle{q[0], q[2], q[3]}});
    } else {
      triangles.insert(triangles.end(), {Triangle{q[1], q[2], q[3]}, Triangle{q[1], q[3], q[0]}});
    }
    triangle_face.insert(triangle_face.end(), {f, f});
  }
  return sphere_over(cube, triangles, triangle_face, k, twist);
}

// Every fine point on the input triangles, the base vertices on their input
// vertices, no fine face folded (its normal points outward), no two fine
// points alike, no fallback.
void expect_on_sphere_without_folds(const SphereCase& s, int levels) {
  const SubdivisionHierarchy hierarchy(s.base, levels);
  const ParametrizedFitResult r = parametrized_fit(hierarchy, s.base.positions, s.surface, s.map);
  EXPECT_EQ(r.statistics.fallback_points, 0u);
  ASSERT_EQ(r.positions.size(), hierarchy.vertex_count(levels));
  const BinnedSurfaceDistance distance(s.surface);
  for (const Vec3& p : r.positions) EXPECT_LT(distance.distance(p), 1e-12);
  for (std::size_t v = 0; v < s.base.vertex_count(); ++v) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vec3& input : s.surface.positions) nearest = std::min(nearest, norm(r.positions[v] - input));
    EXPECT_LT(nearest, 1e-15) << "base vertex " << v;
  }
  const PolygonMesh fine = hierarchy.control_mesh(levels, r.positions);
  for (std::size_t f = 0; f < fine.face_count(); ++f) {
    const std::uint32_t* q = fine.face_begin(f);
    const Vec3 normal = cross(fine.positions[q[2]] - fine.positions[q[0]], fine.positions[q[3]] - fine.positions[q[1]]);
    const Vec3 centroid = 0.25 * (fine.positions[q[0]] + fine.positions[q[1]] + fine.positions[q[2]] + fine.positions[q[3]]);
    EXPECT_GT(dot(normal, centroid), 0) << "face " << f;
  }
  double closest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < r.positions.size(); ++i)
    for (std::size_t j = i + 1; j < r.positions.size(); ++j) closest = std::min(closest, norm(r.positions[i] - r.positions[j]));
  EXPECT_GT(closest, 1e-3);
}

TEST(ParametrizedFit, SphereOverOctahedronLiesOnTheSurfaceWithoutFolds) {
  expect_on_sphere_without_folds(octahedron_sphere(6), 3);
}

TEST(ParametrizedFit, TwistedSphereStraddlingBaseEdgesLiesOnTheSurfaceWithoutFolds) {
  expect_on_sphere_without_folds(octahedron_sphere(7, 0.4), 3);
}

// Round a cube corner the base triangles' angles sum to 3 pi / 2: the
// shorter-way unfold lays a few input triangles there the wrong way round,
// and the points they would hold fall back to the nearest one (clamped onto
// it: still on the surface). A known limit of the isometric unfold; MAPS's
// z^a flattening of the corner's fan would remove it. Its share stays small.
TEST(ParametrizedFit, TwistedSphereOverCubeLiesOnTheSurface) {
  const SphereCase s = cube_sphere(8, 0.2);
  const SubdivisionHierarchy hierarchy(s.base, 5);
  const ParametrizedFitResult r = parametrized_fit(hierarchy, s.base.positions, s.surface, s.map);
  const BinnedSurfaceDistance distance(s.surface);
  for (const Vec3& p : r.positions) EXPECT_LT(distance.distance(p), 1e-12);
  EXPECT_LE(double(r.statistics.fallback_points), 0.005 * double(r.positions.size()));
}

TEST(ParametrizedFit, SameResultForAnyThreadCount) {
  const SphereCase s = octahedron_sphere(24);
  const SubdivisionHierarchy hierarchy(s.base, 5);
  std::vector<ParametrizedFitResult> results;
  for (const int threads : {1, 2}) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    results.push_back(parametrized_fit(hierarchy, s.base.positions, s.surface, s.map));
  }
  EXPECT_TRUE(results[0].positions == results[1].positions);
  EXPECT_EQ(results[0].statistics.fallback_points, results[1].statistics.fallback_points);
}

void expect_invalid(const std::function<void()>& call) {
  try {
    call();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument) << e.what();
  }
}

// Maps that do not fit the base mesh or the surface.
TEST(ParametrizedFit, RejectsMapsThatDoNotFit) {
  const FlatCase flat = two_squares(3);
  const PolygonMesh base = flat.base(), surface = flat.surface();
  const SubdivisionHierarchy hierarchy(base, 1);
  const simplify::SurfaceMap good = flat.map();
  ASSERT_NO_THROW(parametrized_fit(hierarchy, base.positions, surface, good));
  auto expect_rejected = [&](const std::function<void(simplify::SurfaceMap&)>& spoil) {
    simplify::SurfaceMap map = good;
    spoil(map);
    expect_invalid([&] { parametrized_fit(hierarchy, base.positions, surface, map); });
  };
  expect_rejected([](simplify::SurfaceMap& m) { m.vertex_uv.pop_back(); });
  expect_rejected([](simplify::SurfaceMap& m) { m.vertex_triangle.push_back(0); });
  expect_rejected([](simplify::SurfaceMap& m) { m.triangle_face.pop_back(); });
  expect_rejected([](simplify::SurfaceMap& m) { m.triangle_face[1] = 2; });
  expect_rejected([](simplify::SurfaceMap& m) { m.triangles[0][1] = 6; });
  expect_rejected([](simplify::SurfaceMap& m) { m.vertex_triangle[3] = 4; });
  // A triangle of face 0 using vertex 2, a corner of face 1 only.
  expect_rejected([](simplify::SurfaceMap& m) { m.triangles[0] = {0, 2, 4}; });
  // Both of face 1's triangles the same: it is not triangulated.
  expect_rejected([](simplify::SurfaceMap& m) { m.triangles[2] = m.triangles[3]; });
  // A clockwise triangle.
  expect_rejected([](simplify::SurfaceMap& m) { m.triangles[0] = {0, 4, 1}; });
  // Three triangles in face 0.
  expect_rejected([](simplify::SurfaceMap& m) {
    m.triangles.push_back(m.triangles[0]);
    m.triangle_face.push_back(0);
  });
  expect_rejected([](simplify::SurfaceMap& m) { m.vertex_uv[2][0] = std::numeric_limits<double>::quiet_NaN(); });
  expect_rejected([](simplify::SurfaceMap& m) { m.vertex_uv[2] = {0.8, 0.7}; });
  expect_invalid([&] {
    parametrized_fit(hierarchy, std::vector<Vec3>(base.positions.begin(), base.positions.end() - 1), surface, good);
  });
}

}  // namespace
}  // namespace isowave
