// The transpose of one synthesis level: <S x, g> = <x, S^T g> for random x
// and g on meshes with boundaries, creases, sharp corners and polygons, and
// the same result for any thread count.
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "isowave/core/error.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/wavelet_transform.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

double inner(const std::vector<Vec3>& a, const std::vector<Vec3>& b, std::size_t count) {
  double sum = 0;
  for (std::size_t i = 0; i < count; ++i) sum += dot(a[i], b[i]);
  return sum;
}

void check_transpose(const std::string& name, PolygonMesh mesh, int levels, std::uint32_t seed) {
  SCOPED_TRACE(name + " L=" + std::to_string(levels));
  const SubdivisionHierarchy h(mesh, levels);
  for (int level = 1; level <= levels; ++level) {
    const std::size_t n = h.vertex_count(level);
    const std::vector<Vec3> x = test::random_vectors(n, seed + 17 * static_cast<std::uint32_t>(level));
    const std::vector<Vec3> g = test::random_vectors(n, seed + 31 * static_cast<std::uint32_t>(level));
    std::vector<Vec3> sx = x;  // level-(level-1) control points and the level's coefficients
    synthesize_level(h, level, sx);
    std::vector<Vec3> stg = g;
    synthesize_level_transpose(h, level, stg);
    const double left = inner(sx, g, n), right = inner(x, stg, n);
    EXPECT_NEAR(left, right, 1e-10 * (std::abs(left) + std::abs(right) + double(n)));
  }
}

PolygonMesh with_sharp_vertices(PolygonMesh mesh, std::size_t every) {
  mesh.sharp.assign(mesh.vertex_count(), 0);
  for (std::size_t v = 0; v < mesh.vertex_count(); v += every) mesh.sharp[v] = 1;
  return mesh;
}

TEST(SynthesisTranspose, InnerProductsAgreeOnGeneratedMeshes) {
  std::uint32_t seed = 7;
  for (const auto& [name, mesh] : test::generated_corpus()) {
    check_transpose(name, mesh, 3, seed++);
    check_transpose(name + " with sharp vertices", with_sharp_vertices(mesh, 5), 2, seed++);
  }
}

TEST(SynthesisTranspose, IdenticalForAnyThreadCount) {
  const PolygonMesh mesh = test::quad_grid(40, 30, true, true);
  const SubdivisionHierarchy h(mesh, 3);
  const std::vector<Vec3> g = test::random_vectors(h.fine_vertex_count(), 3);
  std::vector<Vec3> parallel = g, serial = g;
  synthesize_level_transpose(h, 3, parallel);
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    synthesize_level_transpose(h, 3, serial);
  }
  EXPECT_EQ(parallel, serial);
}

TEST(SynthesisTranspose, RejectsBadLevelsAndSizes) {
  const SubdivisionHierarchy h(test::cube(), 2);
  std::vector<Vec3> data(h.fine_vertex_count());
  EXPECT_THROW(synthesize_level_transpose(h, 0, data), Error);
  EXPECT_THROW(synthesize_level_transpose(h, 3, data), Error);
  std::vector<Vec3> short_data(h.vertex_count(1));
  EXPECT_THROW(synthesize_level_transpose(h, 2, short_data), Error);
}

}  // namespace
}  // namespace isowave
