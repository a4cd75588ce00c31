#pragma once
// Distance from points to a polygon mesh surface with CGAL's AABB tree
// (private: keeps CGAL out of the public headers).
#include <vector>

#include "isowave/core/mesh.h"

namespace isowave::simplify {

struct DistanceStatistics {
  double max = 0;
  double rms = 0;
};

// Faces are fan-triangulated from their first vertex. Queries run in
// parallel (TBB). O(n log m) for n points and m faces.
DistanceStatistics point_to_surface_distance(const std::vector<Vec3>& points, const PolygonMesh& surface);

}  // namespace isowave::simplify
