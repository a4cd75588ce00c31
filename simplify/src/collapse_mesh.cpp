// The collapse itself with the paper's error propagation (Sec. 4.1), the
// Fig. 8 update stencil, the region test of the two-thread phases, the
// invariant check and the output.
#include <algorithm>
#include <array>
#include <cassert>
#include <limits>
#include <numeric>
#include <string>
#include <tuple>
#include <vector>

#include "collapse_mesh_internal.h"
#include "surface_map_tracker.h"

namespace isowave::simplify {

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

void CollapseMesh::reset_vertex_halfedge(std::uint32_t v, std::uint32_t start) {
  assert(start != kNone && corners_[start].vertex == v);
  if (is_boundary(v))
    while (corners_[start].opposite != kNone) start = next(corners_[start].opposite);  // clockwise to the boundary
  vertices_[v].halfedge = start;
}

std::uint32_t CollapseMesh::collapse(std::uint32_t e, const Vec3& position, std::uint32_t removed_edges[3],
                                     std::uint32_t opposite_vertices[2], int lane) {
  if (map_tracker_) map_tracker_->before_collapse(*this, e, position, lane);
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
  if (!vertex_area_.empty()) vertex_area_[vi] += vertex_area_[vj];
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

  if (map_tracker_) map_tracker_->after_collapse(*this, vi, lane);
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
