// Edge flips (not in the paper): they let the collapse go on where the
// valence rule alone stalls it (SimplifyOptions::valence_flips). A flip
// re-triangulates a nearly flat quad, moving valence from the edge's
// endpoints to its opposite vertices.
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <utility>
#include <vector>

#include "collapse_mesh_internal.h"
#include "surface_map_tracker.h"

namespace isowave::simplify {

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
  if (map_tracker_) map_tracker_->before_flip(*this, e, lane);
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
  if (map_tracker_) map_tracker_->after_flip(*this, e, lane);
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

}  // namespace isowave::simplify
