#pragma once
// Private: the crack-free mesh of a region or view decode over the whole base
// mesh (issue #48, items 1, 2 and 4): the faces of a hierarchy (the whole
// one, or a patch's: transform/patch_hierarchy.h) at their levels, joined by
// adaptive_patch()'s transitions, and the base faces outside a patch whole.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"

namespace isowave::detail {

// Where the faces are built: the whole hierarchy, or a patch of it whose
// faces flagged `exact` hold the complete decode's fine control points.
struct PatchDomain {
  const SubdivisionHierarchy& h;
  const std::vector<std::uint32_t>* entries = nullptr;  // patch entry -> whole entry (null: the same)
  const std::vector<std::uint32_t>* faces = nullptr;    // patch base face -> base face (null: the same)
  const std::vector<std::uint8_t>* exact = nullptr;     // per patch base face (null: every face)
  std::uint32_t entry(std::size_t k) const { return entries ? (*entries)[k] : static_cast<std::uint32_t>(k); }
  std::uint32_t face(std::size_t f) const { return faces ? (*faces)[f] : static_cast<std::uint32_t>(f); }
  bool is_exact(std::size_t f) const { return !exact || (*exact)[f]; }
};

// Which base vertices take their fine points (the others their base
// control points): the corners of faces refined above level 0 (a region:
// the base mesh outside it), or the corners of exact faces (a view: every
// face in view on the surface).
enum class BaseCorners { RefinedFaces, ExactFaces };

// The mesh over the whole base (`base`, `base_points` its control points;
// `whole_entries` the whole hierarchy's): the faces of `d` at `levels` (per
// face of d), the faces outside `d` whole; vertices in the order of their
// whole entries (an array over them: a sort of the corners costs more).
// Cost: O(whole entries + the faces emitted).
PolygonMesh patch_mesh(const PatchDomain& d, const PolygonMesh& base, const std::vector<Vec3>& base_points,
                       std::size_t whole_entries, const std::vector<int>& levels, const std::vector<Vec3>& fine,
                       BaseCorners corners_at);

}  // namespace isowave::detail
