#pragma once
// Exact Euclidean distance from points to a polygon mesh (faces fanned into
// triangles from their first vertex), through a CGAL AABB tree: the
// reference of tests and benchmarks (the base-mesh and fit quality reports
// use the faster BinnedSurfaceDistance, which tests compare with it). CGAL
// stays inside the .cpp. Its primitives must not be degenerate: a triangle of
// collinear corners is measured by its corners only (BinnedSurfaceDistance
// measures its edges).
#include <memory>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"

namespace isowave {

class SurfaceDistance {
 public:
  // Builds the tree: O(n log n) time, about 150 bytes per triangle. The mesh
  // must have at least one face (Error(InvalidArgument) otherwise); its
  // positions are copied.
  explicit SurfaceDistance(const PolygonMesh& mesh);
  ~SurfaceDistance();
  SurfaceDistance(const SurfaceDistance&) = delete;
  SurfaceDistance& operator=(const SurfaceDistance&) = delete;

  std::size_t triangle_count() const;
  // Distance from p to the nearest point of the mesh. Thread-safe.
  double distance(const Vec3& p) const;
  // distance() for every point, in parallel (TBB); out[i] for points[i].
  std::vector<double> distances(const std::vector<Vec3>& points) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

}  // namespace isowave
