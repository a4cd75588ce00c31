#pragma once
// Exact Euclidean distance from points to a polygon mesh of many small faces
// (fanned into triangles from their first vertex), through a uniform grid of
// bins: the fit's quality report measures millions of points against the
// extracted mesh and the extracted vertices against the fitted mesh.
// SurfaceDistance (a CGAL AABB tree) answers the same for any mesh, and the
// tests compare the two; these bins build in linear time and take a small
// fraction of the tree's memory, which matters for meshes of tens of
// millions of triangles. Distances are in the mesh's world units.
//
// Layout: flat arrays, as the queries gather from them at random. Each
// triangle's index is listed in every bin its bounding box overlaps, the
// lists sorted by bin with one offset per bin (x fastest), so that a row of
// bins along x is one contiguous run that a query scans in one go.
#include <cstdint>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"

namespace isowave {

class BinnedSurfaceDistance {
 public:
  // Bins of twice the mean triangle edge (larger if the mesh's bounding box
  // would need more than 8 bins per triangle). O(T + B) time, serial, and
  // about 4 bytes per bin plus 4 per (triangle, overlapped bin) pair, 12 per
  // triangle and 24 per vertex, for T triangles and B bins. Throws
  // Error(InvalidArgument) for a mesh without faces or with a non-finite
  // position.
  explicit BinnedSurfaceDistance(const PolygonMesh& mesh);

  std::size_t triangle_count() const { return triangles_.size() / 3; }

  // Distance from p to the nearest point of the mesh (NaN for a non-finite
  // p). Thread-safe. Scans the bins ring by ring around p's bin until no
  // farther bin can hold a nearer triangle: about the bins within the
  // distance found, so cheap near the surface and slower far from it.
  double distance(const Vec3& p) const;
  // distance() for every point, in parallel (TBB); out[i] for points[i].
  std::vector<double> distances(const std::vector<Vec3>& points) const;
  // The nearest point of the mesh to p (finite; the first found of equally
  // near ones). Thread-safe; the same scan as distance().
  Vec3 closest_point(const Vec3& p) const;

 private:
  // With `closest`, the nearest point is stored there.
  double squared_distance(const Vec3& p, Vec3* closest = nullptr) const;
  // min(best, squared distance from p to the triangle); where the triangle
  // is nearer than best, its closest point goes to `closest` if given.
  double squared_distance_to_triangle(const Vec3& p, std::uint32_t triangle, double best, Vec3* closest) const;
  std::int64_t bin_along(int axis, double coordinate) const;  // clamped to the grid

  std::vector<Vec3> positions_;
  std::vector<std::uint32_t> triangles_;  // 3 vertex indices per triangle
  Vec3 origin_;
  double bin_ = 1;
  std::int64_t dims_[3] = {1, 1, 1};
  std::vector<std::uint32_t> first_;    // per bin, then the end: where its run of listed_ starts
  std::vector<std::uint32_t> listed_;   // triangle indices, bin by bin
};

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection,
// 5.1.5); a triangle of (nearly) collinear or coincident corners counts as
// its three edges.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace isowave
