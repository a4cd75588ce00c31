#include "isowave/transform/limit_surface.h"

#include <opensubdiv/far/primvarRefiner.h>

#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "opensubdiv_bridge.h"

namespace isowave {
namespace {

// Vec3 with the interface Far::PrimvarRefiner expects of a primvar.
struct Point {
  Vec3 p;
  void Clear() { p = Vec3{}; }
  void AddWithWeight(const Point& src, double weight) { p += weight * src.p; }
};

}  // namespace

LimitSurface limit_surface(const PolygonMesh& control_mesh) {
  require_manifold(control_mesh, "control mesh");
  bool all_quads = true;
  for (std::size_t f = 0; f < control_mesh.face_count() && all_quads; ++f) all_quads = control_mesh.face_size(f) == 4;
  const int levels = all_quads ? 0 : 1;

  auto refiner = detail::make_refiner(control_mesh);
  if (levels > 0) {
    OpenSubdiv::Far::TopologyRefiner::UniformOptions options(levels);
    options.fullTopologyInLastLevel = true;
    refiner->RefineUniform(options);
  }
  std::vector<Point> points(static_cast<std::size_t>(refiner->GetNumVerticesTotal()));
  for (std::size_t v = 0; v < control_mesh.vertex_count(); ++v) points[v].p = control_mesh.positions[v];
  OpenSubdiv::Far::PrimvarRefinerReal<double> primvar(*refiner);
  Point* source = points.data();
  for (int level = 1; level <= levels; ++level) {
    Point* destination = source + refiner->GetLevel(level - 1).GetNumVertices();
    primvar.Interpolate(level, source, destination);
    source = destination;
  }
  const std::size_t last_count = static_cast<std::size_t>(refiner->GetLevel(levels).GetNumVertices());
  std::vector<Point> limit(last_count), tangent_u(last_count), tangent_v(last_count);
  primvar.Limit(source, limit, tangent_u, tangent_v);

  // The first vertices of the last level are the control vertices' children.
  LimitSurface result;
  result.positions.resize(control_mesh.vertex_count());
  result.normals.resize(control_mesh.vertex_count());
  for (std::size_t v = 0; v < control_mesh.vertex_count(); ++v) {
    result.positions[v] = limit[v].p;
    result.normals[v] = normalized(cross(tangent_u[v].p, tangent_v[v].p));
  }
  return result;
}

std::vector<std::vector<Vec3>> opensubdiv_refine(const PolygonMesh& base, int levels) {
  require_manifold(base, "base mesh");
  auto refiner = detail::make_refiner(base);
  OpenSubdiv::Far::TopologyRefiner::UniformOptions options(levels);
  refiner->RefineUniform(options);
  std::vector<std::vector<Vec3>> result(static_cast<std::size_t>(levels) + 1);
  std::vector<Point> points(static_cast<std::size_t>(refiner->GetNumVerticesTotal()));
  for (std::size_t v = 0; v < base.vertex_count(); ++v) points[v].p = base.positions[v];
  OpenSubdiv::Far::PrimvarRefinerReal<double> primvar(*refiner);
  Point* source = points.data();
  result[0] = base.positions;
  for (int level = 1; level <= levels; ++level) {
    Point* destination = source + refiner->GetLevel(level - 1).GetNumVertices();
    primvar.Interpolate(level, source, destination);
    source = destination;
    const int count = refiner->GetLevel(level).GetNumVertices();
    result[static_cast<std::size_t>(level)].resize(static_cast<std::size_t>(count));
    for (int v = 0; v < count; ++v) result[static_cast<std::size_t>(level)][static_cast<std::size_t>(v)] = source[v].p;
  }
  return result;
}

}  // namespace isowave
