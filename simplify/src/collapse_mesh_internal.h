#pragma once
// Private to the CollapseMesh files (collapse_table.cpp, legality.cpp,
// valence_flips.cpp, collapse_mesh.cpp): scratch sizes and the fan walk.
#include <cstdint>

#include "isowave/simplify/collapse_mesh.h"

namespace isowave::simplify {

// Valences seen inside evaluate()/collapse() are bounded by the valence rule
// (N_i + N_j - 3 <= max_valence), so fixed-size scratch arrays suffice.
inline constexpr int kMaxRing = 48;

template <typename Visit>
void CollapseMesh::for_each_corner(std::uint32_t v, Visit&& visit) const {
  const std::uint32_t start = vertices_[v].halfedge;
  std::uint32_t c = start;
  do {
    visit(c);
    c = corners_[prev(c)].opposite;
  } while (c != kNone && c != start);
}

}  // namespace isowave::simplify
