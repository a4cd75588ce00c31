#pragma once
// Connectivity of one level of a subdivision hierarchy's control mesh as the
// shrink-wrap (shrink_wrap.h) needs it, with each vertex's role and the box
// face it is held on.
//
// Boundaries: an extracted isosurface's boundary lies on the faces of the
// volume's box. A boundary vertex within one cell of a box face is held on
// that face (Box-held): the steps keep it in the face plane, so it slides
// along its boundary curve. Every vertex is kept inside the box.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

enum class WrapRole : std::uint8_t {
  Free = 0,      // interior vertex
  Boundary = 1,  // on two boundary edges: follows its boundary curve
  Fixed = 2,     // sharp, or on three or more boundary edges: never moves
};

// Flat arrays (compressed rows): millions of vertices at the finest level,
// visited in parallel many times per round. About 60 bytes per vertex.
struct WrapLevelMesh {
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  int level = 0;
  std::size_t vertex_count = 0;
  // Neighbours of vertex v: neighbours[neighbour_offsets[v] .. neighbour_offsets[v+1]).
  std::vector<std::uint32_t> neighbour_offsets, neighbours;
  // Faces (the control mesh's, same order) and, per vertex, its faces ascending.
  std::vector<std::uint32_t> face_offsets, face_vertices;
  std::vector<std::uint32_t> vertex_face_offsets, vertex_faces;
  std::vector<WrapRole> role;
  // Per vertex: its two neighbours along boundary edges (kNone if interior).
  std::vector<std::uint32_t> boundary_neighbours;
  // Per vertex: the box face it is held on, axis * 2 + (0 low, 1 high), or -1.
  std::vector<std::int8_t> box_face;

  std::size_t face_count() const { return face_offsets.size() - 1; }
};

// Connectivity of level `level` (0 .. hierarchy.levels()) of the hierarchy.
// Box faces come from `positions` (at least vertex_count(level) of them) and
// the box of `box` (world units): a boundary vertex is held on the nearest
// face within one cell. One on a box edge is held on a face in which the
// isosurface `iso` of the volume's field comes within two cells of it
// (across the edge), so that it can follow the boundary curve there; of two,
// the one its neighbours lie along; with iso NaN (the volume may then have
// no samples) or no such face, the last in the order x low, x high, y low, ...
// Throws Error(InvalidArgument) for a level outside the hierarchy or too few
// positions. O(vertices) for level >= 1, O(n log n) for the base.
WrapLevelMesh make_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, int level,
                                   const std::vector<Vec3>& positions, const Volume& box,
                                   double iso = std::numeric_limits<double>::quiet_NaN());

// Moves box-held vertices onto their face and every movable vertex into the
// box, in place. O(vertices).
void constrain_to_box(const WrapLevelMesh& mesh, const Volume& box, std::vector<Vec3>& positions);

}  // namespace isowave
