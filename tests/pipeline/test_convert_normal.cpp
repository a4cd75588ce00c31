// convert_volume() with the normal fit (FitMethod::Normal, issue #47):
// against the analytic torus, the decoded surface lies within 1.25 times the
// marching-cubes mesh's own distance from the true surface, without folds;
// every wavelet coefficient of the file decodes along its frame normal (the
// frames of the fit's frame base, renumbered with the base): no tangential
// detail at all.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/pipeline/convert.h"
#include "torus_reference.h"

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

  const IswDecoded decoded = decode_isw(result.bytes, "torus");
  const PolygonMesh fine =
      decoded.hierarchy->control_mesh(decoded.hierarchy->levels(), reconstruct(decoded, decoded.ranked.size()));
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

}  // namespace
}  // namespace isowave
