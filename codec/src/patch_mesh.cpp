#include "patch_mesh.h"

#include "isowave/transform/adaptive_mesh.h"

namespace isowave::detail {

// Whether patch face f and its edge neighbours are all at level 0.
namespace {

bool coarse_with_neighbours(const SubdivisionHierarchy& h, const std::vector<int>& levels, std::size_t f) {
  if (levels[f] != 0) return false;
  if (h.levels() == 0) return true;
  const RefinementStep& s = h.step(1);
  for (std::uint32_t k = s.face_offsets[f]; k < s.face_offsets[f + 1]; ++k) {
    const std::uint32_t e = s.face_edges[k] - s.first_edge_vertex();
    for (int side = 0; side < 2; ++side)
      if (levels[s.edge_faces[2 * std::size_t{e} + side] - s.first_face_vertex()] != 0) return false;
  }
  return true;
}

}  // namespace

PolygonMesh patch_mesh(const PatchDomain& d, const PolygonMesh& base, const std::vector<Vec3>& base_points,
                       std::size_t whole_entries, const std::vector<int>& levels, const std::vector<Vec3>& fine,
                       BaseCorners corners_at) {
  constexpr std::uint32_t kNone = UINT32_MAX;
  std::vector<std::uint32_t> local_face(base.face_count(), kNone);
  for (std::size_t f = 0; f < levels.size(); ++f) local_face[d.face(f)] = static_cast<std::uint32_t>(f);
  // The base vertices that take their fine points.
  std::vector<std::uint8_t> fine_corner(base.vertex_count(), 0);
  for (std::size_t f = 0; f < levels.size(); ++f)
    if (corners_at == BaseCorners::ExactFaces ? d.is_exact(f) : levels[f] > 0)
      for (std::uint32_t k = d.h.base().face_offsets[f]; k < d.h.base().face_offsets[f + 1]; ++k)
        fine_corner[d.entry(d.h.base().face_vertices[k])] = 1;
  // Faces, their corners keyed by whole entries; per key, its patch entry
  // (kBase: a corner of whole base faces only).
  constexpr std::uint32_t kBase = UINT32_MAX - 1;
  std::vector<std::uint32_t> slot(whole_entries, kNone);
  PolygonMesh out;
  std::vector<std::uint32_t> offsets, corners;
  for (std::size_t g = 0; g < base.face_count(); ++g) {
    const std::uint32_t f = local_face[g];
    if (f == kNone) {
      for (const std::uint32_t* v = base.face_begin(g); v != base.face_begin(g) + base.face_size(g); ++v) {
        if (slot[*v] == kNone) slot[*v] = kBase;
        out.face_vertices.push_back(*v);
      }
      out.face_offsets.push_back(static_cast<std::uint32_t>(out.face_vertices.size()));
      continue;
    }
    if (coarse_with_neighbours(d.h, levels, f)) {  // the patch's base polygon, the same corners
      const PolygonMesh& mine = d.h.base();
      for (std::uint32_t k = mine.face_offsets[f]; k < mine.face_offsets[f + 1]; ++k) {
        slot[d.entry(mine.face_vertices[k])] = mine.face_vertices[k];
        out.face_vertices.push_back(d.entry(mine.face_vertices[k]));
      }
      out.face_offsets.push_back(static_cast<std::uint32_t>(out.face_vertices.size()));
      continue;
    }
    offsets = {0};
    corners.clear();
    adaptive_patch(d.h, levels, f, offsets, corners);
    for (std::size_t p = 0; p + 1 < offsets.size(); ++p) {
      for (std::uint32_t k = offsets[p]; k < offsets[p + 1]; ++k) {
        const std::uint32_t key = d.entry(corners[k]);
        slot[key] = corners[k];
        out.face_vertices.push_back(key);
      }
      out.face_offsets.push_back(static_cast<std::uint32_t>(out.face_vertices.size()));
    }
  }
  // The vertices used, in the order of their entries.
  std::uint32_t next = 0;
  for (std::size_t key = 0; key < slot.size(); ++key) {
    if (slot[key] == kNone) continue;
    const bool base_only = key < base.vertex_count() && !fine_corner[key];
    out.positions.push_back(base_only ? base_points[key] : fine[slot[key]]);
    slot[key] = next++;
  }
  for (std::uint32_t& v : out.face_vertices) v = slot[v];
  return out;
}

}  // namespace isowave::detail
