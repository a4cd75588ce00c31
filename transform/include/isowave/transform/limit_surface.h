#pragma once
// Limit surface of a control mesh, evaluated with OpenSubdiv (the project's
// reference for the limit surface): Catmull-Clark limit masks, boundaries as
// VTX_BOUNDARY_EDGE_ONLY, sharp vertices as infinitely sharp corners.
//
// Near extraordinary and interior sharp vertices the paper's operator S
// differs slightly from Catmull-Clark (see tests), so this is the limit of the
// Catmull-Clark surface with these control points.
#include <vector>

#include "isowave/core/mesh.h"

namespace isowave {

struct LimitSurface {
  std::vector<Vec3> positions;  // limit point of each control vertex
  std::vector<Vec3> normals;    // unit normal there (zero where undefined)
};

// `control_mesh` must be a 2-manifold (require_manifold). A mesh with faces
// other than quads is refined once first (its vertices' limit points are those
// of their children). Cost: O(vertices), dominated by OpenSubdiv's topology.
LimitSurface limit_surface(const PolygonMesh& control_mesh);

// Catmull-Clark refinement by OpenSubdiv's Far::PrimvarRefiner, for tests and
// benchmarks: positions of levels 0..levels (each a prefix-compatible array in
// OpenSubdiv's vertex order, the same order SubdivisionHierarchy uses).
std::vector<std::vector<Vec3>> opensubdiv_refine(const PolygonMesh& base, int levels);

}  // namespace isowave
