// convert_volume() with the normal fit (FitMethod::Normal, issue #47):
// against the analytic torus, the decoded surface lies within 1.25 times the
// marching-cubes mesh's own distance from the true surface, without folds;
// every wavelet coefficient of the file decodes along its frame normal (the
// frames of the fit's frame base, renumbered with the base): no tangential
// detail at all, and almost no bits spent on tangential parts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/pipeline/convert.h"
#include "support/test_meshes.h"
#include "convert_test_support.h"

namespace isowave {
namespace {

using test::rms_from_torus;

TEST(ConvertNormal, DecodedTorusIsNearTheTrueSurfaceWithOnlyNormalDetail) {
  constexpr std::size_t n = 48;
  ConvertOptions options;
  options.fit = FitMethod::Normal;
  options.keep_extracted_mesh = true;
  options.summary_percents = {100};
  const ConvertResult result = convert_volume(make_builtin_field("torus", n), "torus", options);
  EXPECT_EQ(result.non_normal_coefficients, 0u);
  EXPECT_EQ(result.fit.folded_faces, 0u);
  ASSERT_EQ(result.normal_share.size(), std::size_t(result.levels));
  for (const double share : result.normal_share) EXPECT_GT(share, 1 - 1e-12);
  // Codec 2.1 spends on tangential parts only one flag (0) per wavelet
  // coefficient that becomes significant: at most 0.0221 bits each once its
  // context has adapted, and under 32 bits per context to get there
  // (tests/codec/test_bitplane_coder.cpp derives both); 4 contexts per class
  // (1 + 2 levels) and group (G = clamp(round(N / 2^17), 1, 64), docs/FORMAT.md).
  const std::size_t groups = std::min<std::size_t>(64, std::max<std::size_t>(1, (result.fine_vertices + 65536) >> 17));
  const std::size_t classes = 1 + 2 * std::size_t(result.levels);
  EXPECT_GT(result.plane_bits.total(), 0);
  EXPECT_LE(result.plane_bits.tangential(), 0.0221 * double(result.fine_vertices) + 32.0 * 4 * classes * groups);
  EXPECT_EQ(result.plane_bits.tangential_sign + result.plane_bits.tangential_refinement, 0.0);

  const IswDecoded decoded = decode_isw(result.bytes, "torus");
  const PolygonMesh fine = test::full_decode_mesh(decoded);
  const double marching_cubes = rms_from_torus(result.extracted_mesh, n), fitted = rms_from_torus(fine, n);
  std::printf("torus %zu: marching cubes %.4f cell RMS from the torus, decoded normal fit %.4f (levels %d)\n", n,
              marching_cubes, fitted, result.levels);
  EXPECT_LE(fitted, 1.25 * marching_cubes);

  ASSERT_EQ(result.frame_base.size(), decoded.hierarchy->vertex_count(0));
  const std::vector<Vec3> normals =
      isw_frame_normals(*decoded.hierarchy, result.frame_base, kFrameStepCells * result.cell_size);
  std::size_t nonzero = 0;
  for (std::size_t i = decoded.hierarchy->vertex_count(0); i < decoded.coefficients.size(); ++i) {
    const Vec3& c = decoded.coefficients[i];
    const Vec3& m = normals[i];
    EXPECT_LE(norm(c - m * dot(m, c)), 1e-12 * (1 + norm(c))) << "coefficient " << i;
    nonzero += norm(c) > 0;
  }
  EXPECT_GT(nonzero, decoded.coefficients.size() / 4);  // the check above is not vacuous
}

// A sphere cut by two faces of the box: the surface's boundary curves lie on
// them. Every decoded point stays in the box (the field is clamped beyond it,
// so its isosurface would go on outside), the decoded surface lies as near
// the true sphere as the marching-cubes mesh, and few coefficients are
// non-normal (the boundary curves' are: a large share of this small mesh).
TEST(ConvertNormal, SphereCutByTheBoxStaysInsideIt) {
  const Vec3 c{0.3, 20.2, 41.6};
  const double r = 14;
  const Volume field = test::sampled_volume(
      {36, 40, 44}, [&](double x, double y, double z) { return r - std::sqrt(squared_norm(Vec3{x, y, z} - c)); });
  ConvertOptions options;
  options.fit = FitMethod::Normal;
  options.keep_extracted_mesh = true;
  options.summary_percents = {100};
  const ConvertResult result = convert_volume(field, "cut sphere", options);
  const IswDecoded decoded = decode_isw(result.bytes, "cut sphere");
  const PolygonMesh fine = test::full_decode_mesh(decoded);
  const auto from_sphere = [&](const PolygonMesh& mesh) {
    return test::rms_distance(mesh, [&](const Vec3& p) { return std::sqrt(squared_norm(p - c)) - r; });
  };
  double beyond = 0, fitted_beyond = 0;
  for (const Vec3& p : fine.positions) beyond = std::max({beyond, -p.x, p.z - 43});
  for (const Vec3& p : result.fit.positions) fitted_beyond = std::max({fitted_beyond, -p.x, p.z - 43});
  std::printf("cut sphere: points at most %.4f cells beyond the box, fitted %.4f\n", beyond, fitted_beyond);
  EXPECT_LE(fitted_beyond, 1e-3);
  EXPECT_LE(beyond, 0.05);  // plus the quantization: a few of the finest steps
  const double marching_cubes = from_sphere(result.extracted_mesh), fitted = from_sphere(fine);
  std::printf("cut sphere: marching cubes %.4f cell RMS from the sphere, decoded normal fit %.4f; %zu of %zu "
              "coefficients non-normal\n",
              marching_cubes, fitted, result.non_normal_coefficients, result.fine_vertices - result.base_vertices);
  EXPECT_LE(fitted, 1.25 * marching_cubes);
  EXPECT_LT(double(result.non_normal_coefficients), 0.1 * double(result.fine_vertices - result.base_vertices));
}

}  // namespace
}  // namespace isowave
