#pragma once
// Private: the sharp-feature rules of Sec. 3.4 that both refinement builders
// (refinement_steps.cpp and the OpenSubdiv reference) apply.
#include <cstdint>

#include "isowave/transform/hierarchy.h"

namespace isowave::detail {

// A vertex is sharp if flagged or on three or more sharp (here: boundary)
// edges, a crease vertex on exactly two, smooth otherwise; an edge is smooth
// unless it is sharp or ends at a sharp vertex.
inline VertexRule vertex_rule(bool flagged_sharp, std::uint32_t sharp_edges) {
  if (flagged_sharp || sharp_edges >= 3) return VertexRule::Sharp;
  return sharp_edges == 2 ? VertexRule::Crease : VertexRule::Smooth;
}
inline bool edge_is_smooth(bool sharp, VertexRule first_end, VertexRule second_end) {
  return !sharp && first_end != VertexRule::Sharp && second_end != VertexRule::Sharp;
}

}  // namespace isowave::detail
