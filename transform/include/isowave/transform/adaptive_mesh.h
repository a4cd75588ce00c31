#pragma once
// A crack-free mesh of a hierarchy refined to a different level on each
// base face (issue #48, item 4; Gross, Staadt and Gatti's transitions as
// mixed polygons): base face f contributes its level-levels[f] faces, and a
// face along a base edge whose other side is finer takes that side's vertices
// on the edge into its boundary, so that no T-junction and no crack appears
// and every edge the output holds is shared as in the full decode.
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// `levels`: per base face, in [0, hierarchy.levels()]; `fine`: the level-L
// control points (at least fine_vertex_count()), whose entries at a level's
// vertex indices place that level's faces (a coarser level's vertices keep
// their indices at finer ones). The output keeps only the vertices its faces
// use, in ascending index order. Faces are level-l quads, the base polygons
// for level 0, and polygons with extra corners along edges to finer faces.
// Throws Error(InvalidArgument) for a level out of range or too few levels
// or points. Cost: one control-mesh topology per level used, and per base
// edge between different levels a walk down its subdivision (O(2^level)).
PolygonMesh adaptive_control_mesh(const SubdivisionHierarchy& hierarchy, const std::vector<int>& levels,
                                  const std::vector<Vec3>& fine);

// The polygons adaptive_control_mesh() gives base face `base_face`, in fine
// vertex indices (the hierarchy's, not renumbered), appended: each polygon's
// corners to `corners` and its end (an index into `corners`) to `offsets`.
// They depend on the face's level and its edge neighbours' only, so a
// viewer that changes some levels re-emits those faces and their
// neighbours. Error(InvalidArgument) for a face out of range, or its or its
// neighbours' level. Cost: the face's faces and the walks down its base
// edges (independent of the mesh's size).
void adaptive_patch(const SubdivisionHierarchy& hierarchy, const std::vector<int>& levels, std::size_t base_face,
                    std::vector<std::uint32_t>& offsets, std::vector<std::uint32_t>& corners);

}  // namespace isowave
