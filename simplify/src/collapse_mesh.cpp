#include "isowave/simplify/collapse_mesh.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <new>
#include <numeric>
#include <tuple>

#include "isowave/simplify/collapse_error.h"

namespace isowave::simplify {

namespace {

// Valences seen inside evaluate()/collapse() are bounded by the valence rule
// (N_i + N_j - 3 <= max_valence), so fixed-size scratch arrays suffice.
constexpr int kMaxRing = 48;

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

CollapseMesh::CollapseMesh(const PolygonMesh& mesh, CollapseRules rules) : rules_(rules) {
  assert(rules_.max_valence >= 3 && rules_.max_valence + 8 <= kMaxRing);
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(mesh.vertex_count());
  const std::uint32_t corner_count = static_cast<std::uint32_t>(mesh.face_vertices.size());
  assert(corner_count == 3 * mesh.face_count());
  positions_ = mesh.positions;
  corner_vertex_ = mesh.face_vertices;
  input_had_sharp_ = !mesh.sharp.empty();
  flags_.assign(vertex_count, 0);
  for (std::uint32_t v = 0; v < vertex_count; ++v)
    if (mesh.is_sharp(v)) flags_[v] |= kSharp;

  // Outgoing corners per vertex (compressed rows) to pair half-edges in O(n).
  std::vector<std::uint32_t> offsets(vertex_count + 1, 0);
  for (std::uint32_t v : corner_vertex_) ++offsets[v + 1];
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  std::vector<std::uint32_t> outgoing(corner_count);
  {
    std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t c = 0; c < corner_count; ++c) outgoing[fill[corner_vertex_[c]]++] = c;
  }
  opposite_.assign(corner_count, kNone);
  corner_edge_.assign(corner_count, kNone);
  edge_halfedge_.reserve(corner_count / 2 + corner_count / 8);
  for (std::uint32_t c = 0; c < corner_count; ++c) {
    if (corner_edge_[c] != kNone) continue;
    const std::uint32_t u = corner_vertex_[c], w = corner_vertex_[next(c)];
    for (std::uint32_t i = offsets[w]; i < offsets[w + 1]; ++i) {
      const std::uint32_t candidate = outgoing[i];
      if (corner_vertex_[next(candidate)] == u) {
        opposite_[c] = candidate;
        opposite_[candidate] = c;
        break;
      }
    }
    const std::uint32_t edge = static_cast<std::uint32_t>(edge_halfedge_.size());
    edge_halfedge_.push_back(c);
    corner_edge_[c] = edge;
    if (opposite_[c] != kNone) corner_edge_[opposite_[c]] = edge;
  }
  std::vector<std::uint32_t>().swap(outgoing);

  vertex_halfedge_.assign(vertex_count, kNone);
  valence_.assign(vertex_count, 0);
  for (std::uint32_t c = 0; c < corner_count; ++c) {
    const std::uint32_t v = corner_vertex_[c];
    ++valence_[v];
    if (opposite_[c] == kNone) {
      vertex_halfedge_[v] = c;
      flags_[v] |= kBoundary;
    } else if (vertex_halfedge_[v] == kNone) {
      vertex_halfedge_[v] = c;
    }
  }
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (is_boundary(v)) ++valence_[v];  // one more neighbour than corners
    if (vertex_halfedge_[v] != kNone) ++alive_vertices_;
  }
  alive_triangles_ = mesh.face_count();

  boundary_loop_.assign(vertex_count, kNone);
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (!is_boundary(v) || boundary_loop_[v] != kNone) continue;
    const std::uint32_t loop = static_cast<std::uint32_t>(loop_size_.size());
    std::uint32_t size = 0;
    for (std::uint32_t w = v; boundary_loop_[w] == kNone; w = target(vertex_halfedge_[w])) {
      boundary_loop_[w] = loop;
      ++size;
    }
    loop_size_.push_back(size);
  }

  const std::size_t edge_count = edge_halfedge_.size();
  accumulated_error_.assign(edge_count, 0.0f);
  latest_delta_.assign(edge_count, 0.0f);
  edge_stamp_.assign(edge_count, 0);
}

template <typename Visit>
void CollapseMesh::for_each_corner(std::uint32_t v, Visit&& visit) const {
  const std::uint32_t start = vertex_halfedge_[v];
  std::uint32_t c = start;
  do {
    visit(c);
    c = opposite_[prev(c)];
  } while (c != kNone && c != start);
}

std::uint32_t CollapseMesh::find_edge(std::uint32_t a, std::uint32_t b) const {
  std::uint32_t found = kNone;
  for_each_corner(a, [&](std::uint32_t c) {
    if (target(c) == b) found = corner_edge_[c];
    if (corner_vertex_[prev(c)] == b) found = corner_edge_[prev(c)];
  });
  return found;
}

Evaluation CollapseMesh::evaluate(std::uint32_t e) const {
  Evaluation result;
  const std::uint32_t h = edge_halfedge_[e];
  if (h == kNone) return result;
  const std::uint32_t o = opposite_[h];
  const bool boundary_edge = o == kNone;
  const std::uint32_t vi = corner_vertex_[h], vj = corner_vertex_[next(h)], a = corner_vertex_[prev(h)];
  const std::uint32_t b = boundary_edge ? kNone : corner_vertex_[prev(o)];

  const auto fail = [&](Legality why) {
    result.legality = why;
    return result;
  };
  if (is_sharp(vi) && is_sharp(vj)) return fail(Legality::BothEndpointsSharp);
  const bool boundary_i = is_boundary(vi), boundary_j = is_boundary(vj);
  if (!boundary_edge && boundary_i && boundary_j) return fail(Legality::InteriorEdgeOnBoundary);
  if (boundary_edge && loop_size_[boundary_loop_[vi]] <= 3) return fail(Legality::BoundaryLoopMinimum);

  // Paper: the new vertex has valence N_i + N_j - 4 (a boundary edge has one
  // shared neighbour fewer: - 3); a and b lose one.
  const bool new_boundary = boundary_i || boundary_j;
  const int new_valence = int(valence_[vi]) + int(valence_[vj]) - (boundary_edge ? 3 : 4);
  if (new_valence > rules_.max_valence || new_valence < (new_boundary ? 2 : 3))
    return fail(Legality::NewVertexValence);
  if (int(valence_[a]) - 1 < (is_boundary(a) ? 2 : 3)) return fail(Legality::OppositeVertexValence);
  if (!boundary_edge && int(valence_[b]) - 1 < (is_boundary(b) ? 2 : 3)) return fail(Legality::OppositeVertexValence);

  // Corners around both endpoints (the valence test bounds their number).
  std::array<std::uint32_t, kMaxRing> corners_i, corners_j;
  int count_i = 0, count_j = 0;
  for_each_corner(vi, [&](std::uint32_t c) { corners_i[count_i++] = c; });
  for_each_corner(vj, [&](std::uint32_t c) { corners_j[count_j++] = c; });

  // Link condition: the common neighbours of v_i and v_j are exactly a and b
  // (only a for a boundary edge); together with the rules above this keeps
  // the surface a 2-manifold of the same topology (Dey et al. 1999).
  std::array<std::uint32_t, kMaxRing> neighbours_i;
  int neighbour_count_i = 0;
  for (int k = 0; k < count_i; ++k) neighbours_i[neighbour_count_i++] = target(corners_i[k]);
  if (boundary_i) neighbours_i[neighbour_count_i++] = corner_vertex_[prev(corners_i[count_i - 1])];
  int common = 0;
  const auto count_common = [&](std::uint32_t w) {
    for (int k = 0; k < neighbour_count_i; ++k)
      if (neighbours_i[k] == w) {
        ++common;
        return;
      }
  };
  for (int k = 0; k < count_j; ++k) count_common(target(corners_j[k]));
  if (boundary_j) count_common(corner_vertex_[prev(corners_j[count_j - 1])]);
  if (common != (boundary_edge ? 1 : 2)) return fail(Legality::LinkCondition);

  // New position: the edge midpoint, or the sharp endpoint; for an interior
  // edge with one boundary endpoint, that endpoint, so that boundaries stay
  // where they are.
  const Vec3& pi = positions_[vi];
  const Vec3& pj = positions_[vj];
  Vec3 p = (pi + pj) * 0.5;
  if (is_sharp(vi)) p = pi;
  else if (is_sharp(vj)) p = pj;
  else if (!boundary_edge && boundary_i) p = pi;
  else if (!boundary_edge && boundary_j) p = pj;

  // Ring triangles after the collapse: every triangle at v_i or v_j except
  // the one or two that disappear; check each for flips and degeneracy and
  // collect its cross product c_t for (4.1)-(4.2).
  const std::uint32_t t0 = h / 3, t1 = boundary_edge ? kNone : o / 3;
  // Raw storage: Vec3's member initialisers would zero 2 * kMaxRing vectors
  // on every call, which costs more than the evaluation itself.
  alignas(Vec3) unsigned char cross_storage[sizeof(Vec3) * 2 * kMaxRing];
  Vec3* const cross_products = reinterpret_cast<Vec3*>(cross_storage);
  std::size_t k = 0;
  const double min_dot = rules_.min_normal_dot;
  const auto add_triangles = [&](const std::array<std::uint32_t, kMaxRing>& corners, int count, const Vec3& old_centre) {
    for (int index = 0; index < count; ++index) {
      const std::uint32_t c = corners[index];
      if (c / 3 == t0 || c / 3 == t1) continue;
      const Vec3& w0 = positions_[corner_vertex_[next(c)]];
      const Vec3& w1 = positions_[corner_vertex_[prev(c)]];
      const Vec3 e0 = w0 - p, e1 = w1 - p;
      const Vec3 new_cross = cross(e0, e1);
      const double new_squared = squared_norm(new_cross);
      if (!(new_squared > 1e-24 * squared_norm(e0) * squared_norm(e1))) return false;
      const Vec3 old_cross = cross(w0 - old_centre, w1 - old_centre);
      const double old_squared = squared_norm(old_cross);
      if (old_squared > 0 && dot(old_cross, new_cross) < min_dot * std::sqrt(old_squared * new_squared)) {
        result.legality = Legality::NormalFlip;
        return true;
      }
      new (&cross_products[k++]) Vec3(new_cross);
    }
    return true;
  };
  result.legality = Legality::Legal;
  if (!add_triangles(corners_i, count_i, pi) || !add_triangles(corners_j, count_j, pj))
    return fail(Legality::DegenerateTriangle);
  if (result.legality != Legality::Legal) return result;
  assert(k >= 1);
  result.geometry_computed = true;
  result.position = p;
  result.delta_error = collapse_error_terms(pj - pi, cross_products, k).delta_e;
  return result;
}

void CollapseMesh::reset_vertex_halfedge(std::uint32_t v, std::uint32_t start) {
  assert(start != kNone && corner_vertex_[start] == v);
  if (is_boundary(v))
    while (opposite_[start] != kNone) start = next(opposite_[start]);  // clockwise to the boundary
  vertex_halfedge_[v] = start;
}

std::uint32_t CollapseMesh::collapse(std::uint32_t e, const Vec3& position, std::uint32_t removed_edges[3],
                                     std::uint32_t opposite_vertices[2]) {
  const std::uint32_t h = edge_halfedge_[e];
  assert(h != kNone);
  const std::uint32_t o = opposite_[h];
  const bool boundary_edge = o == kNone;
  const std::uint32_t vi = corner_vertex_[h], vj = corner_vertex_[next(h)];
  const std::uint32_t t0 = h / 3, t1 = boundary_edge ? kNone : o / 3;

  std::array<std::uint32_t, kMaxRing> corners_j;
  int count_j = 0;
  for_each_corner(vj, [&](std::uint32_t c) { corners_j[count_j++] = c; });

  // Triangle t0 = (v_i, v_j, a): its edges (v_j, a) and (a, v_i) merge.
  const std::uint32_t n0 = next(h), p0 = prev(h);
  const std::uint32_t a = corner_vertex_[p0];
  const std::uint32_t outer_n0 = opposite_[n0], outer_p0 = opposite_[p0];
  const std::uint32_t keep0 = corner_edge_[p0], dead0 = corner_edge_[n0];
  std::uint32_t b = kNone, outer_n1 = kNone, outer_p1 = kNone, keep1 = kNone, dead1 = kNone;
  double destroyed_error = std::max({error(e), error(keep0), error(dead0)});
  if (!boundary_edge) {
    const std::uint32_t n1 = next(o), p1 = prev(o);
    b = corner_vertex_[p1];
    outer_n1 = opposite_[n1];
    outer_p1 = opposite_[p1];
    keep1 = corner_edge_[n1];
    dead1 = corner_edge_[p1];
    destroyed_error = std::max({destroyed_error, error(keep1), error(dead1)});
  }

  assert(outer_n0 != kNone || outer_p0 != kNone);
  if (outer_n0 != kNone) {
    opposite_[outer_n0] = outer_p0;
    corner_edge_[outer_n0] = keep0;
  }
  if (outer_p0 != kNone) opposite_[outer_p0] = outer_n0;
  edge_halfedge_[keep0] = outer_p0 != kNone ? outer_p0 : outer_n0;
  edge_halfedge_[dead0] = kNone;
  if (!boundary_edge) {
    // Triangle t1 = (v_j, v_i, b): its edges (v_i, b) and (b, v_j) merge.
    assert(outer_n1 != kNone || outer_p1 != kNone);
    if (outer_p1 != kNone) {
      opposite_[outer_p1] = outer_n1;
      corner_edge_[outer_p1] = keep1;
    }
    if (outer_n1 != kNone) opposite_[outer_n1] = outer_p1;
    edge_halfedge_[keep1] = outer_n1 != kNone ? outer_n1 : outer_p1;
    edge_halfedge_[dead1] = kNone;
  }
  edge_halfedge_[e] = kNone;
  for (int k = 0; k < count_j; ++k) {
    const std::uint32_t c = corners_j[k];
    if (c / 3 != t0 && c / 3 != t1) corner_vertex_[c] = vi;
  }
  for (std::uint32_t t : {t0, t1}) {
    if (t == kNone) continue;
    corner_vertex_[3 * t] = corner_vertex_[3 * t + 1] = corner_vertex_[3 * t + 2] = kNone;
    --alive_triangles_;
  }

  // Vertex attributes.
  valence_[vi] = valence_[vi] + valence_[vj] - (boundary_edge ? 3 : 4);
  --valence_[a];
  if (b != kNone) --valence_[b];
  if (is_boundary(vj) && !is_boundary(vi)) boundary_loop_[vi] = boundary_loop_[vj];
  flags_[vi] |= flags_[vj] & (kSharp | kBoundary);
  if (boundary_edge) --loop_size_[boundary_loop_[vi]];
  positions_[vi] = position;
  vertex_halfedge_[vj] = kNone;
  boundary_loop_[vj] = kNone;
  --alive_vertices_;
  reset_vertex_halfedge(vi, outer_p0 != kNone ? outer_p0 : next(outer_n0));
  reset_vertex_halfedge(a, outer_n0 != kNone ? outer_n0 : next(outer_p0));
  if (b != kNone) reset_vertex_halfedge(b, outer_n1 != kNone ? outer_n1 : next(outer_p1));

  // Paper: "the accumulated error for any edge adjacent to the new vertex is
  // set to the maximum of its previous value E_acc and the values E for the
  // five old edges destroyed by the collapse".
  const float propagated = static_cast<float>(destroyed_error);
  std::uint32_t last = kNone;
  for_each_corner(vi, [&](std::uint32_t c) {
    float& acc = accumulated_error_[corner_edge_[c]];
    acc = std::max(acc, propagated);
    last = c;
  });
  if (is_boundary(vi)) {
    float& acc = accumulated_error_[corner_edge_[prev(last)]];
    acc = std::max(acc, propagated);
  }

  removed_edges[0] = e;
  removed_edges[1] = dead0;
  removed_edges[2] = dead1;
  opposite_vertices[0] = a;
  opposite_vertices[1] = b;
  return vi;
}

void CollapseMesh::gather_stencil(const std::uint32_t* centres, int count, std::vector<std::uint32_t>& edges) {
  if (++stamp_ == 0) {  // wrapped: clear old stamps
    std::fill(edge_stamp_.begin(), edge_stamp_.end(), 0);
    stamp_ = 1;
  }
  const auto add = [&](std::uint32_t edge) {
    if (edge_stamp_[edge] == stamp_) return;
    edge_stamp_[edge] = stamp_;
    edges.push_back(edge);
  };
  for (int i = 0; i < count; ++i) {
    if (centres[i] == kNone || !vertex_alive(centres[i])) continue;
    for_each_corner(centres[i], [&](std::uint32_t c) {
      add(corner_edge_[c]);
      add(corner_edge_[next(c)]);
      add(corner_edge_[prev(c)]);
    });
  }
}

std::string CollapseMesh::validate() const {
  const auto fail = [](const std::string& what) { return what; };
  const std::uint32_t corner_count = static_cast<std::uint32_t>(corner_vertex_.size());
  std::vector<std::uint32_t> corners_at(positions_.size(), 0);
  std::size_t triangles = 0;
  std::vector<std::array<std::uint32_t, 3>> sorted_triangles;
  for (std::uint32_t t = 0; t < corner_count / 3; ++t) {
    if (corner_vertex_[3 * t] == kNone) {
      if (corner_vertex_[3 * t + 1] != kNone || corner_vertex_[3 * t + 2] != kNone)
        return fail("partly deleted triangle " + std::to_string(t));
      continue;
    }
    ++triangles;
    std::array<std::uint32_t, 3> sorted{corner_vertex_[3 * t], corner_vertex_[3 * t + 1], corner_vertex_[3 * t + 2]};
    std::sort(sorted.begin(), sorted.end());
    if (sorted[0] == sorted[1] || sorted[1] == sorted[2]) return fail("triangle " + std::to_string(t) + " repeats a vertex");
    sorted_triangles.push_back(sorted);
    for (std::uint32_t c = 3 * t; c < 3 * t + 3; ++c) {
      const std::uint32_t v = corner_vertex_[c];
      if (v >= positions_.size() || !vertex_alive(v)) return fail("corner " + std::to_string(c) + " uses a deleted vertex");
      ++corners_at[v];
      const std::uint32_t o = opposite_[c];
      const std::uint32_t edge = corner_edge_[c];
      if (edge >= edge_halfedge_.size() || !edge_alive(edge)) return fail("corner " + std::to_string(c) + " has a deleted edge");
      const std::uint32_t h = edge_halfedge_[edge];
      if (h != c && h != o) return fail("edge " + std::to_string(edge) + " does not point to its corners");
      if (o == kNone) continue;
      if (corner_vertex_[o] == kNone) return fail("corner " + std::to_string(c) + " is opposite a deleted triangle");
      if (opposite_[o] != c) return fail("opposite of corner " + std::to_string(c) + " is not symmetric");
      if (origin(o) != target(c) || target(o) != origin(c))
        return fail("opposite of corner " + std::to_string(c) + " does not run the other way");
      if (corner_edge_[o] != edge) return fail("corners of edge " + std::to_string(edge) + " disagree");
    }
  }
  if (triangles != alive_triangles_) return fail("alive triangle count is wrong");
  std::sort(sorted_triangles.begin(), sorted_triangles.end());
  if (std::adjacent_find(sorted_triangles.begin(), sorted_triangles.end()) != sorted_triangles.end())
    return fail("two triangles share all three vertices");
  for (std::uint32_t e = 0; e < edge_halfedge_.size(); ++e) {
    const std::uint32_t h = edge_halfedge_[e];
    if (h == kNone) continue;
    if (h >= corner_count || corner_vertex_[h] == kNone || corner_edge_[h] != e)
      return fail("edge " + std::to_string(e) + " points to a wrong corner");
  }
  std::size_t vertices = 0;
  std::vector<std::uint32_t> loop_count(loop_size_.size(), 0);
  for (std::uint32_t v = 0; v < positions_.size(); ++v) {
    if (!vertex_alive(v)) {
      if (corners_at[v] != 0) return fail("deleted vertex " + std::to_string(v) + " is used");
      continue;
    }
    ++vertices;
    if (corners_at[v] == 0) return fail("vertex " + std::to_string(v) + " has no triangle");
    const std::uint32_t start = vertex_halfedge_[v];
    if (corner_vertex_[start] != v) return fail("vertex " + std::to_string(v) + " has a wrong half-edge");
    const bool boundary = opposite_[start] == kNone;
    if (boundary != is_boundary(v)) return fail("boundary flag of vertex " + std::to_string(v) + " is wrong");
    std::vector<std::uint32_t> neighbours;
    std::uint32_t fan = 0, last = start;
    for_each_corner(v, [&](std::uint32_t c) {
      ++fan;
      neighbours.push_back(target(c));
      last = c;
    });
    if (boundary) neighbours.push_back(corner_vertex_[prev(last)]);
    if (fan != corners_at[v]) return fail("vertex " + std::to_string(v) + " is not a single fan (non-manifold)");
    if (valence_[v] != neighbours.size()) return fail("valence of vertex " + std::to_string(v) + " is wrong");
    std::sort(neighbours.begin(), neighbours.end());
    if (std::adjacent_find(neighbours.begin(), neighbours.end()) != neighbours.end())
      return fail("vertex " + std::to_string(v) + " has a duplicate edge");
    if (boundary) {
      if (boundary_loop_[v] >= loop_size_.size()) return fail("boundary vertex " + std::to_string(v) + " has no loop");
      ++loop_count[boundary_loop_[v]];
      if (boundary_loop_[target(start)] != boundary_loop_[v]) return fail("boundary loop ids disagree");
    }
  }
  if (vertices != alive_vertices_) return fail("alive vertex count is wrong");
  for (std::size_t l = 0; l < loop_size_.size(); ++l) {
    if (loop_count[l] != loop_size_[l]) return fail("boundary loop " + std::to_string(l) + " has a wrong size");
    if (loop_count[l] < 3) return fail("boundary loop " + std::to_string(l) + " has fewer than 3 vertices");
  }
  return {};
}

PolygonMesh CollapseMesh::to_polygon_mesh(std::vector<std::uint32_t>* vertex_map) const {
  std::vector<std::uint32_t> map(positions_.size(), kNone);
  PolygonMesh result;
  result.positions.reserve(alive_vertices_);
  for (std::uint32_t v = 0; v < positions_.size(); ++v) {
    if (!vertex_alive(v)) continue;
    map[v] = static_cast<std::uint32_t>(result.positions.size());
    result.positions.push_back(positions_[v]);
    if (input_had_sharp_) result.sharp.push_back(is_sharp(v) ? 1 : 0);
  }
  result.face_vertices.reserve(3 * alive_triangles_);
  result.face_offsets.reserve(alive_triangles_ + 1);
  for (std::uint32_t t = 0; t < corner_vertex_.size() / 3; ++t) {
    if (corner_vertex_[3 * t] == kNone) continue;
    result.add_face({map[corner_vertex_[3 * t]], map[corner_vertex_[3 * t + 1]], map[corner_vertex_[3 * t + 2]]});
  }
  if (vertex_map) *vertex_map = std::move(map);
  return result;
}

std::vector<CollapseMesh::ComponentCounts> CollapseMesh::components() const {
  std::vector<std::uint32_t> parent(positions_.size());
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::uint32_t t = 0; t < corner_vertex_.size() / 3; ++t) {
    if (corner_vertex_[3 * t] == kNone) continue;
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t r = find(corner_vertex_[3 * t]);
      const std::uint32_t s = find(corner_vertex_[3 * t + k]);
      if (s != r) parent[std::max(r, s)] = std::min(r, s);
    }
  }
  std::vector<std::uint32_t> label(positions_.size(), kNone);
  std::vector<ComponentCounts> counts;
  for (std::uint32_t v = 0; v < positions_.size(); ++v) {
    if (!vertex_alive(v)) continue;
    const std::uint32_t root = find(v);
    if (label[root] == kNone) {
      label[root] = static_cast<std::uint32_t>(counts.size());
      counts.emplace_back();
    }
    ++counts[label[root]].vertices;
  }
  for (std::uint32_t t = 0; t < corner_vertex_.size() / 3; ++t)
    if (corner_vertex_[3 * t] != kNone) ++counts[label[find(corner_vertex_[3 * t])]].faces;
  for (std::uint32_t e = 0; e < edge_halfedge_.size(); ++e)
    if (edge_alive(e)) ++counts[label[find(corner_vertex_[edge_halfedge_[e]])]].edges;
  std::vector<std::uint8_t> loop_seen(loop_size_.size(), 0);
  for (std::uint32_t v = 0; v < positions_.size(); ++v) {
    if (!vertex_alive(v) || !is_boundary(v) || loop_seen[boundary_loop_[v]]) continue;
    loop_seen[boundary_loop_[v]] = 1;
    ++counts[label[find(v)]].boundary_loops;
  }
  return counts;
}

}  // namespace isowave::simplify
