#pragma once
// Edge-removal pass of paper Sec. 4.1 on OpenMesh's polygon halfedge mesh
// (private: keeps OpenMesh out of the public headers). Rules and priority are
// documented in isowave/simplify/simplify.h.
#include <cstddef>

#include "isowave/core/mesh.h"

namespace isowave::simplify {

// Merges faces of `mesh` (a consistently oriented 2-manifold) in place;
// returns the number of edges removed. Vertex indices are unchanged; faces
// are renumbered. O(n log n) in the number of edges.
std::size_t remove_edges(PolygonMesh& mesh, double min_normal_dot);

}  // namespace isowave::simplify
