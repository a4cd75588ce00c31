#include "isowave/transform/adaptive_mesh.h"

#include <algorithm>
#include <cstdint>
#include <string>
#include <unordered_map>

#include "isowave/core/error.h"

namespace isowave {

namespace {

using Chain = std::vector<std::uint32_t>;

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t{a} << 32) | b : (std::uint64_t{b} << 32) | a;
}

// The e vertex (a level + 1 index) of the level-`level` edge (u, w): among
// u's incident edges' e vertices, the one whose edge joins u and w.
std::uint32_t edge_child(const SubdivisionHierarchy& h, int level, std::uint32_t u, std::uint32_t w) {
  const RefinementStep& s = h.step(level + 1);
  for (std::uint32_t k = s.vertex_edge_offsets[u]; k < s.vertex_edge_offsets[u + 1]; ++k) {
    const std::uint32_t e = s.vertex_edges[k], edge = e - s.first_edge_vertex();
    const std::uint32_t a = s.edge_vertices[2 * std::size_t{edge}], b = s.edge_vertices[2 * std::size_t{edge} + 1];
    if ((a == u && b == w) || (a == w && b == u)) return e;
  }
  throw Error(ErrorKind::InvalidArgument, "adaptive mesh: an edge without a child (inconsistent hierarchy)");
}

// The vertices along the level-`from` edge (u, w) at level `to`, u first and w last.
void edge_chain(const SubdivisionHierarchy& h, int from, int to, std::uint32_t u, std::uint32_t w, Chain& out) {
  if (from == to) {
    if (out.empty()) out.push_back(u);
    out.push_back(w);
    return;
  }
  const std::uint32_t e = edge_child(h, from, u, w);
  edge_chain(h, from + 1, to, u, e, out);
  edge_chain(h, from + 1, to, e, w, out);
}

// Calls emit(corners, count) for each level-`level` face of base face f.
template <class Emit>
void for_each_patch_face(const SubdivisionHierarchy& h, std::size_t f, int level, const Emit& emit) {
  if (level == 0) {
    emit(h.base().face_begin(f), h.base().face_size(f));
    return;
  }
  // Each parent face with n corners splits into n quads: corner k, the e
  // vertex of edge k, the f vertex, the e vertex of edge k - 1 (as control_mesh()).
  const RefinementStep& s = h.step(level);
  const auto [first, end] = h.descendant_faces(f, level - 1);
  for (std::size_t p = first; p < end; ++p) {
    const std::uint32_t row = s.face_offsets[p], row_end = s.face_offsets[p + 1];
    for (std::uint32_t k = row; k < row_end; ++k) {
      const std::uint32_t previous = k == row ? row_end - 1 : k - 1;
      const std::uint32_t quad[4] = {s.face_vertices[k], s.face_edges[k], s.first_face_vertex() + std::uint32_t(p),
                                     s.face_edges[previous]};
      emit(quad, 4u);
    }
  }
}

using Insertions = std::unordered_map<std::uint64_t, Chain>;

// Base edge `edge` (a step-1 parent edge) between faces at two levels: per
// coarse-side edge along it, the finer side's vertices strictly between its
// ends, ordered from the smaller index to the larger, into `inserted`.
void add_transition(const SubdivisionHierarchy& h, const std::vector<int>& levels, std::uint32_t edge,
                    Insertions& inserted) {
  const RefinementStep& s = h.step(1);
  const std::uint32_t f = s.edge_faces[2 * std::size_t{edge}] - s.first_face_vertex();
  const std::uint32_t g = s.edge_faces[2 * std::size_t{edge} + 1] - s.first_face_vertex();
  const int coarse = std::min(levels[f], levels[g]), fine = std::max(levels[f], levels[g]);
  if (f == g || coarse == fine) return;
  const std::uint32_t a = s.edge_vertices[2 * std::size_t{edge}], b = s.edge_vertices[2 * std::size_t{edge} + 1];
  Chain coarse_chain, fine_chain;
  edge_chain(h, 0, coarse, a, b, coarse_chain);
  edge_chain(h, 0, fine, a, b, fine_chain);
  // The coarse chain's vertices recur in the fine chain every 2^(fine - coarse) steps.
  const std::size_t stride = std::size_t{1} << (fine - coarse);
  for (std::size_t k = 0; k + 1 < coarse_chain.size(); ++k) {
    Chain between(fine_chain.begin() + std::ptrdiff_t(k * stride + 1), fine_chain.begin() + std::ptrdiff_t((k + 1) * stride));
    if (coarse_chain[k] > coarse_chain[k + 1]) std::reverse(between.begin(), between.end());
    inserted.emplace(edge_key(coarse_chain[k], coarse_chain[k + 1]), std::move(between));
  }
}

// Base face f's faces at its level, a coarse face's edge along a finer
// neighbour taking that neighbour's vertices on it (`inserted`), appended
// to `offsets` (each polygon's end) and `corners` (fine vertex indices).
void emit_patch(const SubdivisionHierarchy& h, std::size_t f, int level, const Insertions& inserted,
                std::vector<std::uint32_t>& offsets, std::vector<std::uint32_t>& corners) {
  for_each_patch_face(h, f, level, [&](const std::uint32_t* c, std::uint32_t n) {
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t u = c[k], w = c[(k + 1) % n];
      corners.push_back(u);
      const auto it = inserted.find(edge_key(u, w));
      if (it == inserted.end()) continue;
      if (u < w) corners.insert(corners.end(), it->second.begin(), it->second.end());
      else corners.insert(corners.end(), it->second.rbegin(), it->second.rend());
    }
    offsets.push_back(static_cast<std::uint32_t>(corners.size()));
  });
}

void check_levels(const SubdivisionHierarchy& hierarchy, const std::vector<int>& levels) {
  const std::size_t base_faces = hierarchy.base().face_count();
  if (levels.size() != base_faces)
    throw Error(ErrorKind::InvalidArgument, "adaptive mesh: " + std::to_string(levels.size()) + " levels for " +
                                                std::to_string(base_faces) + " base faces");
  for (const int l : levels)
    if (l < 0 || l > hierarchy.levels())
      throw Error(ErrorKind::InvalidArgument, "adaptive mesh: a level outside 0.." + std::to_string(hierarchy.levels()));
}

}  // namespace

void adaptive_patch(const SubdivisionHierarchy& hierarchy, const std::vector<int>& levels, std::size_t base_face,
                    std::vector<std::uint32_t>& offsets, std::vector<std::uint32_t>& corners) {
  // The face's and its neighbours' levels only: O(1) per call.
  const auto in_range = [&](std::size_t f) { return f < levels.size() && levels[f] >= 0 && levels[f] <= hierarchy.levels(); };
  if (levels.size() != hierarchy.base().face_count() || !in_range(base_face))
    throw Error(ErrorKind::InvalidArgument, "adaptive mesh: no such base face, or its level out of range");
  if (hierarchy.levels() > 0) {
    const RefinementStep& s = hierarchy.step(1);
    for (std::uint32_t k = s.face_offsets[base_face]; k < s.face_offsets[base_face + 1]; ++k) {
      const std::uint32_t edge = s.face_edges[k] - s.first_edge_vertex();
      for (int side = 0; side < 2; ++side)
        if (!in_range(s.edge_faces[2 * std::size_t{edge} + side] - s.first_face_vertex()))
          throw Error(ErrorKind::InvalidArgument, "adaptive mesh: a neighbour's level out of range");
    }
  }
  Insertions inserted;
  if (hierarchy.levels() > 0) {
    // The transitions along this face's own base edges only.
    const RefinementStep& s = hierarchy.step(1);
    for (std::uint32_t k = s.face_offsets[base_face]; k < s.face_offsets[base_face + 1]; ++k)
      add_transition(hierarchy, levels, s.face_edges[k] - s.first_edge_vertex(), inserted);
  }
  emit_patch(hierarchy, base_face, levels[base_face], inserted, offsets, corners);
}

PolygonMesh adaptive_control_mesh(const SubdivisionHierarchy& hierarchy, const std::vector<int>& levels,
                                  const std::vector<Vec3>& fine) {
  check_levels(hierarchy, levels);
  if (fine.size() < hierarchy.fine_vertex_count())
    throw Error(ErrorKind::InvalidArgument, "adaptive mesh: fewer points than the fine level");
  Insertions inserted;
  if (hierarchy.levels() > 0)
    for (std::uint32_t edge = 0; edge < hierarchy.step(1).parent_edge_count; ++edge)
      add_transition(hierarchy, levels, edge, inserted);
  PolygonMesh out;
  out.face_offsets = {0};
  for (std::size_t f = 0; f < levels.size(); ++f)
    emit_patch(hierarchy, f, levels[f], inserted, out.face_offsets, out.face_vertices);
  // Only the vertices the faces use, in ascending index order.
  std::vector<std::uint32_t> new_index(hierarchy.fine_vertex_count(), UINT32_MAX);
  for (const std::uint32_t v : out.face_vertices) new_index[v] = 0;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < new_index.size(); ++v)
    if (new_index[v] == 0) {
      new_index[v] = next++;
      out.positions.push_back(fine[v]);
    }
  for (std::uint32_t& v : out.face_vertices) v = new_index[v];
  return out;
}

}  // namespace isowave
