#include "isowave/simplify/collapse_mesh.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>
#include <new>
#include <numeric>
#include <tuple>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"
#include "isowave/simplify/collapse_error.h"

namespace isowave::simplify {

namespace {

// Valences seen inside evaluate()/collapse() are bounded by the valence rule
// (N_i + N_j - 3 <= max_valence), so fixed-size scratch arrays suffice.
constexpr int kMaxRing = 48;
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
  }
  return "?";
}

CollapseMesh::CollapseMesh(const PolygonMesh& mesh, CollapseRules rules) : rules_(rules) { build(mesh, nullptr); }

CollapseMesh::CollapseMesh(const PolygonMesh& mesh, const std::vector<std::uint32_t>& vertex_order, CollapseRules rules)
    : rules_(rules) {
  assert(vertex_order.size() == mesh.vertex_count());
  build(mesh, vertex_order.data());
}

void CollapseMesh::build(const PolygonMesh& mesh, const std::uint32_t* order) {
  assert(rules_.max_valence >= 3 && rules_.max_valence + 8 <= kMaxRing);
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(mesh.vertex_count());
  const std::uint32_t triangle_count = static_cast<std::uint32_t>(mesh.face_count());
  const std::uint32_t corner_count = 3 * triangle_count;
  assert(mesh.face_vertices.size() == corner_count);
  const auto not_manifold = [](const std::string& what) {
    throw Error(ErrorKind::Topology, "not a consistently oriented 2-manifold: " + what);
  };
  if (triangle_count == 0) not_manifold("the mesh has no faces");
  using Range = tbb::blocked_range<std::uint32_t>;
  constexpr std::uint32_t kGrain = 1 << 14;

  std::vector<std::uint32_t> new_index;
  if (order) {
    new_index.resize(vertex_count);
    tbb::parallel_for(Range(0, vertex_count, kGrain), [&](const Range& range) {
      for (std::uint32_t k = range.begin(); k != range.end(); ++k) new_index[order[k]] = k;
    });
  }
  input_had_sharp_ = !mesh.sharp.empty();
  // The big arrays' pages are faulted in on all threads before the fill.
  reserve_fresh_on_huge_pages(vertices_, vertex_count);
  vertices_.resize(vertex_count);
  tbb::parallel_for(Range(0, vertex_count, kGrain), [&](const Range& range) {
    for (std::uint32_t k = range.begin(); k != range.end(); ++k) {
      const std::uint32_t v = order ? order[k] : k;
      vertices_[k] = VertexRecord{mesh.positions[v], kNone, 0, kNone, mesh.is_sharp(v) ? kSharp : std::uint8_t{0}, 0};
    }
  });

  // Renumbered triangles ordered by their smallest vertex: a counting sort,
  // stable, so that ties keep the input order.
  std::vector<std::uint32_t> triangle_order;
  if (order) {
    std::vector<std::uint32_t> smallest(triangle_count);
    tbb::parallel_for(Range(0, triangle_count, kGrain), [&](const Range& range) {
      for (std::uint32_t t = range.begin(); t != range.end(); ++t) {
        const std::uint32_t* face = mesh.face_vertices.data() + 3 * std::size_t{t};
        smallest[t] = std::min({new_index[face[0]], new_index[face[1]], new_index[face[2]]});
      }
    });
    std::vector<std::uint32_t> slot(vertex_count + 1, 0);
    for (std::uint32_t t = 0; t < triangle_count; ++t) ++slot[smallest[t] + 1];
    std::partial_sum(slot.begin(), slot.end(), slot.begin());
    triangle_order.resize(triangle_count);
    for (std::uint32_t t = 0; t < triangle_count; ++t) triangle_order[slot[smallest[t]]++] = t;
  }
  reserve_fresh_on_huge_pages(corners_, corner_count);
  corners_.resize(corner_count);
  std::atomic<bool> repeated_vertex{false};
  tbb::parallel_for(Range(0, triangle_count, kGrain), [&](const Range& range) {
    for (std::uint32_t t = range.begin(); t != range.end(); ++t) {
      const std::uint32_t* face = mesh.face_vertices.data() + 3 * std::size_t{order ? triangle_order[t] : t};
      std::uint32_t v[3];
      for (int i = 0; i < 3; ++i) {
        v[i] = order ? new_index[face[i]] : face[i];
        corners_[3 * t + i] = CornerRecord{v[i], kNone, kNone};
      }
      if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) repeated_vertex = true;
    }
  });
  if (repeated_vertex) not_manifold("a triangle uses a vertex twice");
  std::vector<std::uint32_t>().swap(triangle_order);
  std::vector<std::uint32_t>().swap(new_index);

  // Outgoing corners per vertex (compressed rows, ascending) to pair
  // half-edges in O(n).
  std::vector<std::uint32_t> first(vertex_count + 1, 0);
  for (std::uint32_t c = 0; c < corner_count; ++c) ++first[corners_[c].vertex + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  // Each entry with the corner's target, so that pairing reads the rows only.
  struct Outgoing {
    std::uint32_t corner, target;
  };
  std::vector<Outgoing> outgoing;
  reserve_fresh_on_huge_pages(outgoing, corner_count);  // faulted in on all threads: the fill below is serial
  outgoing.resize(corner_count);
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::uint32_t c = 0; c < corner_count; ++c)
      outgoing[fill[corners_[c].vertex]++] = Outgoing{c, corners_[next(c)].vertex};
  }
  // Opposites. A corner u -> w with two candidates w -> u lies on an edge of
  // more than two triangles or traversed twice in one direction; the case
  // without any w -> u shows up below as a vertex with two boundary corners.
  std::atomic<bool> shared_edge{false};
  tbb::parallel_for(Range(0, corner_count, kGrain), [&](const Range& range) {
    for (std::uint32_t c = range.begin(); c != range.end(); ++c) {
      const std::uint32_t u = corners_[c].vertex, w = corners_[next(c)].vertex;
      std::uint32_t found = kNone, matches = 0;
      for (std::uint32_t i = first[w]; i < first[w + 1]; ++i)
        if (outgoing[i].target == u && matches++ == 0) found = outgoing[i].corner;
      if (matches > 1) shared_edge = true;
      corners_[c].opposite = found;
    }
  });
  if (shared_edge) not_manifold("an edge has more than two triangles or two of the same orientation");

  // Vertices: half-edge (the boundary one, else the first), valence, and the
  // manifold test of require_manifold(): walking the fan from there reaches
  // every corner of the vertex.
  std::atomic<bool> unreferenced{false}, several_fans{false};
  tbb::parallel_for(Range(0, vertex_count, kGrain), [&](const Range& range) {
    for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
      const std::uint32_t begin = first[v], end = first[v + 1];
      if (begin == end) {
        unreferenced = true;
        continue;
      }
      std::uint32_t start = outgoing[begin].corner, boundary_corners = 0;
      for (std::uint32_t i = begin; i < end; ++i)
        if (corners_[outgoing[i].corner].opposite == kNone) {
          start = outgoing[i].corner;
          ++boundary_corners;
        }
      VertexRecord& record = vertices_[v];
      record.halfedge = start;
      record.valence = end - begin + (boundary_corners > 0 ? 1 : 0);  // a boundary vertex has one more neighbour
      if (boundary_corners > 0) record.flags |= kBoundary;
      std::uint32_t visited = 0, c = start;
      do {
        ++visited;
        c = corners_[prev(c)].opposite;
      } while (c != kNone && c != start && visited <= end - begin);
      if (boundary_corners > 1 || visited != end - begin) several_fans = true;
    }
  });
  if (unreferenced) not_manifold("a vertex is used by no triangle");
  if (several_fans) not_manifold("a vertex's triangles form more than one fan");
  // Freed before the edge records are allocated, which then take over their
  // pages: fresh pages cost more than the arithmetic here (the kernel zeroes
  // each; on this machine's VM 1-3.5 ms per MB when the host had reclaimed
  // them). Miranda: peak 886 -> 778 MB.
  std::vector<Outgoing>().swap(outgoing);
  std::vector<std::uint32_t>().swap(first);

  // Edge ids in corner order: one per corner without an opposite or with a
  // later one. Counted per chunk, then numbered.
  constexpr std::uint32_t kChunk = 1 << 16;
  const std::uint32_t chunk_count = (corner_count + kChunk - 1) / kChunk;
  std::vector<std::uint32_t> chunk_first(chunk_count + 1, 0);
  const auto owns_edge = [&](std::uint32_t c) {
    const std::uint32_t o = corners_[c].opposite;
    return o == kNone || o > c;
  };
  tbb::parallel_for(std::uint32_t{0}, chunk_count, [&](std::uint32_t chunk) {
    std::uint32_t count = 0;
    for (std::uint32_t c = chunk * kChunk; c < std::min(corner_count, (chunk + 1) * kChunk); ++c) count += owns_edge(c);
    chunk_first[chunk + 1] = count;
  });
  std::partial_sum(chunk_first.begin(), chunk_first.end(), chunk_first.begin());
  reserve_fresh_on_huge_pages(edges_, chunk_first[chunk_count]);
  edges_.resize(chunk_first[chunk_count]);
  tbb::parallel_for(std::uint32_t{0}, chunk_count, [&](std::uint32_t chunk) {
    std::uint32_t edge = chunk_first[chunk];
    for (std::uint32_t c = chunk * kChunk; c < std::min(corner_count, (chunk + 1) * kChunk); ++c) {
      if (!owns_edge(c)) continue;
      edges_[edge] = EdgeRecord{c, 0.0f, 0.0f, 0, {kNone, kNone, BucketQueue::kNotQueued}, 0};
      corners_[c].edge = edge;
      if (corners_[c].opposite != kNone) corners_[corners_[c].opposite].edge = edge;
      ++edge;
    }
  });

  initial_vertices_ = vertex_count;
  initial_triangles_ = triangle_count;
  for (int l = 0; l < kLanes; ++l) lanes_[l].stamp = static_cast<std::uint32_t>(l);

  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (!is_boundary(v) || vertices_[v].boundary_loop != kNone) continue;
    const std::uint32_t loop = static_cast<std::uint32_t>(loop_size_.size());
    std::uint32_t size = 0;
    for (std::uint32_t w = v; vertices_[w].boundary_loop == kNone; w = target(vertices_[w].halfedge)) {
      vertices_[w].boundary_loop = loop;
      ++size;
    }
    loop_size_.push_back(size);
  }
}

template <typename Visit>
void CollapseMesh::for_each_corner(std::uint32_t v, Visit&& visit) const {
  const std::uint32_t start = vertices_[v].halfedge;
  std::uint32_t c = start;
  do {
    visit(c);
    c = corners_[prev(c)].opposite;
  } while (c != kNone && c != start);
}

void CollapseMesh::append_neighbours(std::uint32_t v, std::vector<std::uint32_t>& neighbours) const {
  for_each_corner(v, [&](std::uint32_t c) {
    neighbours.push_back(target(c));
    neighbours.push_back(corners_[prev(c)].vertex);
  });
}

std::uint32_t CollapseMesh::find_edge(std::uint32_t a, std::uint32_t b) const {
  std::uint32_t found = kNone;
  for_each_corner(a, [&](std::uint32_t c) {
    if (target(c) == b) found = corners_[c].edge;
    if (corners_[prev(c)].vertex == b) found = corners_[prev(c)].edge;
  });
  return found;
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
  // the surface a 2-manifold of the same topology (Dey et al. 1999). The
  // neighbours are the ring, with the closing vertex only on the boundary
  // (inside it repeats ring 0).
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
  if (common != (boundary_edge ? 1 : 2)) return fail(Legality::LinkCondition);

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
    // How far each endpoint's other boundary edge sees the boundary move
    // within the surface: the move's component along the edge's in-surface
    // normal (edge x triangle normal). The endpoint's fan runs from one
    // boundary neighbour (ring 0) to the other (the closing ring entry).
    const auto curve_move = [&](const FanCache::Entry* ring, std::uint32_t corners, std::uint32_t other,
                                const Vec3& from) {
      const bool first_is_other = ring[0].vertex == other;
      const FanCache::Entry& end = first_is_other ? ring[corners] : ring[0];
      const FanCache::Entry& triangle = first_is_other ? ring[corners - 1] : ring[0];
      const Vec3 in_surface =
          cross(Vec3{end.x, end.y, end.z} - from, Vec3{triangle.cross_x, triangle.cross_y, triangle.cross_z});
      const double length = norm(in_surface);
      return length > 0 ? std::abs(dot(p - from, in_surface)) / length : 0.0;
    };
    const double boundary_move = std::max(curve_move(ring_i, fi.corners, vj, pi), curve_move(ring_j, fj.corners, vi, pj));
    result.delta_error = terms.weight * std::max(terms.delta_e1, boundary_move);
  }
  return result;
}

void CollapseMesh::reset_vertex_halfedge(std::uint32_t v, std::uint32_t start) {
  assert(start != kNone && corners_[start].vertex == v);
  if (is_boundary(v))
    while (corners_[start].opposite != kNone) start = next(corners_[start].opposite);  // clockwise to the boundary
  vertices_[v].halfedge = start;
}

std::uint32_t CollapseMesh::collapse(std::uint32_t e, const Vec3& position, std::uint32_t removed_edges[3],
                                     std::uint32_t opposite_vertices[2], int lane) {
  Lane& counts = lanes_[lane];
  ++counts.version;
  const std::uint32_t h = edges_[e].halfedge;
  assert(h != kNone);
  const std::uint32_t o = corners_[h].opposite;
  const bool boundary_edge = o == kNone;
  const std::uint32_t vi = corners_[h].vertex, vj = corners_[next(h)].vertex;
  const std::uint32_t t0 = h / 3, t1 = boundary_edge ? kNone : o / 3;

  std::array<std::uint32_t, kMaxRing> corners_j;
  int count_j = 0;
  for_each_corner(vj, [&](std::uint32_t c) { corners_j[count_j++] = c; });

  // Triangle t0 = (v_i, v_j, a): its edges (v_j, a) and (a, v_i) merge.
  const std::uint32_t n0 = next(h), p0 = prev(h);
  const std::uint32_t a = corners_[p0].vertex;
  const std::uint32_t outer_n0 = corners_[n0].opposite, outer_p0 = corners_[p0].opposite;
  const std::uint32_t keep0 = corners_[p0].edge, dead0 = corners_[n0].edge;
  std::uint32_t b = kNone, outer_n1 = kNone, outer_p1 = kNone, keep1 = kNone, dead1 = kNone;
  double destroyed_error = std::max({error(e), error(keep0), error(dead0)});
  if (!boundary_edge) {
    const std::uint32_t n1 = next(o), p1 = prev(o);
    b = corners_[p1].vertex;
    outer_n1 = corners_[n1].opposite;
    outer_p1 = corners_[p1].opposite;
    keep1 = corners_[n1].edge;
    dead1 = corners_[p1].edge;
    destroyed_error = std::max({destroyed_error, error(keep1), error(dead1)});
  }

  assert(outer_n0 != kNone || outer_p0 != kNone);
  if (outer_n0 != kNone) {
    corners_[outer_n0].opposite = outer_p0;
    corners_[outer_n0].edge = keep0;
  }
  if (outer_p0 != kNone) corners_[outer_p0].opposite = outer_n0;
  edges_[keep0].halfedge = outer_p0 != kNone ? outer_p0 : outer_n0;
  edges_[dead0].halfedge = kNone;
  if (!boundary_edge) {
    // Triangle t1 = (v_j, v_i, b): its edges (v_i, b) and (b, v_j) merge.
    assert(outer_n1 != kNone || outer_p1 != kNone);
    if (outer_p1 != kNone) {
      corners_[outer_p1].opposite = outer_n1;
      corners_[outer_p1].edge = keep1;
    }
    if (outer_n1 != kNone) corners_[outer_n1].opposite = outer_p1;
    edges_[keep1].halfedge = outer_n1 != kNone ? outer_n1 : outer_p1;
    edges_[dead1].halfedge = kNone;
  }
  edges_[e].halfedge = kNone;
  for (int k = 0; k < count_j; ++k) {
    const std::uint32_t c = corners_j[k];
    if (c / 3 != t0 && c / 3 != t1) corners_[c].vertex = vi;
  }
  for (std::uint32_t t : {t0, t1}) {
    if (t == kNone) continue;
    corners_[3 * t].vertex = corners_[3 * t + 1].vertex = corners_[3 * t + 2].vertex = kNone;
    ++counts.removed_triangles;
  }

  // Vertex attributes.
  vertices_[vi].valence = vertices_[vi].valence + vertices_[vj].valence - (boundary_edge ? 3 : 4);
  --vertices_[a].valence;
  if (b != kNone) --vertices_[b].valence;
  if (is_boundary(vj) && !is_boundary(vi)) vertices_[vi].boundary_loop = vertices_[vj].boundary_loop;
  vertices_[vi].flags |= vertices_[vj].flags & (kSharp | kBoundary);
  if (boundary_edge) --loop_size_[vertices_[vi].boundary_loop];
  vertices_[vi].position = position;
  vertices_[vj].halfedge = kNone;
  vertices_[vj].boundary_loop = kNone;
  ++counts.removed_vertices;
  reset_vertex_halfedge(vi, outer_p0 != kNone ? outer_p0 : next(outer_n0));
  reset_vertex_halfedge(a, outer_n0 != kNone ? outer_n0 : next(outer_p0));
  if (b != kNone) reset_vertex_halfedge(b, outer_n1 != kNone ? outer_n1 : next(outer_p1));

  // Paper: "the accumulated error for any edge adjacent to the new vertex is
  // set to the maximum of its previous value E_acc and the values E for the
  // five old edges destroyed by the collapse".
  const float propagated = static_cast<float>(destroyed_error);
  std::uint32_t last = kNone;
  for_each_corner(vi, [&](std::uint32_t c) {
    float& acc = edges_[corners_[c].edge].accumulated_error;
    acc = std::max(acc, propagated);
    last = c;
  });
  if (is_boundary(vi)) {
    float& acc = edges_[corners_[prev(last)].edge].accumulated_error;
    acc = std::max(acc, propagated);
  }

  removed_edges[0] = e;
  removed_edges[1] = dead0;
  removed_edges[2] = dead1;
  opposite_vertices[0] = a;
  opposite_vertices[1] = b;
  return vi;
}

std::size_t CollapseMesh::alive_vertices() const {
  std::size_t removed = 0;
  for (const Lane& lane : lanes_) removed += lane.removed_vertices;
  return initial_vertices_ - removed;
}

std::size_t CollapseMesh::alive_triangles() const {
  std::size_t removed = 0;
  for (const Lane& lane : lanes_) removed += lane.removed_triangles;
  return initial_triangles_ - removed;
}

bool CollapseMesh::collapse_inside(std::uint32_t e, std::uint8_t id) const {
  const std::uint32_t h = edges_[e].halfedge;
  if (h == kNone || corners_[h].opposite == kNone) return false;
  bool inside = true;
  for (const std::uint32_t v : {corners_[h].vertex, corners_[next(h)].vertex}) {
    if (region(v) != id) return false;
    for_each_corner(v, [&](std::uint32_t c) {
      inside = inside && region(target(c)) == id && region(corners_[prev(c)].vertex) == id;
    });
  }
  return inside;
}

std::array<std::uint32_t, 4> CollapseMesh::edge_vertices(std::uint32_t e) const {
  const std::uint32_t h = edges_[e].halfedge;
  assert(h != kNone);
  const std::uint32_t o = corners_[h].opposite;
  return {corners_[h].vertex, corners_[next(h)].vertex, corners_[prev(h)].vertex,
          o == kNone ? kNone : corners_[prev(o)].vertex};
}

bool CollapseMesh::can_flip(std::uint32_t e) const {
  const std::uint32_t h = edges_[e].halfedge;
  if (h == kNone || corners_[h].opposite == kNone) return false;
  const auto [vi, vj, a, b] = edge_vertices(e);
  if (is_sharp(vi) || is_sharp(vj) || (is_sharp(a) && is_sharp(b)) || a == b) return false;
  if (int(vertices_[vi].valence) - 1 < (is_boundary(vi) ? 2 : 3)) return false;
  if (int(vertices_[vj].valence) - 1 < (is_boundary(vj) ? 2 : 3)) return false;
  if (int(vertices_[a].valence) + 1 > rules_.max_valence || int(vertices_[b].valence) + 1 > rules_.max_valence)
    return false;
  // Unit normals of the old triangles (v_i, v_j, a), (v_j, v_i, b) and the new
  // ones (v_i, b, a), (v_j, a, b): all pairs must agree.
  const Vec3 &pi = vertices_[vi].position, &pj = vertices_[vj].position;
  const Vec3 &pa = vertices_[a].position, &pb = vertices_[b].position;
  Vec3 normals[4] = {cross(pj - pi, pa - pi), cross(pi - pj, pb - pj), cross(pb - pi, pa - pi), cross(pa - pj, pb - pj)};
  for (Vec3& n : normals) {
    const double length = std::sqrt(squared_norm(n));
    if (!(length > 0)) return false;
    n = n * (1.0 / length);
  }
  const double min_dot = rules_.flip_min_normal_dot;
  for (int x = 0; x < 4; ++x)
    for (int y = x + 1; y < 4; ++y)
      if (!(dot(normals[x], normals[y]) >= min_dot)) return false;
  return find_edge(a, b) == kNone;
}

void CollapseMesh::flip(std::uint32_t e, int lane) {
  ++lanes_[lane].version;
  // Triangle slots: t0 = (h, n0, p0) holds (v_i, v_j, a) and becomes
  // (v_i, b, a); t1 = (o, n1, p1) holds (v_j, v_i, b) and becomes (v_j, a, b).
  // The half-edges a -> v_i (p0) and b -> v_j (p1) keep their corners.
  const std::uint32_t h = edges_[e].halfedge, o = corners_[h].opposite;
  assert(o != kNone);
  const std::uint32_t n0 = next(h), p0 = prev(h), n1 = next(o), p1 = prev(o);
  const std::uint32_t vi = corners_[h].vertex, vj = corners_[o].vertex;
  const std::uint32_t a = corners_[p0].vertex, b = corners_[p1].vertex;
  const CornerRecord vi_to_b = corners_[n1], vj_to_a = corners_[n0];
  corners_[h] = CornerRecord{vi, vi_to_b.opposite, vi_to_b.edge};
  corners_[n0] = CornerRecord{b, n1, e};
  corners_[o] = CornerRecord{vj, vj_to_a.opposite, vj_to_a.edge};
  corners_[n1] = CornerRecord{a, n0, e};
  if (vi_to_b.opposite != kNone) corners_[vi_to_b.opposite].opposite = h;
  if (vj_to_a.opposite != kNone) corners_[vj_to_a.opposite].opposite = o;
  if (edges_[vi_to_b.edge].halfedge == n1) edges_[vi_to_b.edge].halfedge = h;
  if (edges_[vj_to_a.edge].halfedge == n0) edges_[vj_to_a.edge].halfedge = o;
  edges_[e].halfedge = n0;
  // v_i lost corner n1 and v_j corner n0; h and o now carry their half-edges
  // (the boundary one, if that was it).
  if (vertices_[vi].halfedge == n1) vertices_[vi].halfedge = h;
  if (vertices_[vj].halfedge == n0) vertices_[vj].halfedge = o;
  --vertices_[vi].valence;
  --vertices_[vj].valence;
  ++vertices_[a].valence;
  ++vertices_[b].valence;
}

int CollapseMesh::lower_valence(std::uint32_t v, int count, const std::uint32_t* keep, int keep_count,
                                std::vector<std::uint32_t>& flipped, int lane) {
  // Candidates: the edges at v, ordered by the valence the flip would add to
  // their two opposite vertices.
  std::array<std::pair<std::uint32_t, std::uint32_t>, kMaxRing> candidates;
  int candidate_count = 0;
  for_each_corner(v, [&](std::uint32_t c) {
    if (candidate_count == kMaxRing) return;
    const std::uint32_t w = target(c), edge = corners_[c].edge;
    if (std::find(keep, keep + keep_count, w) != keep + keep_count) return;
    if (corners_[c].opposite == kNone) return;
    const auto quad = edge_vertices(edge);
    candidates[candidate_count++] = {vertices_[quad[2]].valence + vertices_[quad[3]].valence, edge};
  });
  std::sort(candidates.begin(), candidates.begin() + candidate_count);
  int done = 0;
  for (int k = 0; k < candidate_count && done < count; ++k) {
    const std::uint32_t edge = candidates[k].second;
    if (!can_flip(edge)) continue;  // an earlier flip may have changed it
    flip(edge, lane);
    flipped.push_back(edge);
    ++done;
  }
  return done;
}

int CollapseMesh::flip_capacity(std::uint32_t v, const std::uint32_t* keep, int keep_count) const {
  const int room = int(vertices_[v].valence) - (is_boundary(v) ? 2 : 3);
  if (room <= 0 || is_sharp(v)) return 0;
  int capacity = 0;
  for_each_corner(v, [&](std::uint32_t c) {
    const std::uint32_t w = target(c);
    if (corners_[c].opposite == kNone || is_sharp(w) || std::find(keep, keep + keep_count, w) != keep + keep_count) return;
    const std::uint32_t a = corners_[prev(c)].vertex, b = corners_[prev(corners_[c].opposite)].vertex;
    if (int(vertices_[a].valence) < rules_.max_valence && int(vertices_[b].valence) < rules_.max_valence) ++capacity;
  });
  return std::min(capacity, room);
}

void CollapseMesh::gather_stencil(const std::uint32_t* centres, int count, std::vector<std::uint32_t>& edges,
                                  int lane) {
  Lane& state = lanes_[lane];
  if (state.stamp > std::numeric_limits<std::uint32_t>::max() - kLanes) {
    // After about 2^31 gathers: start over (never reached with parallel lanes in practice).
    for (EdgeRecord& record : edges_) record.stamp = 0;
    for (int l = 0; l < kLanes; ++l) lanes_[l].stamp = static_cast<std::uint32_t>(l);
  }
  state.stamp += kLanes;  // lane l uses l + kLanes * k, k >= 1: never 0, never another lane's
  const std::uint32_t stamp = state.stamp;
  const auto add = [&](std::uint32_t edge) {
    if (edges_[edge].stamp == stamp) return;
    edges_[edge].stamp = stamp;
    edges.push_back(edge);
  };
  for (int i = 0; i < count; ++i) {
    if (centres[i] == kNone || !vertex_alive(centres[i])) continue;
    for_each_corner(centres[i], [&](std::uint32_t c) {
      add(corners_[c].edge);
      add(corners_[next(c)].edge);
      add(corners_[prev(c)].edge);
    });
  }
}

std::string CollapseMesh::validate() const {
  const auto fail = [](const std::string& what) { return what; };
  const std::uint32_t corner_count = static_cast<std::uint32_t>(corners_.size());
  std::vector<std::uint32_t> corners_at(vertices_.size(), 0);
  std::size_t triangles = 0;
  std::vector<std::array<std::uint32_t, 3>> sorted_triangles;
  for (std::uint32_t t = 0; t < corner_count / 3; ++t) {
    if (corners_[3 * t].vertex == kNone) {
      if (corners_[3 * t + 1].vertex != kNone || corners_[3 * t + 2].vertex != kNone)
        return fail("partly deleted triangle " + std::to_string(t));
      continue;
    }
    ++triangles;
    std::array<std::uint32_t, 3> sorted{corners_[3 * t].vertex, corners_[3 * t + 1].vertex, corners_[3 * t + 2].vertex};
    std::sort(sorted.begin(), sorted.end());
    if (sorted[0] == sorted[1] || sorted[1] == sorted[2]) return fail("triangle " + std::to_string(t) + " repeats a vertex");
    sorted_triangles.push_back(sorted);
    for (std::uint32_t c = 3 * t; c < 3 * t + 3; ++c) {
      const std::uint32_t v = corners_[c].vertex;
      if (v >= vertices_.size() || !vertex_alive(v)) return fail("corner " + std::to_string(c) + " uses a deleted vertex");
      ++corners_at[v];
      const std::uint32_t o = corners_[c].opposite;
      const std::uint32_t edge = corners_[c].edge;
      if (edge >= edges_.size() || !edge_alive(edge)) return fail("corner " + std::to_string(c) + " has a deleted edge");
      const std::uint32_t h = edges_[edge].halfedge;
      if (h != c && h != o) return fail("edge " + std::to_string(edge) + " does not point to its corners");
      if (o == kNone) continue;
      if (corners_[o].vertex == kNone) return fail("corner " + std::to_string(c) + " is opposite a deleted triangle");
      if (corners_[o].opposite != c) return fail("opposite of corner " + std::to_string(c) + " is not symmetric");
      if (origin(o) != target(c) || target(o) != origin(c))
        return fail("opposite of corner " + std::to_string(c) + " does not run the other way");
      if (corners_[o].edge != edge) return fail("corners of edge " + std::to_string(edge) + " disagree");
    }
  }
  if (triangles != alive_triangles()) return fail("alive triangle count is wrong");
  std::sort(sorted_triangles.begin(), sorted_triangles.end());
  if (std::adjacent_find(sorted_triangles.begin(), sorted_triangles.end()) != sorted_triangles.end())
    return fail("two triangles share all three vertices");
  for (std::uint32_t e = 0; e < edges_.size(); ++e) {
    const std::uint32_t h = edges_[e].halfedge;
    if (h == kNone) continue;
    if (h >= corner_count || corners_[h].vertex == kNone || corners_[h].edge != e)
      return fail("edge " + std::to_string(e) + " points to a wrong corner");
  }
  std::size_t vertices = 0;
  std::vector<std::uint32_t> loop_count(loop_size_.size(), 0);
  for (std::uint32_t v = 0; v < vertices_.size(); ++v) {
    if (!vertex_alive(v)) {
      if (corners_at[v] != 0) return fail("deleted vertex " + std::to_string(v) + " is used");
      continue;
    }
    ++vertices;
    if (corners_at[v] == 0) return fail("vertex " + std::to_string(v) + " has no triangle");
    const std::uint32_t start = vertices_[v].halfedge;
    if (corners_[start].vertex != v) return fail("vertex " + std::to_string(v) + " has a wrong half-edge");
    const bool boundary = corners_[start].opposite == kNone;
    if (boundary != is_boundary(v)) return fail("boundary flag of vertex " + std::to_string(v) + " is wrong");
    std::vector<std::uint32_t> neighbours;
    std::uint32_t fan = 0, last = start;
    for_each_corner(v, [&](std::uint32_t c) {
      ++fan;
      neighbours.push_back(target(c));
      last = c;
    });
    if (boundary) neighbours.push_back(corners_[prev(last)].vertex);
    if (fan != corners_at[v]) return fail("vertex " + std::to_string(v) + " is not a single fan (non-manifold)");
    if (vertices_[v].valence != neighbours.size()) return fail("valence of vertex " + std::to_string(v) + " is wrong");
    std::sort(neighbours.begin(), neighbours.end());
    if (std::adjacent_find(neighbours.begin(), neighbours.end()) != neighbours.end())
      return fail("vertex " + std::to_string(v) + " has a duplicate edge");
    if (boundary) {
      if (vertices_[v].boundary_loop >= loop_size_.size()) return fail("boundary vertex " + std::to_string(v) + " has no loop");
      ++loop_count[vertices_[v].boundary_loop];
      if (vertices_[target(start)].boundary_loop != vertices_[v].boundary_loop) return fail("boundary loop ids disagree");
    }
  }
  if (vertices != alive_vertices()) return fail("alive vertex count is wrong");
  for (std::size_t l = 0; l < loop_size_.size(); ++l) {
    if (loop_count[l] != loop_size_[l]) return fail("boundary loop " + std::to_string(l) + " has a wrong size");
    if (loop_count[l] < 3) return fail("boundary loop " + std::to_string(l) + " has fewer than 3 vertices");
  }
  return {};
}

PolygonMesh CollapseMesh::to_polygon_mesh(std::vector<std::uint32_t>* vertex_map) const {
  std::vector<std::uint32_t> map(vertices_.size(), kNone);
  PolygonMesh result;
  result.positions.reserve(alive_vertices());
  for (std::uint32_t v = 0; v < vertices_.size(); ++v) {
    if (!vertex_alive(v)) continue;
    map[v] = static_cast<std::uint32_t>(result.positions.size());
    result.positions.push_back(vertices_[v].position);
    if (input_had_sharp_) result.sharp.push_back(is_sharp(v) ? 1 : 0);
  }
  result.face_vertices.reserve(3 * alive_triangles());
  result.face_offsets.reserve(alive_triangles() + 1);
  for (std::uint32_t t = 0; t < corners_.size() / 3; ++t) {
    if (corners_[3 * t].vertex == kNone) continue;
    result.add_face({map[corners_[3 * t].vertex], map[corners_[3 * t + 1].vertex], map[corners_[3 * t + 2].vertex]});
  }
  if (vertex_map) *vertex_map = std::move(map);
  return result;
}

std::vector<CollapseMesh::ComponentCounts> CollapseMesh::components() const {
  std::vector<std::uint32_t> parent(vertices_.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::uint32_t t = 0; t < corners_.size() / 3; ++t) {
    if (corners_[3 * t].vertex == kNone) continue;
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t r = find(corners_[3 * t].vertex);
      const std::uint32_t s = find(corners_[3 * t + k].vertex);
      if (s != r) parent[std::max(r, s)] = std::min(r, s);
    }
  }
  std::vector<std::uint32_t> label(vertices_.size(), kNone);
  std::vector<ComponentCounts> counts;
  for (std::uint32_t v = 0; v < vertices_.size(); ++v) {
    if (!vertex_alive(v)) continue;
    const std::uint32_t root = find(v);
    if (label[root] == kNone) {
      label[root] = static_cast<std::uint32_t>(counts.size());
      counts.emplace_back();
    }
    ++counts[label[root]].vertices;
  }
  for (std::uint32_t t = 0; t < corners_.size() / 3; ++t)
    if (corners_[3 * t].vertex != kNone) ++counts[label[find(corners_[3 * t].vertex)]].faces;
  for (std::uint32_t e = 0; e < edges_.size(); ++e)
    if (edge_alive(e)) ++counts[label[find(corners_[edges_[e].halfedge].vertex)]].edges;
  std::vector<std::uint8_t> loop_seen(loop_size_.size(), 0);
  for (std::uint32_t v = 0; v < vertices_.size(); ++v) {
    if (!vertex_alive(v) || !is_boundary(v) || loop_seen[vertices_[v].boundary_loop]) continue;
    loop_seen[vertices_[v].boundary_loop] = 1;
    ++counts[label[find(v)]].boundary_loops;
  }
  return counts;
}

}  // namespace isowave::simplify
