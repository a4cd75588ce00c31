// The inverse of the simplifier's map (fit/src/surface_map_inverse.h) on
// maps simplify() builds from real meshes and an extracted isosurface: every
// input vertex comes back from its own parameter point, and every fine point
// of parametrized_fit() lies on the input triangles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/mesh_io.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/fit/parametrized_fit.h"
#include "isowave/simplify/simplify.h"
#include "support/test_meshes.h"
#include "surface_map_inverse.h"

namespace isowave {
namespace {

double diagonal(const PolygonMesh& mesh) {
  Vec3 low = mesh.positions.front(), high = low;
  for (const Vec3& p : mesh.positions) {
    low = {std::min(low.x, p.x), std::min(low.y, p.y), std::min(low.z, p.z)};
    high = {std::max(high.x, p.x), std::max(high.y, p.y), std::max(high.z, p.z)};
  }
  return std::sqrt(squared_norm(high - low));
}

struct RoundTrip {
  std::size_t vertices = 0, off = 0;  // input vertices not returned to within 1e-9 of the mesh size
  std::size_t fine_points = 0, fine_off = 0;  // fine points farther than that from the input surface
};

RoundTrip round_trip(const PolygonMesh& input, std::size_t base_vertices) {
  simplify::SimplifyOptions options;
  options.target_vertices = base_vertices;
  options.surface_map = simplify::SurfaceMapping::Build;
  options.compute_distance = false;
  const simplify::SimplifyResult simplified = simplify::simplify(input, options);
  const simplify::SurfaceMap& map = simplified.map;
  std::vector<MapPoint> queries(input.vertex_count());
  for (std::size_t v = 0; v < queries.size(); ++v)
    queries[v] = MapPoint{map.vertex_triangle[v], map.vertex_uv[v][0], map.vertex_uv[v][1]};
  const InverseMapResult inverse = inverse_map(map, simplified.base.positions, input, queries);
  const double tolerance = 1e-9 * diagonal(input);
  RoundTrip result;
  result.vertices = input.vertex_count();
  for (std::size_t v = 0; v < queries.size(); ++v)
    if (std::sqrt(squared_norm(inverse.points[v] - input.positions[v])) > tolerance) ++result.off;
  const SubdivisionHierarchy hierarchy(simplified.base, 2);
  const ParametrizedFitResult fit = parametrized_fit(hierarchy, simplified.base.positions, input, map);
  const std::vector<double> distances = BinnedSurfaceDistance(input).distances(fit.positions);
  result.fine_points = distances.size();
  result.fine_off = std::size_t(std::count_if(distances.begin(), distances.end(), [&](double d) { return d > tolerance; }));
  return result;
}

// An input vertex whose incident triangles the map turns over (see
// test_surface_map.cpp) is located in a neighbouring triangle: it comes back
// near, not exactly. Their share stays below this; on a mesh of many small
// holes below kMaxOffShareManyHoles (boundary vertices whose triangles all
// lie along the base boundary are missed: a known limit).
constexpr double kMaxOffShare = 0.02, kMaxOffShareManyHoles = 0.1;

void expect_round_trip(const PolygonMesh& input, std::size_t base_vertices, const std::string& name,
                       double max_off_share = kMaxOffShare) {
  const RoundTrip r = round_trip(input, base_vertices);
  std::printf("%s: %zu of %zu input vertices off their parameter point's image; %zu of %zu fine points off the "
              "surface\n",
              name.c_str(), r.off, r.vertices, r.fine_off, r.fine_points);
  EXPECT_LE(double(r.off), max_off_share * double(r.vertices)) << name;
  EXPECT_EQ(r.fine_off, 0u) << name;
}

TEST(SurfaceMapInverse, ReturnsInputVerticesOnTheMeshCorpus) {
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "shared data absent";
  for (const std::string file : {"fertility_genus4.off", "mushroom_disk.off", "fandisk_sharp.obj"}) {
    const PolygonMesh input = read_mesh(test::shared_data_file("meshes/" + file));
    expect_round_trip(input, input.vertex_count() / 30, file);
  }
  const PolygonMesh holes = read_mesh(test::shared_data_file("meshes/elephant_106holes.off"));
  expect_round_trip(holes, holes.vertex_count() / 30, "elephant_106holes.off", kMaxOffShareManyHoles);
}

TEST(SurfaceMapInverse, ReturnsInputVerticesOnAnExtractedIsosurface) {
  IsosurfaceOptions extract;
  const PolygonMesh input = extract_isosurface(make_builtin_field("mixing", 48), extract).mesh;
  expect_round_trip(input, input.vertex_count() / 20, "mixing 48");
}

}  // namespace
}  // namespace isowave
