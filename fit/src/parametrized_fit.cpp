#include "isowave/fit/parametrized_fit.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"
#include "history_inverse.h"
#include "surface_map_inverse.h"

namespace isowave {
namespace {

using Triangle = std::array<std::uint32_t, 3>;

[[noreturn]] void fail(const std::string& message) {
  throw Error(ErrorKind::InvalidArgument, "parametrized fit: " + message);
}

// Corner k of the chart of a face with n corners: the regular n-gon with
// unit edges, counter-clockwise, corner k at angle 2 pi k / n.
Vec2 compute_chart_corner(std::uint32_t k, std::uint32_t n) {
  const double pi = std::acos(-1.0);
  const double radius = 0.5 / std::sin(pi / n);
  const double angle = 2 * pi * k / n;
  return {radius * std::cos(angle), radius * std::sin(angle)};
}

// The same, from a table for faces of up to 8 corners (hot: every location).
Vec2 chart_corner(std::uint32_t k, std::uint32_t n) {
  constexpr std::uint32_t kTabled = 8;
  using Table = std::array<std::array<Vec2, kTabled>, kTabled + 1>;
  static const Table table = [] {
    Table t{};
    for (std::uint32_t size = 3; size <= kTabled; ++size)
      for (std::uint32_t i = 0; i < size; ++i) t[size][i] = compute_chart_corner(i, size);
    return t;
  }();
  return n <= kTabled ? table[n][k] : compute_chart_corner(k, n);
}

// Position of base vertex a among face f's corners, or -1.
int corner_in_face(const PolygonMesh& base, std::size_t f, std::uint32_t a) {
  const std::uint32_t* v = base.face_begin(f);
  for (std::uint32_t k = 0; k < base.face_size(f); ++k)
    if (v[k] == a) return static_cast<int>(k);
  return -1;
}

// Checks one base face's triangles: n - 2 of them, each of three distinct
// corners of the face, positively oriented in its chart, and together a
// triangulation (every boundary edge once in the face's direction, every
// other edge once each way).
void check_face_triangles(const PolygonMesh& base, const simplify::SurfaceMap& map, std::size_t f,
                          const std::uint32_t* begin, const std::uint32_t* end) {
  const std::uint32_t n = base.face_size(f);
  const std::string face = "base face " + std::to_string(f);
  if (static_cast<std::size_t>(end - begin) != n - 2)
    fail(face + " has " + std::to_string(end - begin) + " map triangles, not " + std::to_string(n - 2));
  std::vector<std::pair<int, int>> edges;
  for (const std::uint32_t* t = begin; t != end; ++t) {
    std::array<int, 3> k;
    Corners chart;
    for (int c = 0; c < 3; ++c) {
      k[c] = corner_in_face(base, f, map.triangles[*t][c]);
      if (k[c] < 0) fail("map triangle " + std::to_string(*t) + " uses a vertex that is not a corner of its " + face);
      chart[c] = chart_corner(static_cast<std::uint32_t>(k[c]), n);
    }
    if (!(cross(chart[1] - chart[0], chart[2] - chart[0]) > 0))
      fail("map triangle " + std::to_string(*t) + " is not positively oriented in its " + face);
    for (int c = 0; c < 3; ++c) edges.emplace_back(k[c], k[(c + 1) % 3]);
  }
  auto count = [&](int i, int j) { return std::count(edges.begin(), edges.end(), std::make_pair(i, j)); };
  for (const auto& [i, j] : edges) {
    const bool boundary = static_cast<std::uint32_t>(j) == (i + 1) % n;
    if (count(i, j) != 1 || (!boundary && count(j, i) != 1))
      fail("the map triangles of " + face + " do not triangulate it");
  }
  for (std::uint32_t i = 0; i < n; ++i)
    if (count(static_cast<int>(i), static_cast<int>((i + 1) % n)) != 1)
      fail("the map triangles of " + face + " do not triangulate it");
}

// Throws Error(InvalidArgument) unless the map fits the base mesh and the
// surface (parametrized_fit.h); Error(Format) for an invalid surface.
void check_inputs(const PolygonMesh& base, const std::vector<Vec3>& base_positions, const PolygonMesh& surface,
                  const simplify::SurfaceMap& map, const IndexRows& by_face) {
  if (base_positions.size() < base.vertex_count())
    fail("base positions: " + std::to_string(base_positions.size()) + " for " +
         std::to_string(base.vertex_count()) + " base vertices");
  for (std::size_t i = 0; i < base.vertex_count(); ++i)
    if (!is_finite(base_positions[i])) fail("base position " + std::to_string(i) + " is not finite");
  validate_indices(surface, "parametrized fit surface");
  for (std::size_t f = 0; f < base.face_count(); ++f) check_face_triangles(base, map, f, by_face.begin(f), by_face.end(f));
  constexpr double kSlack = 1e-6;
  for (std::size_t i = 0; i < map.vertex_count(); ++i) {
    if (map.vertex_triangle[i] >= map.triangle_count())
      fail("input vertex " + std::to_string(i) + " maps into triangle " + std::to_string(map.vertex_triangle[i]) +
           " of " + std::to_string(map.triangle_count()));
    const double u = map.vertex_uv[i][0], v = map.vertex_uv[i][1];
    if (!(u >= -kSlack && v >= -kSlack && u + v <= 1 + kSlack))
      fail("input vertex " + std::to_string(i) + " has barycentric coordinates outside [0, 1] or not finite");
  }
}

// Sizes and index ranges, before anything is built from the map.
void check_map_sizes(const PolygonMesh& base, const PolygonMesh& surface, const simplify::SurfaceMap& map) {
  if (map.triangle_face.size() != map.triangles.size())
    fail("the map has " + std::to_string(map.triangles.size()) + " triangles but " +
         std::to_string(map.triangle_face.size()) + " triangle faces");
  if (map.vertex_triangle.size() != surface.vertex_count() || map.vertex_uv.size() != surface.vertex_count())
    fail("the map has " + std::to_string(map.vertex_triangle.size()) + " vertex triangles and " +
         std::to_string(map.vertex_uv.size()) + " coordinates for " + std::to_string(surface.vertex_count()) +
         " surface vertices");
  for (std::size_t t = 0; t < map.triangle_count(); ++t) {
    if (map.triangle_face[t] >= base.face_count())
      fail("map triangle " + std::to_string(t) + " belongs to base face " + std::to_string(map.triangle_face[t]) +
           " of " + std::to_string(base.face_count()));
    for (const std::uint32_t w : map.triangles[t])
      if (w >= base.vertex_count())
        fail("map triangle " + std::to_string(t) + " uses vertex " + std::to_string(w) + " of " +
             std::to_string(base.vertex_count()));
  }
}

// Where a vertex of the hierarchy lies in the parameter domain.
enum class LocationKind : std::uint8_t { BaseVertex, BaseEdge, Interior };
struct Location {
  LocationKind kind = LocationKind::BaseVertex;
  std::uint32_t a = 0, b = 0;  // BaseVertex a; BaseEdge (a, b), a < b; Interior: base face a
  double x = 0, y = 0;         // BaseEdge: x from a (0) to b (1); Interior: chart coordinates
};

// A location as a point of base face f's chart (f contains it).
Vec2 to_chart(const PolygonMesh& base, std::size_t f, const Location& l) {
  const std::uint32_t n = base.face_size(f);
  auto corner = [&](std::uint32_t w) {
    const int k = corner_in_face(base, f, w);
    assert(k >= 0);
    return chart_corner(static_cast<std::uint32_t>(k), n);
  };
  switch (l.kind) {
    case LocationKind::BaseVertex: return corner(l.a);
    case LocationKind::BaseEdge: return (1 - l.x) * corner(l.a) + l.x * corner(l.b);
    case LocationKind::Interior: assert(l.a == f); return {l.x, l.y};
  }
  return {};
}

// The position along base edge (a, b) of a location on it.
double along_edge(const Location& l, std::uint32_t a) {
  return l.kind == LocationKind::BaseEdge ? l.x : (l.a == a ? 0.0 : 1.0);
}

// The base edge (a < b) both locations lie on, if any, within face f.
bool common_base_edge(const PolygonMesh& base, std::size_t f, const Location& p, const Location& q,
                      std::uint32_t& a, std::uint32_t& b) {
  if (p.kind == LocationKind::Interior || q.kind == LocationKind::Interior) return false;
  if (p.kind == LocationKind::BaseEdge || q.kind == LocationKind::BaseEdge) {
    const Location& e = p.kind == LocationKind::BaseEdge ? p : q;
    const Location& o = p.kind == LocationKind::BaseEdge ? q : p;
    a = e.a;
    b = e.b;
    return o.kind == LocationKind::BaseEdge ? (o.a == a && o.b == b) : (o.a == a || o.a == b);
  }
  const int kp = corner_in_face(base, f, p.a), kq = corner_in_face(base, f, q.a);
  const int n = static_cast<int>(base.face_size(f));
  if (kp < 0 || kq < 0 || ((kp + 1) % n != kq && (kq + 1) % n != kp)) return false;
  a = std::min(p.a, q.a);
  b = std::max(p.a, q.a);
  return true;
}

// The location of the e vertex of an edge of face f from its ends'.
Location edge_location(const PolygonMesh& base, std::size_t f, const Location& p, const Location& q) {
  std::uint32_t a = 0, b = 0;
  if (common_base_edge(base, f, p, q, a, b))
    return {LocationKind::BaseEdge, a, b, 0.5 * (along_edge(p, a) + along_edge(q, a)), 0};
  const Vec2 m = 0.5 * (to_chart(base, f, p) + to_chart(base, f, q));
  return {LocationKind::Interior, static_cast<std::uint32_t>(f), 0, m.x, m.y};
}

// The base face a face of level `level` descends from.
struct BaseFaceOf {
  std::vector<std::uint32_t> face_of_corner;  // level-1 faces are numbered by base corner
  std::size_t operator()(std::size_t face, int level) const {
    return level == 0 ? face : face_of_corner[face >> (2 * (level - 1))];
  }
};

// The locations of level L's vertices: base vertices, then each refinement's
// f and e vertices at the means of their parents' (v vertices keep theirs).
std::vector<Location> fine_locations(const SubdivisionHierarchy& hierarchy, const BaseFaceOf& base_face_of) {
  const PolygonMesh& base = hierarchy.base();
  std::vector<Location> locations(base.vertex_count());
  for (std::uint32_t v = 0; v < base.vertex_count(); ++v) locations[v] = {LocationKind::BaseVertex, v, 0, 0, 0};
  for (int level = 1; level <= hierarchy.levels(); ++level) {
    const RefinementStep& step = hierarchy.step(level);
    locations.resize(step.child_vertex_count());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, step.parent_face_count, 1024), [&](const auto& r) {
      for (std::size_t p = r.begin(); p < r.end(); ++p) {
        const std::size_t f = base_face_of(p, level - 1);
        Vec2 sum;
        for (std::uint32_t i = step.face_offsets[p]; i < step.face_offsets[p + 1]; ++i)
          sum = sum + to_chart(base, f, locations[step.face_vertices[i]]);
        const Vec2 mean = (1.0 / (step.face_offsets[p + 1] - step.face_offsets[p])) * sum;
        locations[step.first_face_vertex() + p] = {LocationKind::Interior, static_cast<std::uint32_t>(f), 0, mean.x, mean.y};
      }
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, step.parent_edge_count, 1024), [&](const auto& r) {
      for (std::size_t e = r.begin(); e < r.end(); ++e) {
        const std::size_t face = step.edge_faces[2 * e] - step.first_face_vertex();
        locations[step.first_edge_vertex() + e] =
            edge_location(base, base_face_of(face, level - 1), locations[step.edge_vertices[2 * e]],
                          locations[step.edge_vertices[2 * e + 1]]);
      }
    });
  }
  return locations;
}

// A triangle point from the weights of its corners.
MapPoint weighted(std::uint32_t t, const std::array<double, 3>& w) { return {t, w[1], w[2]}; }

// Location -> (base triangle, u, v): base vertices and edges in the
// lowest-index map triangle holding them (an edge: one whose face has it as
// an edge), interior points in the chart triangle holding them.
MapPoint to_map_point(const PolygonMesh& base, const simplify::SurfaceMap& map, const IndexRows& by_face,
                      const IndexRows& by_vertex, const std::vector<Corners>& charts, const Location& l) {
  if (l.kind == LocationKind::Interior) {
    MapPoint best;
    double best_smallest = -std::numeric_limits<double>::infinity();
    for (const std::uint32_t* t = by_face.begin(l.a); t != by_face.end(l.a); ++t) {
      std::array<double, 3> w{};
      barycentric(charts[*t], {l.x, l.y}, w);
      const double smallest = std::min({w[0], w[1], w[2]});
      if (smallest > best_smallest) {
        best_smallest = smallest;
        double sum = 0;
        for (double& x : w) sum += (x = std::max(0.0, x));
        for (double& x : w) x /= sum;
        best = weighted(*t, w);
      }
    }
    return best;
  }
  for (const std::uint32_t* t = by_vertex.begin(l.a); t != by_vertex.end(l.a); ++t) {
    const Triangle& tri = map.triangles[*t];
    std::array<double, 3> w{};
    const int ca = tri[0] == l.a ? 0 : tri[1] == l.a ? 1 : 2;
    if (l.kind == LocationKind::BaseVertex) {
      w[ca] = 1;
      return weighted(*t, w);
    }
    const int cb = tri[0] == l.b ? 0 : tri[1] == l.b ? 1 : tri[2] == l.b ? 2 : -1;
    const std::size_t f = map.triangle_face[*t];
    const int ka = corner_in_face(base, f, l.a), kb = corner_in_face(base, f, l.b);
    const int n = static_cast<int>(base.face_size(f));
    if (cb < 0 || ((ka + 1) % n != kb && (kb + 1) % n != ka)) continue;
    w[ca] = 1 - l.x;
    w[cb] = l.x;
    return weighted(*t, w);
  }
  assert(false && "validated maps hold every base vertex and edge");
  return {};
}

// The map's triangles by base face (rows in triangle order).
IndexRows triangles_by_face(const simplify::SurfaceMap& map, std::size_t face_count) {
  std::vector<std::uint32_t> ids(map.triangle_count());
  for (std::uint32_t t = 0; t < map.triangle_count(); ++t) ids[t] = t;
  return sort_into_rows(face_count, map.triangle_face, ids);
}

// The level-L vertices' points of the parameter domain, in the hierarchy's
// order (fine_locations, to_map_point).
std::vector<MapPoint> parameter_points(const SubdivisionHierarchy& hierarchy, const simplify::SurfaceMap& map,
                                       const IndexRows& by_face) {
  const PolygonMesh& base = hierarchy.base();
  std::vector<std::uint32_t> corners, corner_triangles;
  std::vector<Corners> charts(map.triangle_count());  // each map triangle in its face's chart
  for (std::uint32_t t = 0; t < map.triangle_count(); ++t) {
    const std::uint32_t f = map.triangle_face[t];
    for (int c = 0; c < 3; ++c)
      charts[t][c] = chart_corner(static_cast<std::uint32_t>(corner_in_face(base, f, map.triangles[t][c])),
                                  base.face_size(f));
    corners.insert(corners.end(), map.triangles[t].begin(), map.triangles[t].end());
    corner_triangles.insert(corner_triangles.end(), 3, t);
  }
  const IndexRows by_vertex = sort_into_rows(base.vertex_count(), corners, corner_triangles);
  BaseFaceOf base_face_of;
  for (std::uint32_t f = 0; f < base.face_count(); ++f)
    base_face_of.face_of_corner.insert(base_face_of.face_of_corner.end(), base.face_size(f), f);

  const std::vector<Location> locations = fine_locations(hierarchy, base_face_of);
  std::vector<MapPoint> points(locations.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, locations.size(), 4096), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i)
      points[i] = to_map_point(base, map, by_face, by_vertex, charts, locations[i]);
  });
  return points;
}

}  // namespace

ParametrizedFitResult parametrized_fit(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                                       const PolygonMesh& surface, const simplify::SurfaceMap& map,
                                       ProgressSink& progress) {
  const auto start = std::chrono::steady_clock::now();
  progress.begin_stage("parametrized fit");
  check_map_sizes(hierarchy.base(), surface, map);
  const IndexRows by_face = triangles_by_face(map, hierarchy.base().face_count());
  check_inputs(hierarchy.base(), base_positions, surface, map, by_face);
  if (!map.history.empty()) check_history(map.history, map.triangle_count(), surface.vertex_count());
  const std::vector<MapPoint> queries = parameter_points(hierarchy, map, by_face);
  progress.update(0.3);

  InverseMapResult points = map.history.empty() ? inverse_map(map, base_positions, surface, queries)
                                                 : inverse_map_by_history(map.history, surface.positions, queries);
  ParametrizedFitResult result;
  result.positions = std::move(points.points);
  result.statistics.fine_vertices = result.positions.size();
  result.statistics.fallback_points = points.fallback_points;
  result.statistics.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.update(1.0);
  progress.end_stage();
  return result;
}

}  // namespace isowave
