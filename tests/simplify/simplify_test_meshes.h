#pragma once
// Triangle meshes for the simplify tests, on top of tests/support.
#include "isowave/core/mesh.h"
#include "support/test_meshes.h"

namespace isowave::test {

// Splits every face into a fan from its first vertex (quads: always the same
// diagonal, unlike core triangulate(), so that grids have known valences).
PolygonMesh fan_triangulate(const PolygonMesh& mesh);
// Octahedron subdivided `levels` times (each triangle into 4), on the unit sphere.
PolygonMesh icosphere(int levels);
PolygonMesh tetrahedron();
// Planar disk: centre 0 of valence `spokes`, ring 1..spokes, and an outer ring.
PolygonMesh wheel(std::uint32_t spokes);

}  // namespace isowave::test
