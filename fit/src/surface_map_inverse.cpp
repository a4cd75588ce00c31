#include "surface_map_inverse.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace isowave {
namespace {

using Triangle = std::array<std::uint32_t, 3>;
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
// Barycentric tolerance of the containment test (dimensionless).
constexpr double kTolerance = 1e-9;
// Candidates beyond which a base triangle bins them in a grid.
constexpr std::size_t kGridThreshold = 16;

// The surface's faces as triangles, larger faces fanned from their first corner.
std::vector<Triangle> surface_triangles(const PolygonMesh& surface) {
  std::vector<Triangle> triangles;
  triangles.reserve(surface.face_vertices.size() - 2 * surface.face_count());
  for (std::size_t f = 0; f < surface.face_count(); ++f) {
    const std::uint32_t* v = surface.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < surface.face_size(f); ++k) triangles.push_back({v[0], v[k], v[k + 1]});
  }
  return triangles;
}

int corner_of(const Triangle& t, std::uint32_t w) {
  for (int c = 0; c < 3; ++c)
    if (t[c] == w) return c;
  return -1;
}

// The base triangles around each base vertex, counter-clockwise: rows[w]
// starts with the walked fan (length[w] triangles, closed[w] when it is a
// cycle; an open fan starts at the boundary); triangles the walk did not
// reach (only with an invalid map) follow it and are never unfolded.
struct BaseFans {
  IndexRows rows;
  std::vector<std::uint32_t> length;
  std::vector<std::uint8_t> closed;

  // Position of triangle t in w's walked fan, or kNone.
  std::uint32_t position(std::uint32_t w, std::uint32_t t) const {
    for (std::uint32_t i = 0; i < length[w]; ++i)
      if (rows.begin(w)[i] == t) return i;
    return kNone;
  }
};

// Orders the triangles around w (given in index order) into its fan.
void order_fan(const std::vector<Triangle>& triangles, std::uint32_t w, std::uint32_t* fan, std::uint32_t count,
               std::uint32_t& length, std::uint8_t& closed) {
  // The triangle across the edge from w to corner (c + step) of t: the
  // next one counter-clockwise (step 2) or clockwise (step 1).
  auto neighbour = [&](std::uint32_t t, int step) {
    const std::uint32_t target = triangles[t][(corner_of(triangles[t], w) + step) % 3];
    for (std::uint32_t i = 0; i < count; ++i) {
      const Triangle& s = triangles[fan[i]];
      if (s[(corner_of(s, w) + 3 - step) % 3] == target) return fan[i];
    }
    return kNone;
  };
  std::uint32_t start = fan[0];
  for (std::uint32_t i = 0; i < count; ++i)
    if (neighbour(fan[i], 1) == kNone) {
      start = fan[i];
      break;
    }
  std::vector<std::uint32_t> order{start};
  std::uint32_t next = neighbour(start, 2);
  while (next != kNone && next != start && order.size() < count &&
         std::find(order.begin(), order.end(), next) == order.end()) {
    order.push_back(next);
    next = neighbour(next, 2);
  }
  closed = next == start && order.size() > 1;
  length = static_cast<std::uint32_t>(order.size());
  for (std::uint32_t i = 0; i < count; ++i)
    if (std::find(order.begin(), order.end(), fan[i]) == order.end()) order.push_back(fan[i]);
  std::copy(order.begin(), order.end(), fan);
}

BaseFans build_fans(const std::vector<Triangle>& triangles, std::size_t vertex_count) {
  std::vector<std::uint32_t> keys, values;
  keys.reserve(3 * triangles.size());
  values.reserve(3 * triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t)
    for (const std::uint32_t w : triangles[t]) {
      keys.push_back(w);
      values.push_back(t);
    }
  BaseFans fans;
  fans.rows = sort_into_rows(vertex_count, keys, values);
  fans.length.assign(vertex_count, 0);
  fans.closed.assign(vertex_count, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_count, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t w = r.begin(); w < r.end(); ++w) {
      if (fans.rows.size(w) == 0) continue;
      order_fan(triangles, static_cast<std::uint32_t>(w), fans.rows.values.data() + fans.rows.offsets[w],
                static_cast<std::uint32_t>(fans.rows.size(w)), fans.length[w], fans.closed[w]);
    }
  });
  return fans;
}

// Calls visit(position) for the fan positions strictly between from and to:
// along an open fan, its one way; around a closed fan, both ways (which way
// the input triangle goes, the orientation of its image decides: see
// add_candidates).
template <typename Visit>
void between_in_fan(std::uint32_t from, std::uint32_t to, std::uint32_t length, bool closed, Visit visit) {
  if (closed) {
    for (std::uint32_t i = 0; i < length; ++i)
      if (i != from && i != to) visit(i);
  } else if (from < to) {
    for (std::uint32_t i = from + 1; i < to; ++i) visit(i);
  } else {
    for (std::uint32_t i = to + 1; i < from; ++i) visit(i);
  }
}

// The base triangles whose candidate input triangle t is: those of its
// vertices, and those around a base vertex between two of them sharing only
// that vertex. Sorted, distinct.
void candidate_triangles(const simplify::SurfaceMap& map, const BaseFans& fans, const Triangle& input,
                         std::vector<std::uint32_t>& out) {
  out.clear();
  for (const std::uint32_t i : input) out.push_back(map.vertex_triangle[i]);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  const std::size_t distinct = out.size();
  for (std::size_t a = 0; a < distinct; ++a)
    for (std::size_t b = a + 1; b < distinct; ++b) {
      const Triangle& sa = map.triangles[out[a]];
      const Triangle& sb = map.triangles[out[b]];
      int shared = 0;
      std::uint32_t w = kNone;
      for (const std::uint32_t x : sa)
        if (corner_of(sb, x) >= 0) {
          ++shared;
          w = x;
        }
      if (shared != 1) continue;
      const std::uint32_t ia = fans.position(w, out[a]), ib = fans.position(w, out[b]);
      if (ia == kNone || ib == kNone) continue;
      between_in_fan(ia, ib, fans.length[w], fans.closed[w] != 0,
                     [&](std::uint32_t i) { out.push_back(fans.rows.begin(w)[i]); });
    }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

// Per base triangle, its candidate input triangles in index order.
IndexRows candidate_rows(const simplify::SurfaceMap& map, const BaseFans& fans, const std::vector<Triangle>& inputs) {
  const std::size_t n = inputs.size();
  std::vector<std::size_t> first(n + 1, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::uint32_t> scratch;
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      candidate_triangles(map, fans, inputs[t], scratch);
      first[t + 1] = scratch.size();
    }
  });
  for (std::size_t t = 0; t < n; ++t) first[t + 1] += first[t];
  std::vector<std::uint32_t> keys(first[n]), values(first[n]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::uint32_t> scratch;
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      candidate_triangles(map, fans, inputs[t], scratch);
      std::copy(scratch.begin(), scratch.end(), keys.begin() + static_cast<std::ptrdiff_t>(first[t]));
      std::fill_n(values.begin() + static_cast<std::ptrdiff_t>(first[t]), scratch.size(), static_cast<std::uint32_t>(t));
    }
  });
  return sort_into_rows(map.triangle_count(), keys, values);
}

// The point at distance dp from p and dq from q, right of the line p -> q.
Vec2 place_right(Vec2 p, Vec2 q, double dp, double dq) {
  const Vec2 d = q - p;
  const double length = std::sqrt(d.x * d.x + d.y * d.y);
  if (length == 0) return p;
  const double along = (dp * dp - dq * dq + length * length) / (2 * length);
  const double across = std::sqrt(std::max(0.0, dp * dp - along * along));
  const Vec2 dir = (1 / length) * d;
  return p + along * dir + across * Vec2{dir.y, -dir.x};
}

// Everything the per-triangle work reads.
struct Context {
  const simplify::SurfaceMap& map;
  const std::vector<Vec3>& base_positions;
  const PolygonMesh& surface;
  const std::vector<Triangle>& inputs;
  const BaseFans& fans;
  const IndexRows& candidates;

  double edge(std::uint32_t a, std::uint32_t b) const { return norm(base_positions[a] - base_positions[b]); }
};

// Lays out triangle `next` in the plane of `current` (corners `at`), across
// the edge they share, from the base triangles' 3D edge lengths. False if
// they share no edge with opposite orientations.
bool unfold_across(const Context& c, std::uint32_t current, const Corners& at, std::uint32_t next, Corners& out) {
  const Triangle& cur = c.map.triangles[current];
  const Triangle& nxt = c.map.triangles[next];
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t p = cur[k], q = cur[(k + 1) % 3];
    const int j = corner_of(nxt, q);
    if (j < 0 || nxt[(j + 1) % 3] != p) continue;
    const std::uint32_t r = nxt[(j + 2) % 3];
    out[j] = at[(k + 1) % 3];
    out[(j + 1) % 3] = at[k];
    out[(j + 2) % 3] = place_right(at[k], at[(k + 1) % 3], c.edge(p, r), c.edge(q, r));
    return true;
  }
  return false;
}

struct Layout {
  std::uint32_t triangle;
  Corners corners;  // in the (u, v) frame of the base triangle being processed
};

struct Candidate {
  std::uint32_t input;  // input triangle
  Corners corners;      // its vertices in the (u, v) frame
  Vec2 lo, hi;          // their box
};

struct Scratch {
  std::vector<Layout> layouts;
  std::vector<Candidate> candidates;
  std::vector<std::uint32_t> cell_offsets, cell_list, cell_cursor;
  int grid = 0;  // cells per axis; 0: no grid
  Vec2 grid_lo, grid_scale;
};

const Layout* find_layout(const Scratch& s, std::uint32_t triangle) {
  for (const Layout& l : s.layouts)
    if (l.triangle == triangle) return &l;
  return nullptr;
}

// Lays out the base triangles around every corner of T (the shorter way
// round each, all of an open fan) in T's (u, v) frame; T itself first.
void build_layouts(const Context& c, std::uint32_t t, Scratch& s) {
  s.layouts.clear();
  s.layouts.push_back({t, {Vec2{0, 0}, Vec2{1, 0}, Vec2{0, 1}}});
  const Triangle& tri = c.map.triangles[t];
  Corners plane;  // T in its plane: corner 0 at the origin, corner 1 on the x axis
  plane[0] = {0, 0};
  plane[1] = {c.edge(tri[0], tri[1]), 0};
  plane[2] = place_right(plane[1], plane[0], c.edge(tri[1], tri[2]), c.edge(tri[0], tri[2]));
  const Vec2 e1 = plane[1] - plane[0], e2 = plane[2] - plane[0];
  const double det = cross(e1, e2);
  if (!(det > 0)) return;  // degenerate in 3D: only T's own candidates
  auto to_frame = [&](Vec2 x) { return Vec2{cross(x - plane[0], e2) / det, cross(e1, x - plane[0]) / det}; };
  for (const std::uint32_t w : tri) {
    const std::uint32_t at = c.fans.position(w, t), length = c.fans.length[w];
    if (at == kNone) continue;
    const bool closed = c.fans.closed[w] != 0;
    const std::uint32_t forward = closed ? length / 2 : length - 1 - at;
    const std::uint32_t backward = closed ? length - 1 - length / 2 : at;
    for (const int direction : {1, -1}) {
      std::uint32_t current = t;
      Corners corners = plane;
      const std::uint32_t steps = direction > 0 ? forward : backward;
      for (std::uint32_t step = 1; step <= steps; ++step) {
        const std::uint32_t i = direction > 0 ? (at + step) % length : (at + length - step) % length;
        const std::uint32_t next = c.fans.rows.begin(w)[i];
        Corners next_corners;
        if (!unfold_across(c, current, corners, next, next_corners)) break;
        if (!find_layout(s, next))
          s.layouts.push_back({next, {to_frame(next_corners[0]), to_frame(next_corners[1]), to_frame(next_corners[2])}});
        current = next;
        corners = next_corners;
      }
    }
  }
}

// Adds the input triangles [begin, end) whose three vertices lie in laid-out
// base triangles, in T's (u, v) frame, unless their image there is not
// positively oriented: the map preserves orientation, so such an image is
// the triangle unfolded the wrong way round a base vertex (or the map folds).
void add_candidates(const Context& c, const std::uint32_t* begin, const std::uint32_t* end, Scratch& s) {
  for (const std::uint32_t* it = begin; it != end; ++it) {
    Candidate candidate{*it, {}, {}, {}};
    bool placed = true;
    for (int k = 0; k < 3 && placed; ++k) {
      const std::uint32_t vertex = c.inputs[*it][k];
      const Layout* layout = find_layout(s, c.map.vertex_triangle[vertex]);
      placed = layout != nullptr;
      if (!placed) break;
      const auto& uv = c.map.vertex_uv[vertex];
      const Corners& l = layout->corners;
      candidate.corners[k] = l[0] + uv[0] * (l[1] - l[0]) + uv[1] * (l[2] - l[0]);
    }
    const Corners& p = candidate.corners;
    if (!placed || !(cross(p[1] - p[0], p[2] - p[0]) > 0)) continue;
    candidate.lo = {std::min({p[0].x, p[1].x, p[2].x}), std::min({p[0].y, p[1].y, p[2].y})};
    candidate.hi = {std::max({p[0].x, p[1].x, p[2].x}), std::max({p[0].y, p[1].y, p[2].y})};
    s.candidates.push_back(candidate);
  }
}

// T's candidates; if none can be laid out, those of the triangles around T.
void gather_candidates(const Context& c, std::uint32_t t, Scratch& s) {
  s.candidates.clear();
  add_candidates(c, c.candidates.begin(t), c.candidates.end(t), s);
  if (!s.candidates.empty()) return;
  for (std::size_t i = 1; i < s.layouts.size(); ++i) {
    const std::uint32_t around = s.layouts[i].triangle;
    add_candidates(c, c.candidates.begin(around), c.candidates.end(around), s);
  }
}

int grid_cell(double x, double lo, double scale, int cells) {
  return std::clamp(static_cast<int>((x - lo) * scale), 0, cells - 1);
}

// Bins the candidates' boxes (widened by a tolerance) in a uniform grid of
// about one candidate per cell over their union, when there are many.
void build_grid(Scratch& s) {
  s.grid = 0;
  if (s.candidates.size() <= kGridThreshold) return;
  const int cells = static_cast<int>(std::sqrt(static_cast<double>(s.candidates.size())));
  Vec2 lo = s.candidates[0].lo, hi = s.candidates[0].hi;
  for (const Candidate& k : s.candidates) {
    lo = {std::min(lo.x, k.lo.x), std::min(lo.y, k.lo.y)};
    hi = {std::max(hi.x, k.hi.x), std::max(hi.y, k.hi.y)};
  }
  const Vec2 extent = hi - lo;
  const double margin = 1e-9 * std::max({extent.x, extent.y, 1.0});
  s.grid = cells;
  s.grid_lo = lo;
  s.grid_scale = {extent.x > 0 ? cells / extent.x : 0, extent.y > 0 ? cells / extent.y : 0};
  s.cell_offsets.assign(static_cast<std::size_t>(cells * cells) + 1, 0);
  auto for_cells = [&](const Candidate& k, auto visit) {
    const int x0 = grid_cell(k.lo.x - margin, lo.x, s.grid_scale.x, cells);
    const int x1 = grid_cell(k.hi.x + margin, lo.x, s.grid_scale.x, cells);
    const int y0 = grid_cell(k.lo.y - margin, lo.y, s.grid_scale.y, cells);
    const int y1 = grid_cell(k.hi.y + margin, lo.y, s.grid_scale.y, cells);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) visit(static_cast<std::size_t>(y * cells + x));
  };
  for (const Candidate& k : s.candidates) for_cells(k, [&](std::size_t cell) { ++s.cell_offsets[cell + 1]; });
  for (std::size_t i = 0; i + 1 < s.cell_offsets.size(); ++i) s.cell_offsets[i + 1] += s.cell_offsets[i];
  s.cell_cursor.assign(s.cell_offsets.begin(), s.cell_offsets.end() - 1);
  s.cell_list.resize(s.cell_offsets.back());
  for (std::uint32_t i = 0; i < s.candidates.size(); ++i)
    for_cells(s.candidates[i], [&](std::size_t cell) { s.cell_list[s.cell_cursor[cell]++] = i; });
}

// The best candidate for q so far: the largest smallest barycentric coordinate.
struct Hit {
  std::uint32_t candidate = kNone;
  std::array<double, 3> weights{};
  double smallest = -std::numeric_limits<double>::infinity();
  bool inside() const { return smallest >= 0; }
};

void try_candidate(const Scratch& s, std::uint32_t i, Vec2 q, Hit& hit) {
  std::array<double, 3> w;
  if (!barycentric(s.candidates[i].corners, q, w)) return;
  const double smallest = std::min({w[0], w[1], w[2]});
  if (smallest > hit.smallest) hit = {i, w, smallest};
}

// Locates q among the candidates: in its grid cell first, then all of them.
Hit locate(const Scratch& s, Vec2 q) {
  Hit hit;
  if (s.grid > 0) {
    const std::size_t cell = static_cast<std::size_t>(grid_cell(q.y, s.grid_lo.y, s.grid_scale.y, s.grid)) * s.grid +
                             grid_cell(q.x, s.grid_lo.x, s.grid_scale.x, s.grid);
    for (std::size_t j = s.cell_offsets[cell]; j < s.cell_offsets[cell + 1] && !hit.inside(); ++j)
      try_candidate(s, s.cell_list[j], q, hit);
    if (hit.smallest >= -kTolerance) return hit;
  }
  for (std::uint32_t i = 0; i < s.candidates.size() && !hit.inside(); ++i) try_candidate(s, i, q, hit);
  return hit;
}

// The surface point of one query of T; counts a fallback.
Vec3 evaluate(const Context& c, std::uint32_t t, const Scratch& s, const MapPoint& query, std::size_t& fallbacks) {
  const Hit hit = locate(s, {query.u, query.v});
  if (hit.smallest < -kTolerance) ++fallbacks;
  if (hit.candidate == kNone) {
    const Triangle& tri = c.map.triangles[t];
    return (1 - query.u - query.v) * c.base_positions[tri[0]] + query.u * c.base_positions[tri[1]] +
           query.v * c.base_positions[tri[2]];
  }
  std::array<double, 3> w;
  double sum = 0;
  for (int k = 0; k < 3; ++k) sum += (w[k] = std::max(0.0, hit.weights[k]));
  const Triangle& input = c.inputs[s.candidates[hit.candidate].input];
  Vec3 point;
  for (int k = 0; k < 3; ++k) point += (w[k] / sum) * c.surface.positions[input[k]];
  return point;
}

}  // namespace

IndexRows sort_into_rows(std::size_t key_count, const std::vector<std::uint32_t>& keys,
                         const std::vector<std::uint32_t>& values) {
  IndexRows rows;
  rows.offsets.assign(key_count + 1, 0);
  for (const std::uint32_t k : keys) ++rows.offsets[k + 1];
  for (std::size_t k = 0; k < key_count; ++k) rows.offsets[k + 1] += rows.offsets[k];
  std::vector<std::size_t> cursor(rows.offsets.begin(), rows.offsets.end() - 1);
  rows.values.resize(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) rows.values[cursor[keys[i]]++] = values[i];
  return rows;
}

InverseMapResult inverse_map(const simplify::SurfaceMap& map, const std::vector<Vec3>& base_positions,
                             const PolygonMesh& surface, const std::vector<MapPoint>& queries) {
  const std::vector<Triangle> inputs = surface_triangles(surface);
  const BaseFans fans = build_fans(map.triangles, base_positions.size());
  const IndexRows candidates = candidate_rows(map, fans, inputs);
  std::vector<std::uint32_t> keys(queries.size()), order(queries.size());
  for (std::size_t i = 0; i < queries.size(); ++i) {
    keys[i] = queries[i].triangle;
    order[i] = static_cast<std::uint32_t>(i);
  }
  const IndexRows by_triangle = sort_into_rows(map.triangle_count(), keys, order);
  const Context c{map, base_positions, surface, inputs, fans, candidates};

  InverseMapResult result;
  result.points.resize(queries.size());
  result.fallback_points = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, map.triangle_count(), 64), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t fallbacks) {
        Scratch s;
        for (std::size_t t = r.begin(); t < r.end(); ++t) {
          if (by_triangle.size(t) == 0) continue;
          const auto triangle = static_cast<std::uint32_t>(t);
          build_layouts(c, triangle, s);
          gather_candidates(c, triangle, s);
          build_grid(s);
          for (const std::uint32_t* q = by_triangle.begin(t); q != by_triangle.end(t); ++q)
            result.points[*q] = evaluate(c, triangle, s, queries[*q], fallbacks);
        }
        return fallbacks;
      },
      std::plus<>());
  return result;
}

}  // namespace isowave
