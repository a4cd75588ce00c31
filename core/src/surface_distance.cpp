#include "isowave/core/surface_distance.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"

namespace isowave {

// Simple_cartesian<double>: distance queries need no exact predicates, and it
// is the fastest kernel for them.
using Kernel = CGAL::Simple_cartesian<double>;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

struct SurfaceDistance::Tree {
  std::vector<Triangle> triangles;
  ::isowave::Tree tree;
};

SurfaceDistance::SurfaceDistance(const PolygonMesh& mesh) : tree_(std::make_unique<Tree>()) {
  if (mesh.face_count() == 0) throw Error(ErrorKind::InvalidArgument, "distance to a mesh without faces");
  tree_->triangles.reserve(mesh.face_vertices.size() - 2 * mesh.face_count());
  const auto point = [&](std::uint32_t v) {
    const Vec3& p = mesh.positions[v];
    return Kernel::Point_3(p.x, p.y, p.z);
  };
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < mesh.face_size(f); ++k)
      tree_->triangles.emplace_back(point(face[0]), point(face[k]), point(face[k + 1]));
  }
  tree_->tree.insert(tree_->triangles.cbegin(), tree_->triangles.cend());
  tree_->tree.build();
  tree_->tree.accelerate_distance_queries();
}

SurfaceDistance::~SurfaceDistance() = default;

std::size_t SurfaceDistance::triangle_count() const { return tree_->triangles.size(); }

double SurfaceDistance::distance(const Vec3& p) const {
  return std::sqrt(tree_->tree.squared_distance(Kernel::Point_3(p.x, p.y, p.z)));
}

std::vector<double> SurfaceDistance::distances(const std::vector<Vec3>& points) const {
  std::vector<double> out(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i < r.end(); ++i) out[i] = distance(points[i]);
                    });
  return out;
}

}  // namespace isowave
