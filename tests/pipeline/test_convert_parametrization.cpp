// convert_volume() with the parametrization-based fit (FitMethod::
// Parametrization, issue #33): against the analytic torus, the decoded
// surface lies within the marching-cubes mesh's own distance of the true
// surface, without folds and with the torus's topology; on a turbulent field
// its surface error D is below the shrink-wrap's and it folds no more faces
// than the marching-cubes mesh does.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/fit/fold_repair.h"
#include "isowave/fit/wrap_level_mesh.h"
#include "isowave/pipeline/convert.h"
#include "convert_test_support.h"

namespace isowave {
namespace {

// The share of the marching-cubes mesh's own faces that the fits' fold test
// (count_folded_faces) finds folded: the bar for a fit of the same field.
double marching_cubes_folded_share(const ConvertResult& result, const Volume& field) {
  const PolygonMesh& mesh = result.extracted_mesh;
  const WrapLevelMesh level = make_wrap_level_mesh(SubdivisionHierarchy(mesh, 0), 0, mesh.positions, field);
  return double(count_folded_faces(level, mesh.positions, field, Orientation::TowardLower)) / double(mesh.face_count());
}

using test::rms_from_torus;

TEST(ConvertParametrization, DecodedTorusIsAsNearTheTrueSurfaceAsMarchingCubes) {
  constexpr std::size_t n = 48;
  const Volume field = make_builtin_field("torus", n);
  const test::DecodedConversion conversion = test::convert_and_decode(field, "torus", FitMethod::Parametrization);
  const ConvertResult& result = conversion.result;
  const PolygonMesh& fine = conversion.fine;
  const double marching_cubes = rms_from_torus(result.extracted_mesh, n);
  const double fitted = rms_from_torus(fine, n);
  std::printf("torus %zu: marching cubes %.4f cell RMS from the torus, decoded fit %.4f (levels %d)\n", n,
              marching_cubes, fitted, result.levels);
  EXPECT_LE(fitted, 1.25 * marching_cubes);
  EXPECT_EQ(marching_cubes_folded_share(result, field), 0.0);
  EXPECT_EQ(result.fit.folded_faces, 0u);
  const TopologySummary topology = summarize_topology(fine);
  EXPECT_EQ(topology.components, 1u);
  EXPECT_EQ(topology.genus, 1);
  EXPECT_EQ(topology.boundary_loops, 0u);
  // The levels stop at the first whose D meets the bound, or before a fine
  // mesh beyond max_auto_fine_vertices().
  ASSERT_FALSE(result.level_reports.empty());
  const SubdivisionHierarchy next(result.hierarchy->base(), result.levels + 1);
  if (double(next.fine_vertex_count()) <= max_auto_fine_vertices(FitMethod::Parametrization, result.extracted_vertices)) {
    EXPECT_LE(result.level_reports.back().d_cells(), result.max_error_cells);
  }
  for (std::size_t k = 0; k + 1 < result.level_reports.size(); ++k)
    EXPECT_GT(result.level_reports[k].d_cells(), result.max_error_cells);
  // The summary's D is measured on the decoded surface against the extracted one.
  ASSERT_EQ(result.summary_surface_error.size(), result.summary.size());
  const double d = surface_error(fine, result.extracted_mesh).d() / result.cell_size;
  EXPECT_NEAR(result.summary_surface_error.front(), d, 0.05 * d + 1e-3);
}

TEST(ConvertParametrization, LiesNearerATurbulentIsosurfaceThanTheShrinkWrap) {
  const Volume field = make_builtin_field("mixing", 64);
  ConvertOptions options;
  options.fit = FitMethod::ShrinkWrap;
  options.summary_percents = {100};
  options.folded_fit = FoldedFit::Keep;
  const ConvertResult wrapped = convert_volume(field, "mixing", options);
  options.fit = FitMethod::Parametrization;
  options.keep_extracted_mesh = true;
  const ConvertResult parametrized = convert_volume(field, "mixing", options);
  const double marching_cubes_folded = marching_cubes_folded_share(parametrized, field);
  std::printf("mixing 64: D at 100%% shrink-wrap %.4f, parametrization %.4f cells; folded faces %.4f%%, marching "
              "cubes' own %.4f%%\n",
              wrapped.summary_surface_error.front(), parametrized.summary_surface_error.front(),
              100 * parametrized.folded_share(), 100 * marching_cubes_folded);
  EXPECT_LT(parametrized.summary_surface_error.front(), wrapped.summary_surface_error.front());
  // No more folds than the marching-cubes mesh has by the same test.
  EXPECT_LE(parametrized.folded_share(), marching_cubes_folded);
}

TEST(ConvertParametrization, RejectsANegativeErrorBound) {
  ConvertOptions options;
  options.fit = FitMethod::Parametrization;
  options.max_error_cells = -1;
  EXPECT_THROW(convert_volume(make_builtin_field("sphere", 16), "sphere", options), Error);
}

}  // namespace
}  // namespace isowave
