#pragma once
// Checks shared by the isosurface tests: where boundary edges lie and which
// way the triangles face, computed from the mesh and the samples alone.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/volume.h"

namespace isowave::test {

// Faces of the volume box a world position lies on (bit 2 axis + side).
int box_faces_of(const Volume& volume, const Vec3& p);

// Edges used by exactly one face, counted from scratch.
std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary_edges(const PolygonMesh& mesh);

// GoogleTest expectation: every boundary edge has both endpoints on one face
// of the volume box.
void expect_boundary_on_box(const Volume& volume, const PolygonMesh& mesh, const std::string& name);

// Fraction of the triangle area (where the field's gradient is not zero)
// whose normal points toward lower values: the normal against the gradient
// of the trilinear interpolant at the triangle centroid.
double fraction_toward_lower(const Volume& volume, const PolygonMesh& mesh);

}  // namespace isowave::test
