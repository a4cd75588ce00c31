// convert_volume()'s levels by error (issue #33, items 3 and 4), for both
// fits: --levels auto picks the smallest level whose fitted fine mesh lies
// within the bound of the extracted isosurface (D), and each level tried is
// reported with D both ways, its folds and its face areas, as surface_error()
// and the fine mesh itself give them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/pipeline/convert.h"
#include "convert_test_support.h"
#include "isowave/pipeline/prepare.h"

namespace isowave {
namespace {

class LevelsByError : public ::testing::TestWithParam<FitMethod> {
 protected:
  // The fine points as fitted (the parametrization's stay on the extracted
  // surface), so that the fitted fine mesh in the result is the one the
  // levels were measured on.
  ConvertOptions options() const {
    ConvertOptions o;
    o.fit = GetParam();
    o.fine_points = FinePoints::OnExtractedSurface;
    o.summary_percents = {100};
    o.keep_extracted_mesh = true;
    return o;
  }
};

std::string fit_name(const ::testing::TestParamInfo<FitMethod>& info) {
  switch (info.param) {
    case FitMethod::ShrinkWrap: return "ShrinkWrap";
    case FitMethod::Parametrization: return "Parametrization";
    case FitMethod::Normal: return "Normal";
  }
  return "";
}

// The torus at 48^3: a few thousand extracted vertices, several levels fit.
const Volume& torus() {
  static const Volume field = make_builtin_field("torus", 48);
  return field;
}

PolygonMesh fitted_mesh(const ConvertResult& r) { return r.hierarchy->control_mesh(r.levels, r.fit.positions); }

// Vector area of a polygon as the sum of its fan triangles' (additive).
double polygon_area(const PolygonMesh& mesh, std::size_t f) {
  const std::uint32_t* v = mesh.face_begin(f);
  Vec3 sum;
  for (std::uint32_t k = 1; k + 1 < mesh.face_size(f); ++k)
    sum += cross(mesh.positions[v[k]] - mesh.positions[v[0]], mesh.positions[v[k + 1]] - mesh.positions[v[0]]);
  return 0.5 * norm(sum);
}

TEST_P(LevelsByError, ATighterBoundPicksMoreLevels) {
  ConvertOptions o = options();
  o.max_error_cells = 1.0;  // a cell: any level meets it
  const ConvertResult loose = convert_volume(torus(), "torus", o);
  o.max_error_cells = 0.001;
  const ConvertResult tight = convert_volume(torus(), "torus", o);
  std::printf("torus 48: levels %d within 1 cell, %d within 0.001 cell\n", loose.levels, tight.levels);
  EXPECT_EQ(loose.levels, 1);
  ASSERT_EQ(loose.level_reports.size(), 1u);
  EXPECT_LE(loose.level_reports[0].d_cells(), 1.0);
  EXPECT_GT(tight.levels, loose.levels);
  // No fit comes within 0.001 cell: the levels stop at the cap on the fine mesh.
  EXPECT_GT(double(fine_vertex_count(tight.hierarchy->base(), tight.levels + 1)),
            max_auto_fine_vertices(o.fit, tight.extracted_vertices));
  EXPECT_LE(double(tight.fine_vertices), max_auto_fine_vertices(o.fit, tight.extracted_vertices));
}

TEST_P(LevelsByError, PicksTheSmallestLevelWithinTheBound) {
  ConvertOptions o = options();
  o.max_error_cells = 0.015;
  const ConvertResult result = convert_volume(torus(), "torus", o);
  ASSERT_GE(result.levels, 2) << "the torus should need more than one level within 0.015 cell";
  ASSERT_EQ(result.level_reports.size(), std::size_t(result.levels));
  EXPECT_LE(result.level_reports.back().d_cells(), 0.015);
  // One level fewer, fitted on its own and measured by surface_error() with
  // the default sample count, is over the bound.
  o.levels = result.levels - 1;
  const ConvertResult fewer = convert_volume(torus(), "torus", o);
  const double d_fewer = surface_error(fitted_mesh(fewer), fewer.extracted_mesh).d() / fewer.cell_size;
  std::printf("torus 48: %d levels, D %.4f cell; %d levels, D %.4f cell\n", result.levels,
              result.level_reports.back().d_cells(), fewer.levels, d_fewer);
  EXPECT_GT(d_fewer, 0.015);
  // Fixed levels: that level alone, without a bound.
  ASSERT_EQ(fewer.level_reports.size(), 1u);
  EXPECT_EQ(fewer.level_reports[0].levels, result.levels - 1);
  EXPECT_EQ(fewer.max_error_cells, 0.0);
}

TEST_P(LevelsByError, ReportsTheFittedAndDecodedSurfacesError) {
  ConvertOptions o = options();
  o.levels = 2;
  const ConvertResult result = convert_volume(torus(), "torus", o);
  ASSERT_EQ(result.level_reports.size(), 1u);
  const LevelReport& report = result.level_reports[0];
  const PolygonMesh fitted = fitted_mesh(result);
  EXPECT_EQ(report.fine_vertices, fitted.vertex_count());

  // D both ways: surface_error() of the fitted fine mesh. The result holds it
  // renumbered for the file's base coder (canonical_surface), so its faces
  // are sampled in another order: the same surface, other samples.
  const SurfaceError error = surface_error(fitted, result.extracted_mesh, kErrorSamples);
  EXPECT_NEAR(report.forward_rms_cells, error.forward_rms / result.cell_size, 0.05 * report.forward_rms_cells);
  EXPECT_NEAR(report.backward_rms_cells, error.backward_rms / result.cell_size, 0.05 * report.backward_rms_cells);
  // The decoded file's fine mesh is the fitted one moved by the quantization
  // (at most its maximum error): its D, from other samples, differs by about that.
  const IswDecoded decoded = decode_isw(result.bytes, "torus");
  const PolygonMesh decoded_mesh = test::full_decode_mesh(decoded);
  const double d_decoded = surface_error(decoded_mesh, result.extracted_mesh).d() / result.cell_size;
  EXPECT_NEAR(report.d_cells(), d_decoded, result.quantization.max / result.cell_size + 0.05 * d_decoded);

  // Stretch: the fine faces' areas over their mean.
  std::vector<double> areas(fitted.face_count());
  double mean = 0;
  for (std::size_t f = 0; f < areas.size(); ++f) mean += areas[f] = polygon_area(fitted, f);
  mean /= double(areas.size());
  std::sort(areas.begin(), areas.end());
  EXPECT_NEAR(report.stretch_min, areas.front() / mean, 1e-9);
  EXPECT_NEAR(report.stretch_max, areas.back() / mean, 1e-9);
  EXPECT_NEAR(report.stretch_median, areas[areas.size() / 2] / mean, 1e-9);
  // The torus's fit does not fold: the share is the result's own.
  EXPECT_EQ(report.folded_share, result.folded_share());
  EXPECT_LT(report.folded_share, 0.01);
}

INSTANTIATE_TEST_SUITE_P(EveryFit, LevelsByError,
                         ::testing::Values(FitMethod::ShrinkWrap, FitMethod::Parametrization, FitMethod::Normal),
                         fit_name);

}  // namespace
}  // namespace isowave
