#pragma once
// Exact Euclidean distances from one fixed set of points to the surface of
// many meshes: the backward direction of the surface error D (the
// reference's samples against each decoded mesh, surface_error.h).
//
// The points are binned once in a uniform grid. A mesh is swept in blocks
// of consecutive faces: each block gathers the points binned within the
// search radius of its bounding box, and each of its fan triangles lowers
// their best distance (an atomic minimum). A point with no triangle within
// the radius is swept again, in a grid of the points left, with a radius
// four times larger, until none is left. Nothing per triangle is stored,
// unlike BinnedSurfaceDistance: memory is about 40 bytes per point and 48
// per 16 faces, and time one pass over the faces plus, for each larger
// radius the farthest points need, one over the blocks. Blocks are small
// where consecutive faces lie near each other (a hierarchy's fine level,
// extracted meshes); any face order gives the same distances, more slowly.
#include <cstddef>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"

namespace isowave {

class PointSetDistance {
 public:
  // `points`: at least one, all finite; `radius`: the first search radius,
  // world units, > 0 and finite (a point farther from a mesh costs another
  // sweep). Throws Error(InvalidArgument) otherwise. O(points) time.
  PointSetDistance(std::vector<Vec3> points, double radius);

  const std::vector<Vec3>& points() const { return points_; }

  // Per point, in order, its distance to the nearest point of `mesh` (faces
  // fanned from their first vertex; degenerate triangles count as their
  // edges). Parallel (TBB); the result does not depend on the thread count.
  // Throws Error(InvalidArgument) for a mesh without faces or with a
  // non-finite position.
  std::vector<double> distances(const PolygonMesh& mesh) const;

 private:
  std::vector<Vec3> points_;
  double radius_;
};

}  // namespace isowave
