#pragma once
// The base mesh order the .isw 2.0 base coder sends compactly (about 3 bits
// per base vertex; any other order falls back to version 1's coder, about
// 28): vertices numbered as a traversal first meets them, faces in its order,
// each face starting at a fixed corner. Converting a fitted surface to it
// renumbers the whole hierarchy, so the fitted fine control points move with
// their vertices.
#include <cstdint>
#include <memory>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

struct CanonicalSurface {
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;  // over the base in canonical order, same levels
  std::vector<Vec3> fine;  // the fine control points given, renumbered for it
  // Per base vertex of the given hierarchy: its index in the canonical one.
  std::vector<std::uint32_t> base_order;
};

// `fine`: level-L control points of `hierarchy` (at least fine_vertex_count()).
// The same surface over the canonical base: the same control mesh at every
// level up to numbering. Returns `hierarchy` itself (and `fine`) when its base
// is canonical already. Cost: O(fine vertices) plus one hierarchy build.
CanonicalSurface canonical_surface(const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
                                   std::vector<Vec3> fine);

}  // namespace isowave
