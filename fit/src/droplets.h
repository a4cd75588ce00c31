#pragma once
// Droplets (not in the paper): closed components of the base mesh with few
// vertices, all near their centroid (ShrinkWrapOptions::droplet_vertices,
// droplet_cells), a few cells across or less, mostly tetrahedra. On them the
// paper's steps fold: the relaxation shrinks a tetrahedron to a third of its
// size per round, and the attraction along the normals of valence-3 corners,
// which point anywhere but at the surface, turns it inside out. Their free
// vertices instead relax within their tangent planes (relax_with's
// tangent_only) and are attracted and corrected along rays from the
// component's centroid (fit_droplets). A base simplified as far as the rules
// allow makes every closed genus-0 component a tetrahedron, large ones
// included: hence the size limit. Private to fit/.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/fit/orientation.h"
#include "isowave/fit/trilinear.h"
#include "isowave/fit/wrap_level_mesh.h"
#include "isowave/transform/hierarchy.h"
#include "wrap_kernels.h"

namespace isowave::wrap {

struct Droplets {
  std::vector<std::vector<std::uint32_t>> base_faces;  // per component
  std::vector<double> inside_sign;                     // sign of field - iso inside (0: unknown)
  std::vector<double> base_radius;                     // of the base vertices around their centroid
  std::vector<std::vector<std::uint32_t>> vertices;    // on the current level, ascending

  bool empty() const { return base_faces.empty(); }

  // Vertices of level `level`: the corners of the faces descending from the
  // components' base faces. O(their faces).
  void set_level(const SubdivisionHierarchy& hierarchy, int level, const WrapLevelMesh& mesh);
};

// The closed components of the base (level 0's `mesh`; no box-held, boundary
// or sharp vertex) with at most max_vertices vertices, all within max_radius
// (world units) of their centroid, and a nonzero signed volume; the inside
// judged by the faces' `orientation`. O(base).
Droplets find_droplets(const SubdivisionHierarchy& hierarchy, const WrapLevelMesh& mesh,
                       const std::vector<Vec3>& positions, std::size_t max_vertices, double max_radius,
                       Orientation orientation);

// Attraction (and correction) of the droplets' free vertices along the ray
// from their component's centroid (of `source`) through the vertex (in
// `source`) to the first crossing of the trilinear field's isosurface iso,
// written to `target` (within about 1e-5 cells). A component whose centroid
// is not inside, and a vertex without a crossing within max(3 times the base
// component's radius, 0.02 cells), are left as they are in `target`. The
// base radius, not the current one: a component that is no droplet (the
// inside reaching far) would otherwise let vertices go ever farther, on
// every round and level. 32 samples and a bisection per vertex.
void fit_droplets(const WrapLevelMesh& mesh, const Droplets& droplets, const TrilinearGrid& field, const Box& box,
                  double cell, double iso, const std::vector<Vec3>& source, std::vector<Vec3>& target);

}  // namespace isowave::wrap
