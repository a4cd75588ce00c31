#pragma once
// Polygon mesh shared by every stage: positions, faces of 3 or more vertices
// and optional per-vertex sharp flags.
//
// Faces are stored as flat index arrays (compressed rows: face f has the
// vertices face_vertices[face_offsets[f] .. face_offsets[f+1])) rather than as
// a vector of vectors: one allocation for millions of faces, and streaming
// loops touch contiguous memory.
#include <cstdint>
#include <string>
#include <vector>

#include "isowave/core/vec3.h"

namespace isowave {

struct PolygonMesh {
  std::vector<Vec3> positions;  // world coordinates (the volume's units); finite (validate_indices)
  std::vector<std::uint32_t> face_offsets{0};  // face_count() + 1 entries, first is 0, non-decreasing
  std::vector<std::uint32_t> face_vertices;    // vertex indices < vertex_count(), in orientation order
  // Empty (no vertex is sharp) or one entry per vertex: 1 = sharp.
  std::vector<std::uint8_t> sharp;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t face_count() const { return face_offsets.size() - 1; }
  std::uint32_t face_size(std::size_t f) const { return face_offsets[f + 1] - face_offsets[f]; }
  const std::uint32_t* face_begin(std::size_t f) const { return face_vertices.data() + face_offsets[f]; }
  bool is_sharp(std::size_t v) const { return !sharp.empty() && sharp[v] != 0; }
  std::size_t sharp_count() const;

  // Appends a face; indices are not checked here (see validate_indices()).
  void add_face(const std::uint32_t* vertices, std::size_t count);
  void add_face(std::initializer_list<std::uint32_t> vertices) { add_face(vertices.begin(), vertices.size()); }
  void clear();
};

// Throws Error(Format) naming `source` if a face has fewer than 3 vertices,
// an index is out of range, a position is not finite, or the sharp array has
// the wrong size. O(vertices + corners).
void validate_indices(const PolygonMesh& mesh, const std::string& source);

// Drops vertices no face references, renumbering the rest in order.
// Returns how many were removed. O(vertices + corners).
std::size_t remove_unreferenced_vertices(PolygonMesh& mesh);

// How triangulate() splits quads.
enum class QuadSplit {
  Shorter,  // along the shorter diagonal (a refined level's quads: no diagonal is another face's edge)
  // Along the shorter diagonal unless it is an edge of the mesh or another
  // quad's diagonal, then the other, and failing both around a centroid
  // (base faces may share two corners). O(corners log corners) more.
  ShorterAvoidingEdges,
};

// Splits every face into triangles, keeping orientation, vertices and sharp
// flags: quads as `split` says, larger polygons as a fan around a new vertex
// at their centroid (appended, not sharp). O(corners).
PolygonMesh triangulate(const PolygonMesh& mesh, QuadSplit split = QuadSplit::Shorter);

}  // namespace isowave
