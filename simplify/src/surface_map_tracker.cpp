#include "surface_map_tracker.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace isowave::simplify {

namespace {

constexpr double kTwoPi = 6.283185307179586;
// Each boundary edge's share of the circle gets this fraction of the mean
// edge length on top of its own, so that no two chart vertices come close.
constexpr double kArcFloor = 0.1;

bool contains(const std::vector<std::uint32_t>& list, std::uint32_t x) {
  return std::find(list.begin(), list.end(), x) != list.end();
}

double distance(const Vec3& a, const Vec3& b) { return std::sqrt(squared_norm(a - b)); }

// Twice the signed area of the chart triangle (a, b, c).
double signed_area(const double* a, const double* b, const double* c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

}  // namespace

SurfaceMapTracker::SurfaceMapTracker(const CollapseMesh& mesh)
    : point_triangle_(mesh.vertex_slots()),
      point_uv_(mesh.vertex_slots()),
      next_point_(mesh.vertex_slots(), kNone),
      first_point_(mesh.triangle_slots(), kNone),
      version_(mesh.triangle_slots()) {
  history_.input_corners.resize(mesh.triangle_slots());
  for (std::uint32_t t = 0; t < mesh.triangle_slots(); ++t) {
    version_[t] = t;
    for (int k = 0; k < 3; ++k) history_.input_corners[t][k] = mesh.origin(3 * t + static_cast<std::uint32_t>(k));
  }
  history_.chart_begin.push_back(0);
  history_.consumed_begin.push_back(0);
  history_.made_begin.push_back(mesh.triangle_slots());
  for (std::uint32_t v = 0; v < mesh.vertex_slots(); ++v) {
    assert(mesh.vertex_alive(v));
    const std::uint32_t corner = mesh.vertex_halfedge(v);
    const std::uint32_t t = corner / 3;
    point_triangle_[v] = t;
    point_uv_[v] = {corner % 3 == 1 ? 1.0 : 0.0, corner % 3 == 2 ? 1.0 : 0.0};
    next_point_[v] = first_point_[t];
    first_point_[t] = v;
  }
}

void SurfaceMapTracker::append_fan(const CollapseMesh& mesh, std::uint32_t v, std::vector<std::uint32_t>& out) {
  const std::uint32_t start = mesh.vertex_halfedge(v);
  std::uint32_t c = start;
  do {
    if (!contains(out, c / 3)) out.push_back(c / 3);
    c = mesh.opposite(CollapseMesh::prev(c));
  } while (c != kNone && c != start);
}

void SurfaceMapTracker::boundary_polygon(const CollapseMesh& mesh, Lane& lane) {
  lane.boundary_from.clear();
  lane.boundary_to.clear();
  for (const std::uint32_t t : lane.triangles)
    for (std::uint32_t h = 3 * t; h < 3 * t + 3; ++h) {
      const std::uint32_t twin = mesh.opposite(h);
      if (twin != kNone && contains(lane.triangles, twin / 3)) continue;
      lane.boundary_from.push_back(mesh.origin(h));
      lane.boundary_to.push_back(mesh.target(h));
    }
  // The region is a disk (link condition): its boundary is one cycle.
  lane.polygon.clear();
  std::uint32_t v = lane.boundary_from.front();
  for (std::size_t k = 0; k < lane.boundary_from.size(); ++k) {
    lane.polygon.push_back(v);
    const auto at = std::find(lane.boundary_from.begin(), lane.boundary_from.end(), v);
    assert(at != lane.boundary_from.end());
    v = lane.boundary_to[static_cast<std::size_t>(at - lane.boundary_from.begin())];
  }
  assert(v == lane.polygon.front());
}

void SurfaceMapTracker::set_lengths(const CollapseMesh& mesh, Lane& lane) {
  const std::size_t n = lane.polygon.size();
  lane.arcs.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    lane.arcs[k] = distance(mesh.position(lane.polygon[k]), mesh.position(lane.polygon[(k + 1) % n]));
}

void SurfaceMapTracker::place_on_circle(Lane& lane) {
  const std::size_t n = lane.polygon.size();
  double total = 0;
  for (std::size_t k = 0; k < n; ++k) total += lane.arcs[k];
  const double floor = total > 0 && std::isfinite(total) ? kArcFloor * total / double(n) : 1.0;
  double sum = 0;
  for (double& arc : lane.arcs) sum += arc = (std::isfinite(arc) ? arc : 0.0) + floor;  // each edge's share
  double angle = 0;
  for (std::size_t k = 0; k < n; ++k) {
    lane.chart.push_back(ChartVertex{lane.polygon[k], std::cos(angle), std::sin(angle)});
    angle += kTwoPi * lane.arcs[k] / sum;
  }
}

const SurfaceMapTracker::ChartVertex& SurfaceMapTracker::chart_of(const Lane& lane, std::uint32_t v) {
  for (const ChartVertex& c : lane.chart)
    if (c.vertex == v) return c;
  assert(false && "vertex not in the chart");
  return lane.chart.front();
}

double SurfaceMapTracker::mean_value_position(const CollapseMesh& mesh, std::uint32_t v, std::uint32_t unplaced,
                                              Lane& lane, double& x, double& y) {
  // v is interior: its fan is closed, ring k and k+1 span corner k's triangle.
  lane.ring.clear();
  const std::uint32_t start = mesh.vertex_halfedge(v);
  std::uint32_t c = start;
  do {
    lane.ring.push_back(mesh.target(c));
    c = mesh.opposite(CollapseMesh::prev(c));
  } while (c != kNone && c != start);
  const std::size_t n = lane.ring.size();
  const Vec3& centre = mesh.position(v);
  // tan(alpha_k / 2) of the angle between ring k and k+1: |a x b| / (|a||b| + a.b).
  lane.weights.assign(n, 0.0);
  bool usable = true;
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3 a = mesh.position(lane.ring[k]) - centre, b = mesh.position(lane.ring[(k + 1) % n]) - centre;
    const double la = std::sqrt(squared_norm(a)), lb = std::sqrt(squared_norm(b));
    const double half_tan = std::sqrt(squared_norm(cross(a, b))) / (la * lb + dot(a, b));
    lane.weights[k] += half_tan / la;
    lane.weights[(k + 1) % n] += half_tan / lb;
  }
  double total = 0;
  for (double w : lane.weights) {
    usable = usable && std::isfinite(w) && w > 0;
    total += w;
  }
  if (!usable || !(total > 0) || !std::isfinite(total)) {
    lane.weights.assign(n, 1.0);
    total = double(n);
  }
  x = y = 0;
  double unplaced_weight = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double w = lane.weights[k] / total;
    if (lane.ring[k] == unplaced) {
      unplaced_weight += w;
      continue;
    }
    const ChartVertex& p = chart_of(lane, lane.ring[k]);
    x += w * p.x;
    y += w * p.y;
  }
  return unplaced_weight;
}

void SurfaceMapTracker::chart_inside(const CollapseMesh& mesh, std::uint32_t vi, std::uint32_t vj,
                                     const Vec3& position, Lane& lane) {
  set_lengths(mesh, lane);
  place_on_circle(lane);
  // p_i = A_i + w_ij p_j, p_j = A_j + w_ji p_i (w_ij w_ji < 1: both have other neighbours).
  double ax, ay, bx, by;
  const double w_ij = mean_value_position(mesh, vi, vj, lane, ax, ay);
  const double w_ji = mean_value_position(mesh, vj, vi, lane, bx, by);
  const double scale = 1.0 / (1.0 - w_ij * w_ji);
  const double xi = (ax + w_ij * bx) * scale, yi = (ay + w_ij * by) * scale;
  const double xj = bx + w_ji * xi, yj = by + w_ji * yi;
  lane.chart.push_back(ChartVertex{vi, xi, yi});
  lane.chart.push_back(ChartVertex{vj, xj, yj});
  if (position == mesh.position(vi))
    lane.new_vertex = {xi, yi};
  else if (position == mesh.position(vj))
    lane.new_vertex = {xj, yj};
  else
    lane.new_vertex = {0.5 * (xi + xj), 0.5 * (yi + yj)};
}

void SurfaceMapTracker::chart_one_on_boundary(const CollapseMesh& mesh, std::uint32_t on, std::uint32_t inside,
                                              Lane& lane) {
  set_lengths(mesh, lane);
  place_on_circle(lane);
  double x, y;
  mean_value_position(mesh, inside, kNone, lane, x, y);
  lane.chart.push_back(ChartVertex{inside, x, y});
  const ChartVertex& kept = chart_of(lane, on);
  lane.new_vertex = {kept.x, kept.y};
}

void SurfaceMapTracker::chart_boundary_edge(const CollapseMesh& mesh, std::uint32_t vi, std::uint32_t vj,
                                            Lane& lane) {
  // The endpoint with more triangles goes on the chord between its polygon
  // neighbours (one with a single triangle would flatten it), the other
  // stays on the circle and becomes the new vertex.
  std::vector<std::uint32_t>& fan = lane.ring;
  fan.clear();
  append_fan(mesh, vi, fan);
  const std::size_t fan_i = fan.size();
  fan.clear();
  append_fan(mesh, vj, fan);
  const std::uint32_t chord = fan.size() >= fan_i ? vj : vi, kept = chord == vj ? vi : vj;
  set_lengths(mesh, lane);
  const std::size_t n = lane.polygon.size();
  const std::size_t at = static_cast<std::size_t>(std::find(lane.polygon.begin(), lane.polygon.end(), chord) -
                                                  lane.polygon.begin());
  const std::uint32_t before = lane.polygon[(at + n - 1) % n], after = lane.polygon[(at + 1) % n];
  const double to_chord = lane.arcs[(at + n - 1) % n], from_chord = lane.arcs[at];
  // The polygon without the chord vertex: its two edges become one.
  lane.arcs[(at + n - 1) % n] = to_chord + from_chord;
  lane.arcs.erase(lane.arcs.begin() + static_cast<std::ptrdiff_t>(at));
  lane.polygon.erase(lane.polygon.begin() + static_cast<std::ptrdiff_t>(at));
  place_on_circle(lane);
  const ChartVertex a = chart_of(lane, before), b = chart_of(lane, after);
  const double sum = to_chord + from_chord;
  const double s = sum > 0 && std::isfinite(sum) ? to_chord / sum : 0.5;
  const double share = std::clamp(s, 0.05, 0.95);
  lane.chart.push_back(ChartVertex{chord, a.x + share * (b.x - a.x), a.y + share * (b.y - a.y)});
  const ChartVertex& k = chart_of(lane, kept);
  lane.new_vertex = {k.x, k.y};
}

std::uint8_t SurfaceMapTracker::chart_index(const Lane& lane, std::uint32_t v) {
  const std::size_t k = static_cast<std::size_t>(&chart_of(lane, v) - lane.chart.data());
  assert(k < 255);
  return static_cast<std::uint8_t>(k);
}

void SurfaceMapTracker::note_consumed(const CollapseMesh& mesh, Lane& lane) const {
  lane.consumed.clear();
  lane.consumed_corners.clear();
  for (const std::uint32_t t : lane.triangles) {
    lane.consumed.push_back(version_[t]);
    lane.consumed_corners.push_back({chart_index(lane, mesh.origin(3 * t)), chart_index(lane, mesh.origin(3 * t + 1)),
                                     chart_index(lane, mesh.origin(3 * t + 2))});
  }
}

void SurfaceMapTracker::record(const CollapseMesh& mesh, const Lane& lane) {
  assert(lane.chart.size() < 255);  // regions are bounded by kMaxRing
  const auto new_vertex = static_cast<std::uint8_t>(lane.chart.size());
  const std::lock_guard<std::mutex> lock(history_mutex_);
  SurfaceMapHistory& h = history_;
  for (const ChartVertex& c : lane.chart) h.chart.push_back({c.x, c.y});
  if (lane.survivor != kNone) h.chart.push_back(lane.new_vertex);
  h.chart_begin.push_back(static_cast<std::uint32_t>(h.chart.size()));
  h.consumed.insert(h.consumed.end(), lane.consumed.begin(), lane.consumed.end());
  h.consumed_corners.insert(h.consumed_corners.end(), lane.consumed_corners.begin(), lane.consumed_corners.end());
  h.consumed_begin.push_back(static_cast<std::uint32_t>(h.consumed.size()));
  std::uint32_t version = h.made_begin.back();
  for (const std::uint32_t t : lane.triangles) {
    if (mesh.origin(3 * t) == kNone) continue;  // deleted by the collapse
    std::array<std::uint8_t, 3> corners{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.origin(3 * t + static_cast<std::uint32_t>(k));
      corners[k] = v == lane.survivor ? new_vertex : chart_index(lane, v);
    }
    h.made_corners.push_back(corners);
    version_[t] = version++;
  }
  h.made_begin.push_back(version);
}

void SurfaceMapTracker::take_points(const CollapseMesh& mesh, Lane& lane) {
  lane.carried.clear();
  for (const std::uint32_t t : lane.triangles) {
    const ChartVertex& c0 = chart_of(lane, mesh.origin(3 * t));
    const ChartVertex& c1 = chart_of(lane, mesh.origin(3 * t + 1));
    const ChartVertex& c2 = chart_of(lane, mesh.origin(3 * t + 2));
    for (std::uint32_t p = first_point_[t]; p != kNone; p = next_point_[p]) {
      const double u = point_uv_[p][0], v = point_uv_[p][1], w = 1.0 - u - v;
      lane.carried.push_back(Carried{p, w * c0.x + u * c1.x + v * c2.x, w * c0.y + u * c1.y + v * c2.y});
    }
    first_point_[t] = kNone;
  }
}

void SurfaceMapTracker::place_points(const CollapseMesh& mesh, Lane& lane) {
  const auto corner = [&](std::uint32_t h, double* xy) {
    const std::uint32_t v = mesh.origin(h);
    if (v == lane.survivor) {
      xy[0] = lane.new_vertex[0];
      xy[1] = lane.new_vertex[1];
    } else {
      const ChartVertex& c = chart_of(lane, v);
      xy[0] = c.x;
      xy[1] = c.y;
    }
  };
  // Corner positions of the region's live triangles, 6 per triangle.
  std::vector<double>& corners = lane.corner_xy;
  corners.clear();
  for (const std::uint32_t t : lane.triangles) {
    double xy[6] = {0, 0, 0, 0, 0, 0};
    if (mesh.origin(3 * t) != kNone)
      for (int k = 0; k < 3; ++k) corner(3 * t + static_cast<std::uint32_t>(k), xy + 2 * k);
    corners.insert(corners.end(), xy, xy + 6);
  }
  for (const Carried& point : lane.carried) {
    const double q[2] = {point.x, point.y};
    std::uint32_t best = kNone;
    double best_min = -1e300, best_b1 = 0, best_b2 = 0;
    for (std::size_t k = 0; k < lane.triangles.size(); ++k) {
      const double* c = corners.data() + 6 * k;
      const double area = signed_area(c, c + 2, c + 4);
      if (!(area > 0)) continue;  // a deleted triangle
      const double b1 = signed_area(c, q, c + 4) / area, b2 = signed_area(c, c + 2, q) / area;
      const double smallest = std::min({1.0 - b1 - b2, b1, b2});
      if (smallest > best_min) {
        best_min = smallest;
        best = lane.triangles[k];
        best_b1 = b1;
        best_b2 = b2;
      }
      if (smallest >= 0) break;
    }
    assert(best != kNone);
    // Clamp what rounding put outside.
    double b0 = std::max(0.0, 1.0 - best_b1 - best_b2), b1 = std::max(0.0, best_b1), b2 = std::max(0.0, best_b2);
    const double sum = b0 + b1 + b2;
    point_uv_[point.point] = {b1 / sum, b2 / sum};
    point_triangle_[point.point] = best;
    next_point_[point.point] = first_point_[best];
    first_point_[best] = point.point;
  }
}

void SurfaceMapTracker::before_collapse(const CollapseMesh& mesh, std::uint32_t e, const Vec3& position,
                                        int lane_index) {
  Lane& lane = lanes_[static_cast<std::size_t>(lane_index)];
  const std::uint32_t h = mesh.edge_halfedge(e);
  const std::uint32_t vi = mesh.origin(h), vj = mesh.target(h);
  lane.triangles.clear();
  append_fan(mesh, vi, lane.triangles);
  append_fan(mesh, vj, lane.triangles);
  boundary_polygon(mesh, lane);
  lane.chart.clear();
  const bool on_i = contains(lane.polygon, vi), on_j = contains(lane.polygon, vj);
  if (!on_i && !on_j)
    chart_inside(mesh, vi, vj, position, lane);
  else if (on_i && on_j)
    chart_boundary_edge(mesh, vi, vj, lane);
  else
    chart_one_on_boundary(mesh, on_i ? vi : vj, on_i ? vj : vi, lane);
  take_points(mesh, lane);
  note_consumed(mesh, lane);
  lane.survivor = vi;
}

void SurfaceMapTracker::after_collapse(const CollapseMesh& mesh, std::uint32_t survivor, int lane_index) {
  Lane& lane = lanes_[static_cast<std::size_t>(lane_index)];
  assert(survivor == lane.survivor);
  (void)survivor;
  place_points(mesh, lane);
  record(mesh, lane);
}

void SurfaceMapTracker::before_flip(const CollapseMesh& mesh, std::uint32_t e, int lane_index) {
  Lane& lane = lanes_[static_cast<std::size_t>(lane_index)];
  const std::uint32_t h = mesh.edge_halfedge(e);
  lane.triangles.assign({h / 3, mesh.opposite(h) / 3});
  boundary_polygon(mesh, lane);
  lane.chart.clear();
  set_lengths(mesh, lane);
  place_on_circle(lane);
  take_points(mesh, lane);
  note_consumed(mesh, lane);
  lane.survivor = kNone;
}

void SurfaceMapTracker::after_flip(const CollapseMesh& mesh, std::uint32_t e, int lane_index) {
  (void)e;
  Lane& lane = lanes_[static_cast<std::size_t>(lane_index)];
  place_points(mesh, lane);
  record(mesh, lane);
}

SurfaceMap SurfaceMapTracker::finish(const CollapseMesh& mesh, const std::vector<std::uint32_t>& vertex_map,
                                     const std::vector<std::uint32_t>& input_of_vertex) {
  SurfaceMap map;
  std::vector<std::uint32_t> compact(mesh.triangle_slots(), kNone);
  for (std::uint32_t t = 0; t < mesh.triangle_slots(); ++t) {
    if (mesh.origin(3 * t) == kNone) continue;
    compact[t] = static_cast<std::uint32_t>(map.triangles.size());
    map.triangles.push_back(
        {vertex_map[mesh.origin(3 * t)], vertex_map[mesh.origin(3 * t + 1)], vertex_map[mesh.origin(3 * t + 2)]});
  }
  history_.base_version.resize(map.triangles.size());
  for (std::uint32_t t = 0; t < mesh.triangle_slots(); ++t)
    if (compact[t] != kNone) history_.base_version[compact[t]] = version_[t];
  for (auto& corners : history_.input_corners)
    for (std::uint32_t& v : corners) v = input_of_vertex[v];
  map.history = std::move(history_);
  map.triangle_face.resize(map.triangles.size());
  for (std::uint32_t t = 0; t < map.triangle_face.size(); ++t) map.triangle_face[t] = t;
  map.vertex_triangle.resize(point_triangle_.size());
  map.vertex_uv.resize(point_triangle_.size());
  for (std::size_t k = 0; k < point_triangle_.size(); ++k) {
    assert(compact[point_triangle_[k]] != kNone);
    map.vertex_triangle[input_of_vertex[k]] = compact[point_triangle_[k]];
    map.vertex_uv[input_of_vertex[k]] = point_uv_[k];
  }
  return map;
}

}  // namespace isowave::simplify
