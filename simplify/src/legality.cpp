// The legality of a collapse (paper Sec. 4.1 and Hoppe 1996): the rules on
// sharp and boundary vertices and valences (vertex_rules), the link
// condition, the face-flip and degeneracy tests, and the new position and
// delta E (4.1)-(4.3) of a legal collapse (evaluate), with the fan cache
// they read the neighbourhood through.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <new>

#include "collapse_mesh_internal.h"
#include "isowave/simplify/collapse_error.h"

namespace isowave::simplify {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

}  // namespace

const char* to_string(Legality legality) {
  switch (legality) {
    case Legality::Legal: return "legal";
    case Legality::DeadEdge: return "deleted edge";
    case Legality::BothEndpointsSharp: return "both endpoints sharp";
    case Legality::InteriorEdgeOnBoundary: return "interior edge joining two boundary vertices";
    case Legality::BoundaryLoopMinimum: return "boundary loop at 3 vertices";
    case Legality::NewVertexValence: return "valence of the new vertex";
    case Legality::OppositeVertexValence: return "valence of an opposite vertex";
    case Legality::LinkCondition: return "link condition";
    case Legality::NormalFlip: return "normal flip";
    case Legality::DegenerateTriangle: return "degenerate triangle";
    case Legality::AreaBudget: return "area budget";
  }
  return "?";
}

FanCache::FanCache(int lane)
    : lane_(lane), slot_vertex_(kSlots), slot_fan_(kSlots), slot_stamp_(kSlots, 0), entries_(new Entry[kEntries]) {
  assert(lane >= 0 && lane < CollapseMesh::kLanes);
  fans_.reserve(kMaxFans);
}

void FanCache::clear(const CollapseMesh* mesh, std::uint64_t version) {
  mesh_ = mesh;
  version_ = version;
  if (++stamp_ == 0) {  // wrapped: forget old stamps
    std::fill(slot_stamp_.begin(), slot_stamp_.end(), 0);
    stamp_ = 1;
  }
  fans_.clear();
  used_entries_ = 0;
}

std::uint32_t CollapseMesh::fan(std::uint32_t v, FanCache& cache) const {
  std::uint32_t slot = (v * 2654435761u) >> 23;  // kSlots = 2^9
  for (; cache.slot_stamp_[slot] == cache.stamp_; slot = (slot + 1) % FanCache::kSlots)
    if (cache.slot_vertex_[slot] == v) return cache.slot_fan_[slot];
  const std::uint32_t index = static_cast<std::uint32_t>(cache.fans_.size());
  cache.slot_stamp_[slot] = cache.stamp_;
  cache.slot_vertex_[slot] = v;
  cache.slot_fan_[slot] = index;

  // Corner t's triangle is (v, ring t, ring t+1): ring t+1 is the vertex
  // before v in that triangle, since the next corner is opposite prev(c).
  const std::uint32_t begin = cache.used_entries_;
  FanCache::Entry* const entries = cache.entries_.get() + begin;
  std::uint32_t count = 0;
  const std::uint32_t start = vertices_[v].halfedge;
  std::uint32_t c = start, last;
  do {
    const std::uint32_t w = corners_[next(c)].vertex;
    const Vec3& q = vertices_[w].position;
    FanCache::Entry& entry = entries[count++];
    entry.x = q.x;
    entry.y = q.y;
    entry.z = q.z;
    entry.vertex = w;
    entry.triangle = c / 3;
    last = c;
    c = corners_[prev(c)].opposite;
  } while (c != kNone && c != start);
  const std::uint32_t closing = corners_[prev(last)].vertex;
  entries[count].vertex = closing;
  fill_fan_geometry(v, entries, count);
  std::uint64_t neighbours = 0;
  for (std::uint32_t t = 0; t < count + (is_boundary(v) ? 1 : 0); ++t) neighbours |= std::uint64_t{1} << (entries[t].vertex % 64);
  cache.used_entries_ = begin + count + 1;
  cache.fans_.push_back(FanCache::Fan{v, begin, count, neighbours});
  return index;
}

void CollapseMesh::fill_fan_geometry(std::uint32_t v, FanCache::Entry* entries, std::uint32_t count) const {
  const Vec3& q = vertices_[entries[count].vertex].position;
  entries[count] = FanCache::Entry{q.x, q.y, q.z, 0.0, 0.0, 0.0, 0.0, entries[count].vertex, kNone};
  const Vec3& centre = vertices_[v].position;
  Vec3 before = Vec3{entries[0].x, entries[0].y, entries[0].z} - centre;
  for (std::uint32_t t = 0; t < count; ++t) {
    const Vec3 after = Vec3{entries[t + 1].x, entries[t + 1].y, entries[t + 1].z} - centre;
    const Vec3 old_cross = cross(before, after);
    entries[t].cross_x = old_cross.x;
    entries[t].cross_y = old_cross.y;
    entries[t].cross_z = old_cross.z;
    entries[t].cross_squared = squared_norm(old_cross);
    before = after;
  }
}

Evaluation CollapseMesh::evaluate(std::uint32_t e) const {
  FanCache cache;
  return evaluate(e, cache);
}

Evaluation CollapseMesh::evaluate(std::uint32_t e, FanCache& cache) const {
  return evaluate(e, cache, rules_.max_valence);
}

Legality CollapseMesh::vertex_rules(std::uint32_t e, int max_valence) const {
  const std::uint32_t h = edges_[e].halfedge;
  if (h == kNone) return Legality::DeadEdge;
  const std::uint32_t o = corners_[h].opposite;
  const bool boundary_edge = o == kNone;
  const std::uint32_t vi = corners_[h].vertex, vj = corners_[next(h)].vertex, a = corners_[prev(h)].vertex;
  if (is_sharp(vi) && is_sharp(vj)) return Legality::BothEndpointsSharp;
  const bool boundary_i = is_boundary(vi), boundary_j = is_boundary(vj);
  if (!boundary_edge && boundary_i && boundary_j) return Legality::InteriorEdgeOnBoundary;
  if (boundary_edge && loop_size_[vertices_[vi].boundary_loop] <= 3) return Legality::BoundaryLoopMinimum;
  if (!vertex_area_.empty() && double(vertex_area_[vi]) + vertex_area_[vj] > rules_.max_vertex_area)
    return Legality::AreaBudget;

  // Paper: the new vertex has valence N_i + N_j - 4 (a boundary edge has one
  // shared neighbour fewer: - 3); a and b lose one.
  const bool new_boundary = boundary_i || boundary_j;
  const int new_valence = int(vertices_[vi].valence) + int(vertices_[vj].valence) - (boundary_edge ? 3 : 4);
  if (new_valence > max_valence || new_valence < (new_boundary ? 2 : 3)) return Legality::NewVertexValence;
  if (int(vertices_[a].valence) - 1 < (is_boundary(a) ? 2 : 3)) return Legality::OppositeVertexValence;
  if (!boundary_edge) {
    const std::uint32_t b = corners_[prev(o)].vertex;
    if (int(vertices_[b].valence) - 1 < (is_boundary(b) ? 2 : 3)) return Legality::OppositeVertexValence;
  }
  return Legality::Legal;
}

Evaluation CollapseMesh::evaluate(std::uint32_t e, FanCache& cache, int max_valence) const {
  assert(max_valence + 8 <= kMaxRing);
  Evaluation result;
  const auto fail = [&](Legality why) {
    result.legality = why;
    return result;
  };
  if (const Legality rules = vertex_rules(e, max_valence); rules != Legality::Legal) return fail(rules);
  const std::uint32_t h = edges_[e].halfedge;
  const std::uint32_t o = corners_[h].opposite;
  const bool boundary_edge = o == kNone;
  const std::uint32_t vi = corners_[h].vertex, vj = corners_[next(h)].vertex;
  const bool boundary_i = is_boundary(vi), boundary_j = is_boundary(vj);

  // Fans of both endpoints (the valence test bounds their size). Indices
  // first: gathering the second fan may reallocate the cache.
  const std::uint64_t version = lanes_[cache.lane_].version;
  if (cache.mesh_ != this || cache.version_ != version || cache.fans_.size() + 2 > FanCache::kMaxFans ||
      cache.used_entries_ + 2 * (kMaxRing + 1) > FanCache::kEntries)
    cache.clear(this, version);
  const std::uint32_t fan_i = fan(vi, cache), fan_j = fan(vj, cache);
  const FanCache::Fan fi = cache.fans_[fan_i], fj = cache.fans_[fan_j];
  const FanCache::Entry* ring_i = cache.entries_.get() + fi.begin;
  const FanCache::Entry* ring_j = cache.entries_.get() + fj.begin;

  // Link condition: the common neighbours of v_i and v_j are exactly a and b
  // (only a for a boundary edge); together with the rules above this keeps
  // the surface a 2-manifold of the same topology (Dey et al. 1999).
  if (common_neighbours(fi, ring_i, boundary_i, fj, ring_j, boundary_j) != (boundary_edge ? 1 : 2))
    return fail(Legality::LinkCondition);

  // New position: the edge midpoint, or the sharp endpoint; for an interior
  // edge with one boundary endpoint, that endpoint, so that boundaries stay
  // where they are.
  const Vec3& pi = vertices_[vi].position;
  const Vec3& pj = vertices_[vj].position;
  Vec3 p = (pi + pj) * 0.5;
  if (is_sharp(vi)) p = pi;
  else if (is_sharp(vj)) p = pj;
  else if (!boundary_edge && boundary_i) p = pi;
  else if (!boundary_edge && boundary_j) p = pj;

  // Ring triangles after the collapse: every triangle at v_i or v_j except
  // the one or two that disappear; check each for flips and degeneracy and
  // collect its cross product c_t for (4.1)-(4.2). Each ring vertex's offset
  // from p serves the two triangles it belongs to.
  const std::uint32_t t0 = h / 3, t1 = boundary_edge ? kNone : o / 3;
  // Raw storage: Vec3's member initialisers would zero 2 * kMaxRing vectors
  // on every call, which costs more than the evaluation itself.
  alignas(Vec3) unsigned char cross_storage[sizeof(Vec3) * 2 * kMaxRing];
  Vec3* const cross_products = reinterpret_cast<Vec3*>(cross_storage);
  double squared_norms[2 * kMaxRing];
  std::size_t k = 0;
  const double min_dot = rules_.min_normal_dot;
  // The first problem of one fan: a degenerate triangle, or a flip (which
  // ends that fan's triangles).
  const auto add_triangles = [&](const FanCache::Entry* ring, std::uint32_t corners) {
    Vec3 before = Vec3{ring[0].x, ring[0].y, ring[0].z} - p;
    double before_squared = squared_norm(before);
    for (std::uint32_t index = 0; index < corners; ++index) {
      const FanCache::Entry& corner = ring[index];
      const Vec3 after = Vec3{ring[index + 1].x, ring[index + 1].y, ring[index + 1].z} - p;
      const double after_squared = squared_norm(after);
      if (corner.triangle != t0 && corner.triangle != t1) {
        const Vec3 new_cross = cross(before, after);
        const double new_squared = squared_norm(new_cross);
        if (!(new_squared > 1e-24 * before_squared * after_squared)) return Legality::DegenerateTriangle;
        const double old_squared = corner.cross_squared;
        if (old_squared > 0) {
          const double turn = corner.cross_x * new_cross.x + corner.cross_y * new_cross.y + corner.cross_z * new_cross.z;
          // For the default threshold 0, skip the square root: 0 * sqrt(P) is
          // +0 for finite P and NaN (never smaller) for P = inf.
          const bool flipped = min_dot == 0.0 ? turn < 0 && old_squared * new_squared != kInfinity
                                              : turn < min_dot * std::sqrt(old_squared * new_squared);
          if (flipped) return Legality::NormalFlip;
        }
        squared_norms[k] = new_squared;
        new (&cross_products[k++]) Vec3(new_cross);
      }
      before = after;
      before_squared = after_squared;
    }
    return Legality::Legal;
  };
  const Legality problem_i = add_triangles(ring_i, fi.corners);
  if (problem_i == Legality::DegenerateTriangle) return fail(problem_i);
  const Legality problem_j = add_triangles(ring_j, fj.corners);
  if (problem_j == Legality::DegenerateTriangle) return fail(problem_j);
  if (problem_i != Legality::Legal || problem_j != Legality::Legal) return fail(Legality::NormalFlip);
  assert(k >= 1);
  result.legality = Legality::Legal;
  result.geometry_computed = true;
  result.position = p;
  const CollapseErrorTerms terms = collapse_error_terms(pj - pi, cross_products, squared_norms, k);
  result.delta_error = terms.delta_e;
  if (boundary_edge && rules_.boundary_curve_error) {
    const double boundary_move = std::max(boundary_curve_move(ring_i, fi.corners, vj, pi, p),
                                          boundary_curve_move(ring_j, fj.corners, vi, pj, p));
    result.delta_error = terms.weight * std::max(terms.delta_e1, boundary_move);
  }
  return result;
}

int CollapseMesh::common_neighbours(const FanCache::Fan& fi, const FanCache::Entry* ring_i, bool boundary_i,
                                    const FanCache::Fan& fj, const FanCache::Entry* ring_j, bool boundary_j) {
  // The neighbours are the ring, with the closing vertex only on the
  // boundary (inside it repeats ring 0).
  const std::uint32_t neighbour_count_i = fi.corners + (boundary_i ? 1 : 0);
  const std::uint32_t neighbour_count_j = fj.corners + (boundary_j ? 1 : 0);
  int common = 0;
  for (std::uint32_t k = 0; k < neighbour_count_j; ++k) {
    const std::uint32_t w = ring_j[k].vertex;
    if (((fi.neighbours >> (w % 64)) & 1) == 0) continue;
    for (std::uint32_t m = 0; m < neighbour_count_i; ++m)
      if (ring_i[m].vertex == w) {
        ++common;
        break;
      }
  }
  return common;
}

double CollapseMesh::boundary_curve_move(const FanCache::Entry* ring, std::uint32_t corners, std::uint32_t other,
                                         const Vec3& from, const Vec3& p) {
  // The move's component along the other boundary edge's in-surface normal
  // (edge x triangle normal). The endpoint's fan runs from one boundary
  // neighbour (ring 0) to the other (the closing ring entry).
  const bool first_is_other = ring[0].vertex == other;
  const FanCache::Entry& end = first_is_other ? ring[corners] : ring[0];
  const FanCache::Entry& triangle = first_is_other ? ring[corners - 1] : ring[0];
  const Vec3 in_surface =
      cross(Vec3{end.x, end.y, end.z} - from, Vec3{triangle.cross_x, triangle.cross_y, triangle.cross_z});
  const double length = norm(in_surface);
  return length > 0 ? std::abs(dot(p - from, in_surface)) / length : 0.0;
}

}  // namespace isowave::simplify
