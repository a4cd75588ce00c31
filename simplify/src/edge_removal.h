#pragma once
// Edge-removal pass of paper Sec. 4.1 on the corner table of the collapsed
// triangles (private). Rules and priority are documented in
// isowave/simplify/simplify.h.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "isowave/core/mesh.h"

namespace isowave::simplify {

// Merges faces of `mesh` (a consistently oriented 2-manifold of triangles
// without unreferenced vertices) in place; returns the number of edges
// removed. Vertex indices are unchanged; faces are renumbered. The paper's
// bucket queue (kBucketCount buckets over the priority range, first in first
// out inside one): O(1) per queue update, O(n) in all.
// `triangle_face`, if given, receives per input triangle the output face it
// became part of.
std::size_t remove_edges(PolygonMesh& mesh, double min_normal_dot, std::vector<std::uint32_t>* triangle_face = nullptr);

}  // namespace isowave::simplify
