#include "isowave/fit/map_smoothing.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "surface_map_inverse.h"  // Vec2, Corners, barycentric

namespace isowave {
namespace {

using Triangle = std::array<std::uint32_t, 3>;
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
// Base triangles a walk crosses at most (round a base vertex, or along a move).
constexpr int kMaxWalk = 64;
// The steps a move tries, as shares of the way to the neighbours' mean.
constexpr std::array<double, 3> kSteps = {1.0, 0.5, 0.25};
constexpr double kPi = 3.141592653589793;

int corner_of(const Triangle& t, std::uint32_t w) {
  for (int c = 0; c < 3; ++c)
    if (t[c] == w) return c;
  return -1;
}

// The base mesh's triangles (the map's) with their edge neighbours and 3D
// corner angles: what unfolding them into one plane needs.
struct BaseDomain {
  const simplify::SurfaceMap& map;
  const std::vector<Vec3>& positions;
  std::vector<std::array<std::uint32_t, 3>> across;  // the triangle across edge k (corners k, k + 1), or kNone
  std::vector<std::array<double, 3>> angles;         // radians
  std::vector<Corners> planes;                       // each in its own plane (plane_of)
  double mean_edge = 0;

  const Triangle& triangle(std::uint32_t t) const { return map.triangles[t]; }
  const Vec3& corner(std::uint32_t t, int k) const { return positions[map.triangles[t][k]]; }
};

// Pairs each directed base edge with its opposite; an edge of more than two
// triangles or of equal orientations stays unpaired (a boundary to walks).
void pair_edges(BaseDomain& d) {
  struct Half {
    std::uint32_t lo, hi, triangle;
    int edge;
  };
  std::vector<Half> halves;
  halves.reserve(3 * d.map.triangle_count());
  for (std::uint32_t t = 0; t < d.map.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = d.triangle(t)[k], b = d.triangle(t)[(k + 1) % 3];
      halves.push_back({std::min(a, b), std::max(a, b), t, k});
    }
  std::sort(halves.begin(), halves.end(), [](const Half& x, const Half& y) {
    return std::tie(x.lo, x.hi, x.triangle, x.edge) < std::tie(y.lo, y.hi, y.triangle, y.edge);
  });
  d.across.assign(d.map.triangle_count(), {kNone, kNone, kNone});
  for (std::size_t i = 0; i < halves.size();) {
    std::size_t j = i;
    while (j < halves.size() && halves[j].lo == halves[i].lo && halves[j].hi == halves[i].hi) ++j;
    const Half& x = halves[i];
    const Half& y = halves[i + 1 < j ? i + 1 : i];
    if (j - i == 2 && d.triangle(x.triangle)[x.edge] != d.triangle(y.triangle)[y.edge]) {
      d.across[x.triangle][x.edge] = y.triangle;
      d.across[y.triangle][y.edge] = x.triangle;
    }
    i = j;
  }
}

// The image of 3D point r in the plane, left of a2 -> b2, where a2 and b2
// are the images of a and b: r's distance along and across a -> b kept.
Vec2 apex(Vec2 a2, Vec2 b2, const Vec3& a, const Vec3& b, const Vec3& r) {
  const Vec3 e = b - a;
  const double length = norm(e);
  if (length == 0) return a2;
  const double along = dot(r - a, e) / length, off = norm(cross(r - a, e)) / length;
  const Vec2 d = b2 - a2;
  const double d_length = std::sqrt(d.x * d.x + d.y * d.y);
  if (d_length == 0) return a2;
  const Vec2 dir = (1 / d_length) * d;
  return a2 + along * dir + off * Vec2{-dir.y, dir.x};
}


double corner_angle(const Vec3& at, const Vec3& a, const Vec3& b) {
  const Vec3 u = a - at, v = b - at;
  return std::atan2(norm(cross(u, v)), dot(u, v));
}

// Base triangle t isometrically in its own plane, counter-clockwise.
Corners plane_of(const BaseDomain& d, std::uint32_t t) {
  const Vec2 p0{0, 0}, p1{norm(d.corner(t, 1) - d.corner(t, 0)), 0};
  return {p0, p1, apex(p0, p1, d.corner(t, 0), d.corner(t, 1), d.corner(t, 2))};
}

BaseDomain make_domain(const simplify::SurfaceMap& map, const std::vector<Vec3>& positions) {
  BaseDomain d{map, positions, {}, {}, {}, 0};
  pair_edges(d);
  d.angles.resize(map.triangle_count());
  double length = 0;
  for (std::uint32_t t = 0; t < map.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      d.angles[t][k] = corner_angle(d.corner(t, k), d.corner(t, (k + 1) % 3), d.corner(t, (k + 2) % 3));
      length += norm(d.corner(t, (k + 1) % 3) - d.corner(t, k));
    }
  d.planes.resize(map.triangle_count());
  for (std::uint32_t t = 0; t < map.triangle_count(); ++t) d.planes[t] = plane_of(d, t);
  d.mean_edge = map.triangle_count() ? length / (3.0 * double(map.triangle_count())) : 0;
  return d;
}

// The triangle across edge k of `current` (corners `at`) and its corners in
// the same plane; false at the base mesh's boundary.
bool step_across(const BaseDomain& d, std::uint32_t current, const Corners& at, int k, std::uint32_t& next,
                 Corners& out) {
  next = d.across[current][k];
  if (next == kNone) return false;
  const Triangle& cur = d.triangle(current);
  const int j = corner_of(d.triangle(next), cur[(k + 1) % 3]);
  out[j] = at[(k + 1) % 3];
  out[(j + 1) % 3] = at[k];
  out[(j + 2) % 3] = apex(at[(k + 1) % 3], at[k], d.positions[cur[(k + 1) % 3]], d.positions[cur[k]],
                          d.corner(next, (j + 2) % 3));
  return true;
}

Vec2 point_in(const Corners& c, const std::array<double, 2>& uv) {
  return c[0] + uv[0] * (c[1] - c[0]) + uv[1] * (c[2] - c[0]);
}

double distance(Vec2 a, Vec2 b) { return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y)); }

// Base triangle s laid out in the plane of base triangle t (corners
// `plane`), by breadth-first search over the edge neighbours up to
// kMaxReach crossings (the fewest crossings, then the lowest edge index):
// for points the walks round t's corners do not reach.
bool reach(const BaseDomain& d, std::uint32_t t, const Corners& plane, std::uint32_t s, Corners& out) {
  struct Reached {
    std::uint32_t triangle;
    Corners corners;
  };
  constexpr int kMaxReach = 4;
  std::array<Reached, 1 + 3 + 6 + 12 + 24> queue;  // each ring at most twice the previous one
  std::size_t size = 0, ring_begin = 0;
  queue[size++] = {t, plane};
  for (int depth = 0; depth < kMaxReach; ++depth) {
    const std::size_t ring_end = size;
    for (std::size_t q = ring_begin; q < ring_end; ++q)
      for (int k = 0; k < 3 && size < queue.size(); ++k) {
        Reached next;
        if (!step_across(d, queue[q].triangle, queue[q].corners, k, next.triangle, next.corners)) continue;
        if (std::any_of(queue.begin(), queue.begin() + size, [&](const Reached& r) { return r.triangle == next.triangle; }))
          continue;
        if (next.triangle == s) {
          out = next.corners;
          return true;
        }
        queue[size++] = next;
      }
    ring_begin = ring_end;
  }
  return false;
}

// The ways base triangle s is laid out in the plane of base triangle t
// (corners `plane`): t itself, across an edge, round each shared base vertex
// either way (within pi of angle: no straight segment goes farther round
// it), or else by the fewest edge crossings (reach). Returns how many (0:
// none reaches s).
struct Ways {
  std::uint32_t triangle = kNone;
  int count = 0;
  std::array<Corners, 4> corners;
};

void find_ways(const BaseDomain& d, std::uint32_t t, const Corners& plane, std::uint32_t s, Ways& ways) {
  ways.triangle = s;
  ways.count = 0;
  if (s == t) {
    ways.corners[ways.count++] = plane;
    return;
  }
  for (int k = 0; k < 3; ++k) {
    std::uint32_t next = kNone;
    if (d.across[t][k] == s && step_across(d, t, plane, k, next, ways.corners[0])) {
      ways.count = 1;
      return;
    }
  }
  for (const std::uint32_t w : d.triangle(t)) {
    if (corner_of(d.triangle(s), w) < 0) continue;
    for (const int direction : {1, -1}) {
      std::uint32_t current = t;
      Corners corners = plane;
      double turned = 0;
      for (int step = 0; step < kMaxWalk && turned < kPi && ways.count < 4; ++step) {
        const int c = corner_of(d.triangle(current), w);
        std::uint32_t next = kNone;
        Corners next_corners;
        if (!step_across(d, current, corners, direction > 0 ? c : (c + 2) % 3, next, next_corners)) break;
        current = next;
        corners = next_corners;
        if (current == s) {
          ways.corners[ways.count++] = corners;
          break;
        }
        turned += d.angles[current][corner_of(d.triangle(current), w)];
      }
    }
  }
  if (ways.count == 0 && reach(d, t, plane, s, ways.corners[0])) ways.count = 1;
}

// The point uv of ways.triangle laid out the way nearest to `near`.
bool place(const Ways& ways, const std::array<double, 2>& uv, Vec2 near, Vec2& out) {
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < ways.count; ++k) {
    const Vec2 p = point_in(ways.corners[k], uv);
    if (distance(p, near) < best) best = distance(p, near), out = p;
  }
  return ways.count > 0;
}

// Where a move ends: its base triangle, its point in the moving vertex's
// plane and its barycentric coordinates in that triangle.
struct Landing {
  std::uint32_t triangle = kNone;
  Vec2 point;
  std::array<double, 3> weights{};
};

std::array<double, 3> clamped(std::array<double, 3> w) {
  double sum = 0;
  for (double& x : w) sum += (x = std::max(0.0, x));
  for (double& x : w) x = sum > 0 ? x / sum : 1.0 / 3;
  return w;
}

// Walks the segment from `from` (in t) to `to` across base edges; stops on
// the base mesh's boundary where it leaves it. False if the walk is too long.
bool walk(const BaseDomain& d, std::uint32_t t, const Corners& plane, Vec2 from, Vec2 to, Landing& out) {
  std::uint32_t current = t;
  Corners corners = plane;
  for (int step = 0; step < kMaxWalk; ++step) {
    std::array<double, 3> b0{}, b1{};
    if (!barycentric(corners, from, b0) || !barycentric(corners, to, b1)) return false;
    if (std::min({b1[0], b1[1], b1[2]}) >= 0) {
      out = {current, to, b1};
      return true;
    }
    int exit = -1;  // the corner opposite the edge the segment leaves by
    double first = std::numeric_limits<double>::infinity();
    for (int m = 0; m < 3; ++m) {
      if (b1[m] >= 0) continue;
      const double s = std::max(0.0, b0[m]) / (std::max(0.0, b0[m]) - b1[m]);
      if (s < first) first = s, exit = m;
    }
    const Vec2 crossing = from + first * (to - from);
    std::uint32_t next = kNone;
    Corners next_corners;
    if (!step_across(d, current, corners, (exit + 1) % 3, next, next_corners)) {
      std::array<double, 3> w{};
      barycentric(corners, crossing, w);
      out = {current, crossing, clamped(w)};
      return true;
    }
    current = next;
    corners = next_corners;
    from = crossing;
  }
  return false;
}

// The input surface: triangles, each vertex's triangles and its neighbours
// with their mean-value weights (compressed rows), and which vertices move.
struct InputMesh {
  std::vector<Triangle> triangles;
  std::vector<std::size_t> star_offsets;  // vertex i's triangles: star[star_offsets[i] .. star_offsets[i + 1])
  std::vector<std::uint32_t> star;
  // Per star entry: the neighbour slots of the triangle's next and previous
  // corners after i (so that (i, next, previous) keeps its orientation).
  std::vector<std::array<std::uint8_t, 2>> star_slots;
  // Vertex i's neighbours: neighbours[2 star_offsets[i] ..) , neighbour_count[i] of them.
  std::vector<std::uint32_t> neighbours, neighbour_count;
  std::vector<double> weights;
  std::vector<std::uint8_t> free;
};

std::vector<Triangle> fan_triangles(const PolygonMesh& surface) {
  std::vector<Triangle> triangles;
  for (std::size_t f = 0; f < surface.face_count(); ++f) {
    const std::uint32_t* v = surface.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < surface.face_size(f); ++k) triangles.push_back({v[0], v[k], v[k + 1]});
  }
  return triangles;
}

// Whether i's triangles form one closed fan (i is inside the surface).
bool closed_fan(const InputMesh& m, std::uint32_t i) {
  const std::uint32_t* begin = m.star.data() + m.star_offsets[i];
  const std::size_t count = m.star_offsets[i + 1] - m.star_offsets[i];
  std::uint32_t t = begin[0];
  for (std::size_t step = 1; step <= count; ++step) {
    const Triangle& tri = m.triangles[t];
    const std::uint32_t next_vertex = tri[(corner_of(tri, i) + 1) % 3];  // continue across edge (i, next_vertex)
    std::uint32_t found = kNone;
    int matches = 0;
    for (std::size_t k = 0; k < count; ++k) {
      const Triangle& other = m.triangles[begin[k]];
      if (other[(corner_of(other, i) + 2) % 3] == next_vertex) found = begin[k], ++matches;
    }
    if (matches != 1) return false;
    t = found;
    if (t == begin[0]) return step == count;
  }
  return false;
}

// Vertex i's neighbours and weights: Floater's mean-value weights,
// tan(angle / 2) / length summed over the two angles at i beside each edge.
void weigh_neighbours(const PolygonMesh& surface, InputMesh& m, std::uint32_t i) {
  std::uint32_t* ids = m.neighbours.data() + 2 * m.star_offsets[i];
  double* weights = m.weights.data() + 2 * m.star_offsets[i];
  std::uint32_t count = 0;
  auto add = [&](std::uint32_t j, double w) {
    std::uint32_t k = 0;
    while (k < count && ids[k] != j) ++k;
    if (k == count) ids[count] = j, weights[count++] = 0;
    weights[k] += w;
    return static_cast<std::uint8_t>(std::min<std::uint32_t>(k, 255));
  };
  for (std::size_t s = m.star_offsets[i]; s < m.star_offsets[i + 1]; ++s) {
    const Triangle& tri = m.triangles[m.star[s]];
    const int c = corner_of(tri, i);
    const std::uint32_t j = tri[(c + 1) % 3], k = tri[(c + 2) % 3];
    const Vec3 a = surface.positions[j] - surface.positions[i], b = surface.positions[k] - surface.positions[i];
    const double la = norm(a), lb = norm(b), denominator = la * lb + dot(a, b);
    const double half_tan = denominator > 0 ? norm(cross(a, b)) / denominator : 0;
    m.star_slots[s] = {add(j, la > 0 ? half_tan / la : 0), add(k, lb > 0 ? half_tan / lb : 0)};
  }
  m.neighbour_count[i] = count;
}

InputMesh make_input(const PolygonMesh& surface, const simplify::SurfaceMap& map) {
  InputMesh m;
  m.triangles = fan_triangles(surface);
  const std::size_t n = surface.vertex_count();
  m.star_offsets.assign(n + 1, 0);
  for (const Triangle& t : m.triangles)
    for (const std::uint32_t v : t) ++m.star_offsets[v + 1];
  std::partial_sum(m.star_offsets.begin(), m.star_offsets.end(), m.star_offsets.begin());
  std::vector<std::size_t> cursor(m.star_offsets.begin(), m.star_offsets.end() - 1);
  m.star.resize(m.star_offsets.back());
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (const std::uint32_t v : m.triangles[t]) m.star[cursor[v]++] = t;
  m.star_slots.resize(m.star.size());
  m.neighbours.resize(2 * m.star.size());
  m.weights.resize(2 * m.star.size());
  m.neighbour_count.assign(n, 0);
  m.free.assign(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v) {
      const auto i = static_cast<std::uint32_t>(v);
      if (m.star_offsets[i] == m.star_offsets[i + 1]) continue;
      weigh_neighbours(surface, m, i);
      const auto& uv = map.vertex_uv[i];
      const bool at_base_vertex = uv[0] == 1 || uv[1] == 1 || (uv[0] == 0 && uv[1] == 0);
      double total = 0;
      for (std::uint32_t k = 0; k < m.neighbour_count[i]; ++k) total += m.weights[2 * m.star_offsets[i] + k];
      const bool few_neighbours = m.neighbour_count[i] < 256;  // star_slots are bytes
      m.free[i] = !at_base_vertex && few_neighbours && total > 0 && closed_fan(m, i);
    }
  });
  return m;
}

// The free vertices by colour class (a greedy colouring of the edge graph in
// index order: no two neighbours in one class), each class in index order.
std::vector<std::vector<std::uint32_t>> colour_classes(const InputMesh& m) {
  const std::size_t n = m.free.size();
  std::vector<std::uint32_t> colour(n, kNone);
  std::vector<std::vector<std::uint32_t>> classes;
  std::vector<std::uint8_t> used;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (!m.free[i]) continue;
    used.assign(classes.size() + 1, 0);
    for (std::uint32_t k = 0; k < m.neighbour_count[i]; ++k) {
      const std::uint32_t c = colour[m.neighbours[2 * m.star_offsets[i] + k]];
      if (c != kNone) used[c] = 1;
    }
    const auto c = static_cast<std::uint32_t>(std::find(used.begin(), used.end(), 0) - used.begin());
    if (c == classes.size()) classes.emplace_back();
    classes[c].push_back(i);
    colour[i] = c;
  }
  return classes;
}

struct Context {
  const BaseDomain& domain;
  const InputMesh& mesh;
  simplify::SurfaceMap& map;
};

// Vertex i's neighbourhood in the plane of its base triangle.
struct Star {
  Corners plane;
  Vec2 point;                // i itself
  std::vector<Vec2> points;  // its neighbours, in row order
  std::vector<Ways> ways;    // of the base triangles they lie in
};

bool gather_star(const Context& c, std::uint32_t i, Star& s) {
  const std::uint32_t t = c.map.vertex_triangle[i];
  s.plane = c.domain.planes[t];
  s.point = point_in(s.plane, c.map.vertex_uv[i]);
  const std::uint32_t* ids = c.mesh.neighbours.data() + 2 * c.mesh.star_offsets[i];
  s.points.resize(c.mesh.neighbour_count[i]);
  s.ways.clear();
  for (std::uint32_t k = 0; k < c.mesh.neighbour_count[i]; ++k) {
    const std::uint32_t base = c.map.vertex_triangle[ids[k]];
    auto known = std::find_if(s.ways.begin(), s.ways.end(), [&](const Ways& w) { return w.triangle == base; });
    if (known == s.ways.end()) {
      s.ways.emplace_back();
      find_ways(c.domain, t, s.plane, base, s.ways.back());
      known = s.ways.end() - 1;
    }
    if (!place(*known, c.map.vertex_uv[ids[k]], s.point, s.points[k])) return false;
  }
  return true;
}

// Bit k set: the k-th triangle round i is not positively oriented with i at `at`.
std::uint64_t inverted_around(const Context& c, std::uint32_t i, const Star& s, Vec2 at) {
  std::uint64_t bits = 0;
  const std::size_t first = c.mesh.star_offsets[i], count = std::min<std::size_t>(c.mesh.star_offsets[i + 1] - first, 64);
  for (std::size_t k = 0; k < count; ++k) {
    const auto [next, previous] = c.mesh.star_slots[first + k];
    if (!(cross(s.points[next] - at, s.points[previous] - at) > 0)) bits |= std::uint64_t{1} << k;
  }
  return bits;
}

int ones(std::uint64_t bits) {
  int n = 0;
  for (; bits; bits &= bits - 1) ++n;
  return n;
}

// Whether `after` (bits of inverted_around) is acceptable against `before`:
// no triangle newly turned over, or fewer turned over.
bool acceptable(std::uint64_t before, std::uint64_t after) {
  return (after & ~before) == 0 || ones(after) < ones(before);
}

// Whether every neighbour of i lies in base triangle t or in one across its
// edges: the unfoldings of those agree in every plane (not round a vertex).
bool edge_local(const Context& c, std::uint32_t i, std::uint32_t t) {
  const std::uint32_t* ids = c.mesh.neighbours.data() + 2 * c.mesh.star_offsets[i];
  const auto& across = c.domain.across[t];
  for (std::uint32_t k = 0; k < c.mesh.neighbour_count[i]; ++k) {
    const std::uint32_t b = c.map.vertex_triangle[ids[k]];
    if (b != t && b != across[0] && b != across[1] && b != across[2]) return false;
  }
  return true;
}

// Moves vertex i toward its neighbours' weighted mean (untangled vertices
// only where edge_local): the first step that
// is acceptable in the plane of its base triangle and, where it lands in
// another base triangle, in that one's plane too (round a base vertex the
// two planes disagree). Returns the distance moved in its plane.
double move_vertex(const Context& c, std::uint32_t i, Star& s, Star& landed, std::uint8_t& tangled) {
  if (!gather_star(c, i, s)) return 0;
  const double* weights = c.mesh.weights.data() + 2 * c.mesh.star_offsets[i];
  Vec2 mean;
  double total = 0;
  for (std::size_t k = 0; k < s.points.size(); ++k) {
    mean = mean + weights[k] * s.points[k];
    total += weights[k];
  }
  mean = (1 / total) * mean;
  const std::uint64_t before = inverted_around(c, i, s, s.point);
  tangled = before != 0;
  const std::uint32_t from = c.map.vertex_triangle[i];
  const std::array<double, 2> from_uv = c.map.vertex_uv[i];
  if (!tangled && !edge_local(c, i, from)) return 0;
  for (const double step : kSteps) {
    Landing landing;
    if (!walk(c.domain, from, s.plane, s.point, s.point + step * (mean - s.point), landing)) continue;
    std::uint64_t after = inverted_around(c, i, s, landing.point);
    if (!acceptable(before, after)) continue;
    c.map.vertex_triangle[i] = landing.triangle;
    c.map.vertex_uv[i] = {landing.weights[1], landing.weights[2]};
    if (landing.triangle != from) {
      after = gather_star(c, i, landed) ? inverted_around(c, i, landed, landed.point) : ~std::uint64_t{0};
      if (!acceptable(before, after)) {
        c.map.vertex_triangle[i] = from;
        c.map.vertex_uv[i] = from_uv;
        continue;
      }
    }
    tangled = after != 0;
    return distance(landing.point, s.point);
  }
  return 0;
}

// Per input triangle, 1 if its image is not positively oriented in the
// plane of its first corner's base triangle (or cannot be unfolded there).
std::vector<std::uint8_t> find_inverted(const Context& c) {
  std::vector<std::uint8_t> inverted(c.mesh.triangles.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, inverted.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      const Triangle& tri = c.mesh.triangles[t];
      const std::uint32_t base = c.map.vertex_triangle[tri[0]];
      const Corners& plane = c.domain.planes[base];
      std::array<Vec2, 3> p;
      p[0] = point_in(plane, c.map.vertex_uv[tri[0]]);
      bool placed = true;
      Ways ways;
      for (int k = 1; k < 3 && placed; ++k) {
        find_ways(c.domain, base, plane, c.map.vertex_triangle[tri[k]], ways);
        placed = place(ways, c.map.vertex_uv[tri[k]], p[0], p[k]);
      }
      inverted[t] = !placed || !(cross(p[1] - p[0], p[2] - p[0]) > 0);
    }
  });
  return inverted;
}

// What a round reads and writes per input vertex.
struct RoundState {
  std::vector<double> moves;          // distance moved this round (plane units)
  std::vector<std::uint8_t> tangled;  // an inverted triangle round it when it last moved (or at the start)
  std::vector<std::uint8_t> active;   // it or a neighbour moved in the last round
};

// Moves the vertices of `classes` whose flag in `selected` is set, class by
// class; adds each one's distance moved to moves[i].
void sweep(const Context& c, const std::vector<std::vector<std::uint32_t>>& classes,
           const std::vector<std::uint8_t>& selected, RoundState& state) {
  for (const std::vector<std::uint32_t>& members : classes)
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, members.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
      Star s, landed;
      for (std::size_t k = r.begin(); k < r.end(); ++k) {
        const std::uint32_t i = members[k];
        if (selected[i]) state.moves[i] += move_vertex(c, i, s, landed, state.tangled[i]);
      }
    });
}

// Marks the vertices that moved farther than `threshold` and their
// neighbours (only they can move on); false if none did.
bool mark_active(const InputMesh& m, const std::vector<double>& moves, double threshold, std::vector<std::uint8_t>& active) {
  std::fill(active.begin(), active.end(), std::uint8_t{0});
  bool any = false;
  for (std::uint32_t i = 0; i < moves.size(); ++i) {
    if (!(moves[i] > threshold)) continue;
    any = true;
    active[i] = 1;
    for (std::uint32_t k = 0; k < m.neighbour_count[i]; ++k) active[m.neighbours[2 * m.star_offsets[i] + k]] = 1;
  }
  return any;
}

std::size_t count(const std::vector<std::uint8_t>& flags) {
  return static_cast<std::size_t>(std::count(flags.begin(), flags.end(), std::uint8_t{1}));
}

}  // namespace

SmoothingStatistics smooth_surface_map(simplify::SurfaceMap& map, const PolygonMesh& surface,
                                       const std::vector<Vec3>& base_positions, const SmoothingOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  assert(map.vertex_count() == surface.vertex_count() && map.vertex_uv.size() == map.vertex_count());
  if (options.max_rounds <= 0) return {};
  const BaseDomain domain = make_domain(map, base_positions);
  const InputMesh mesh = make_input(surface, map);
  const std::vector<std::vector<std::uint32_t>> classes = colour_classes(mesh);
  const Context c{domain, mesh, map};

  SmoothingStatistics statistics;
  statistics.free_vertices = count(mesh.free);
  const std::vector<std::uint8_t> inverted = find_inverted(c);
  statistics.inverted_before = count(inverted);
  const std::size_t n = map.vertex_count();
  RoundState state{std::vector<double>(n, 0), std::vector<std::uint8_t>(n, 0), std::vector<std::uint8_t>(n, 1)};
  for (std::size_t t = 0; t < inverted.size(); ++t)
    if (inverted[t])
      for (const std::uint32_t v : mesh.triangles[t]) state.tangled[v] = 1;
  std::vector<double> total(n, 0);
  while (statistics.rounds < options.max_rounds && n > 0) {
    ++statistics.rounds;
    std::fill(state.moves.begin(), state.moves.end(), 0.0);
    sweep(c, classes, state.tangled, state);  // untangling first
    if (options.mode == SmoothingMode::Relax) sweep(c, classes, state.active, state);
    for (std::size_t i = 0; i < n; ++i) total[i] += state.moves[i];
    if (!mark_active(mesh, state.moves, options.min_move * domain.mean_edge, state.active)) break;
  }
  statistics.inverted_after = count(find_inverted(c));
  if (statistics.free_vertices > 0 && domain.mean_edge > 0)
    statistics.mean_move =
        std::accumulate(total.begin(), total.end(), 0.0) / double(statistics.free_vertices) / domain.mean_edge;
  statistics.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return statistics;
}

}  // namespace isowave

