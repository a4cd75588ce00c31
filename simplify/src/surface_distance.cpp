#include "surface_distance.h"

#include <algorithm>
#include <cmath>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace isowave::simplify {

namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point to_point(const Vec3& p) { return Point(p.x, p.y, p.z); }

struct Partial {
  double max_squared = 0;
  double sum_squared = 0;
};
}  // namespace

DistanceStatistics point_to_surface_distance(const std::vector<Vec3>& points, const PolygonMesh& surface) {
  DistanceStatistics result;
  if (points.empty() || surface.face_count() == 0) return result;
  std::vector<Triangle> triangles;
  triangles.reserve(surface.face_vertices.size());
  for (std::size_t f = 0; f < surface.face_count(); ++f) {
    const std::uint32_t* face = surface.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < surface.face_size(f); ++k)
      triangles.emplace_back(to_point(surface.positions[face[0]]), to_point(surface.positions[face[k]]),
                             to_point(surface.positions[face[k + 1]]));
  }
  Tree tree(triangles.begin(), triangles.end());
  tree.build();
  tree.accelerate_distance_queries();  // built here, before the parallel queries
  const Partial total = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), 4096), Partial{},
      [&](const tbb::blocked_range<std::size_t>& range, Partial partial) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const double squared = tree.squared_distance(to_point(points[i]));
          partial.max_squared = std::max(partial.max_squared, squared);
          partial.sum_squared += squared;
        }
        return partial;
      },
      [](Partial x, const Partial& y) {
        x.max_squared = std::max(x.max_squared, y.max_squared);
        x.sum_squared += y.sum_squared;
        return x;
      });
  result.max = std::sqrt(total.max_squared);
  result.rms = std::sqrt(total.sum_squared / static_cast<double>(points.size()));
  return result;
}

}  // namespace isowave::simplify
