#pragma once
// The subdivision hierarchy of a patch of the base mesh, its entries numbered
// back to the whole hierarchy's (issue #48, item 5: a region decode that
// builds only what it reads). A patch is a set of base faces; its hierarchy
// has the same rules as the whole one wherever a vertex's faces all lie in
// the patch, in the same order (a patch keeps the base's face order and
// each face's corner order), so the synthesis of a fine control point equals
// the whole hierarchy's, bit for bit, once the patch holds every face within
// kExactRings rings of the point's base face. The patch's own boundary is a
// boundary of its hierarchy (crease rules): points nearer to it differ.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// Rings of base faces (vertex neighbours) around a base face within which
// the patch must hold every face for the face's fine control points to
// equal the whole hierarchy's: a level's six lifting steps (Sec. 3.3) read
// about two rings of that level's faces, one of its parent's, so the levels
// together reach below two base rings, and the patch's boundary rules reach
// as far in. One ring is not enough (tests/transform/test_patch_hierarchy.cpp).
constexpr int kExactRings = 2;

// The base mesh's incidences as the whole hierarchy numbers them: its faces
// per vertex (ascending) and its edges (numbered and oriented as
// SubdivisionHierarchy numbers level 0's). Cost: O(corners); the mesh must
// be one SubdivisionHierarchy accepts (else Error(Topology)).
struct BaseIncidence {
  std::vector<std::uint32_t> vertex_face_offsets, vertex_faces;
  std::vector<std::uint32_t> face_edges;      // per corner: the edge from it to the next corner
  std::vector<std::uint32_t> edge_vertices;   // 2 per edge, in its orientation
  std::vector<std::uint32_t> edge_faces;      // 2 per edge; a boundary edge lists its face twice
  std::size_t edge_count() const { return edge_vertices.size() / 2; }
};
BaseIncidence base_incidence(const PolygonMesh& base);

// Adds to `in_patch` (one flag per base face) every face that shares a vertex
// with a flagged one, `rings` times, then every face around each vertex whose
// flagged faces would not form one fan (so that the patch is a manifold).
// Returns the flagged faces, ascending. Cost: O(corners of the result) per
// ring, plus O(faces) for the list.
std::vector<std::uint32_t> grow_patch(const PolygonMesh& base, const BaseIncidence& incidence,
                                      std::vector<std::uint8_t>& in_patch, int rings);

class PatchHierarchy {
 public:
  // `faces`: base faces of `base`, ascending, forming a manifold (as
  // grow_patch() leaves them). Throws what SubdivisionHierarchy throws.
  // Cost: the patch's hierarchy plus O(its fine vertices).
  PatchHierarchy(const PolygonMesh& base, const BaseIncidence& incidence, std::vector<std::uint32_t> faces, int levels);

  const SubdivisionHierarchy& hierarchy() const { return hierarchy_; }
  // Patch base face -> base face; patch base vertex -> base vertex.
  const std::vector<std::uint32_t>& faces() const { return faces_; }
  const std::vector<std::uint32_t>& base_vertices() const { return vertices_; }
  // Patch entry (fine vertex) -> the whole hierarchy's entry of `base` at
  // `levels` (the coarse-to-fine array's index).
  const std::vector<std::uint32_t>& entries() const { return entries_; }

 private:
  std::vector<std::uint32_t> faces_, vertices_, entries_;
  SubdivisionHierarchy hierarchy_;
};

}  // namespace isowave
