#include "isowave/codec/base_order.h"

#include <cassert>
#include <unordered_map>

#include "base_connectivity.h"

namespace isowave {

namespace {

// A face of one hierarchy level and the face it is in the other, with the
// other's corner that this face's corner 0 is.
struct FaceMatch {
  std::uint32_t face = 0;
  std::uint32_t rotation = 0;
};

std::uint64_t directed(std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; }

// Base faces of `from` matched in `to`, given the base vertex map, by a
// directed edge each (unique in an oriented manifold).
std::vector<FaceMatch> match_base_faces(const PolygonMesh& from, const PolygonMesh& to,
                                        const std::vector<std::uint32_t>& vertex_map) {
  std::unordered_map<std::uint64_t, FaceMatch> by_edge;
  by_edge.reserve(to.face_vertices.size());
  for (std::uint32_t f = 0; f < to.face_count(); ++f) {
    const std::uint32_t* v = to.face_begin(f);
    const std::uint32_t n = to.face_size(f);
    for (std::uint32_t k = 0; k < n; ++k) by_edge[directed(v[k], v[(k + 1) % n])] = {f, k};
  }
  std::vector<FaceMatch> matches(from.face_count());
  for (std::uint32_t f = 0; f < from.face_count(); ++f) {
    const std::uint32_t* v = from.face_begin(f);
    const auto it = by_edge.find(directed(vertex_map[v[0]], vertex_map[v[1]]));
    assert(it != by_edge.end() && to.face_size(it->second.face) == from.face_size(f));
    matches[f] = it->second;
  }
  return matches;
}

// One refinement: extends the vertex map to the next level and matches its
// faces. A quad's child face is rotated so that its parent corner sits at
// that corner's index (refinement_steps.cpp), so it inherits the parent's
// rotation; any other polygon's child starts at its corner (rotation 0).
std::vector<FaceMatch> refine_matches(const RefinementStep& a, const RefinementStep& b,
                                      const std::vector<FaceMatch>& faces, std::vector<std::uint32_t>& vertex_map) {
  vertex_map.resize(a.child_vertex_count());
  std::vector<FaceMatch> children(a.face_vertices.size());
  for (std::uint32_t f = 0; f < a.parent_face_count; ++f) {
    const FaceMatch m = faces[f];
    const std::uint32_t first_a = a.face_offsets[f], first_b = b.face_offsets[m.face];
    const std::uint32_t n = a.face_offsets[f + 1] - first_a;
    vertex_map[a.first_face_vertex() + f] = b.first_face_vertex() + m.face;
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t kb = (k + m.rotation) % n;
      assert(vertex_map[a.face_vertices[first_a + k]] == b.face_vertices[first_b + kb]);
      vertex_map[a.face_edges[first_a + k]] = b.face_edges[first_b + kb];
      children[first_a + k] = {first_b + kb, n == 4 ? m.rotation : 0};
    }
  }
  return children;
}

}  // namespace

CanonicalSurface canonical_surface(const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
                                   std::vector<Vec3> fine) {
  const PolygonMesh& base = hierarchy->base();
  if (detail::is_canonical(base)) {
    std::vector<std::uint32_t> identity(base.vertex_count());
    for (std::size_t v = 0; v < identity.size(); ++v) identity[v] = static_cast<std::uint32_t>(v);
    return {hierarchy, std::move(fine), std::move(identity)};
  }
  detail::CanonicalMesh canonical = detail::canonical_order(base);
  auto ordered = std::make_shared<const SubdivisionHierarchy>(canonical.mesh, hierarchy->levels());
  std::vector<std::uint32_t> vertex_map = std::move(canonical.new_of_old);
  std::vector<FaceMatch> faces = match_base_faces(base, ordered->base(), vertex_map);
  for (int level = 1; level <= hierarchy->levels(); ++level)
    faces = refine_matches(hierarchy->step(level), ordered->step(level), faces, vertex_map);
  std::vector<Vec3> moved(ordered->fine_vertex_count());
  for (std::size_t i = 0; i < moved.size(); ++i) moved[vertex_map[i]] = fine[i];
  std::vector<std::uint32_t> base_order(vertex_map.begin(), vertex_map.begin() + static_cast<std::ptrdiff_t>(base.vertex_count()));
  return {std::move(ordered), std::move(moved), std::move(base_order)};
}

}  // namespace isowave
