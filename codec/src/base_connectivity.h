#pragma once
// Private: the base mesh's connectivity coder — a polygon cut-border machine
// (Gumhold & Strasser 1998's cut-border machine extended to polygons and holes,
// as in Isenburg & Snoeyink's Face Fixer 2000).
//
// Every boundary loop of the mesh is closed by a virtual "hole" face, so each
// component is a closed surface. A component grows from a seed face; the
// processed faces are bounded by border loops of half-edges ("slots"). The
// face across the current gate slot is coded as: hole or not, its size, how
// many border slots it consumes backward and forward of the gate, and for each
// remaining corner whether it is a new vertex or an existing one -- given by
// the border slot whose wedge it lies in (by distance along the border when
// near the gate, else by age), with the slots the face consumes from there: a
// split of the loop or, for a handle, a merge of two. The gate then moves to
// the next slot along the border (a spiral), or to a pending loop.
//
// The decoder reproduces the mesh exactly, which fixes the numbering:
// canonical_order() renumbers vertices in order of first appearance, faces in
// traversal order and rotates each face to start at the gate's end vertex.
#include <cstdint>
#include <vector>

#include "isowave/core/mesh.h"
#include "range_coder.h"

namespace isowave::detail {

struct CanonicalMesh {
  PolygonMesh mesh;                          // the same mesh in the coder's order
  std::vector<std::uint32_t> new_of_old;     // vertex permutation: old index -> new index
};

// Renumbers vertices and faces of a mesh that passed require_manifold() into
// the traversal's order; positions and sharp flags move with their vertices
// (sharp is empty when no vertex is sharp). Components are seeded at their
// first face in the input order, so the result is a fixed point:
// canonical_order(canonical_order(m).mesh).mesh == canonical_order(m).mesh.
// O(vertices + corners) for bounded valences.
CanonicalMesh canonical_order(const PolygonMesh& mesh);

// True when canonical_order(mesh) would return `mesh` unchanged (positions
// aside). Runs the traversal once without building a mesh.
bool is_canonical(const PolygonMesh& mesh);

// The counts a container stores beside the coded stream (e.g. a section
// header); the decoder checks the stream against them.
struct ConnectivityCounts {
  std::uint64_t vertices = 0;
  std::uint64_t faces = 0;
  std::uint64_t corners = 0;
};
ConnectivityCounts connectivity_counts(const PolygonMesh& mesh);

// Codes the faces and sharp flags (not positions) of a mesh for which
// is_canonical() holds; throws Error(InvalidArgument) otherwise. The caller
// finishes the range coder. About 2-4 bits per vertex on quad-dominant meshes.
void encode_connectivity(RangeEncoder& rc, const PolygonMesh& canonical);

// Decodes what encode_connectivity() wrote: the mesh with every position at
// the origin, identical otherwise (faces, corner order, sharp flags). The
// bytes are hostile: nothing is allocated ahead of decoded data, the stream
// is abandoned as soon as the decoder reads past its end (time linear in the
// input), and anything inconsistent -- counts other than `expected`, a
// result that fails require_manifold() -- throws Error(Format).
PolygonMesh decode_connectivity(RangeDecoder& rc, const ConnectivityCounts& expected);

}  // namespace isowave::detail
