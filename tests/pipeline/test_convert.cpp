// convert_volume(): the fit check that the error rows cannot make (they are
// measured against the full decode of the file).
#include <gtest/gtest.h>

#include <chrono>
#include <iterator>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "isowave/pipeline/convert.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"
#include "isowave/core/surface_distance.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/volume_io.h"
#include "isowave/fit/fit_quality.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

bool warns(const ConvertResult& result, const std::string& about) {
  return std::any_of(result.warnings.begin(), result.warnings.end(),
                     [&](const std::string& w) { return w.find(about) != std::string::npos; });
}
const std::string kOffTheIsosurface = "off the isosurface", kUncovered = "from every fine control point",
                  kFolded = "fold against the field gradient";

// Distances, in cells, from the extracted vertices to the decoded finest
// control mesh: an independent, exact measure of how much of the surface the
// fit misses.
std::vector<double> coverage(const ConvertResult& result) {
  const IswDecoded decoded = decode_isw(result.bytes, "test");
  const std::vector<Vec3> points = reconstruct(decoded, decoded.ranked.size());
  const PolygonMesh fitted = decoded.hierarchy->control_mesh(decoded.hierarchy->levels(), points);
  std::vector<double> distances = SurfaceDistance(fitted).distances(result.extracted_mesh.positions);
  for (double& d : distances) d /= result.cell_size;
  return distances;
}

double share_over(const std::vector<double>& values, double limit) {
  return double(std::count_if(values.begin(), values.end(), [&](double v) { return v > limit; })) / double(values.size());
}

// The torus at 48^3 (3,240 extracted vertices): from 18 base vertices the fit
// stays on the isosurface but covers only a tenth of it; from 9 its points
// end off the surface unless the correction starts them again from the
// extracted surface (CorrectionStatistics::from_extracted_surface), which
// crumples them onto a few spots of it; from twice 18, or the default base
// (1/16), it is exact. (Which of these tiny bases cover depends on how the base
// falls on the ring: 16, 17 and 19 cover, 15 leaves 12% out.)
// Each summary row's D is the D of what `decode --percent` of the file gives:
// the decode of its coefficients, measured as surface_error() measures it.
TEST(Convert, SummaryRowsReportTheirDecodesSurfaceError) {
  ConvertOptions options;
  options.keep_extracted_mesh = true;
  options.summary_percents = {100, 20, 5};
  const ConvertResult result = convert_volume(make_builtin_field("mixing", 32), "mixing", options);
  ASSERT_EQ(result.summary_surface_error.size(), result.summary.size());
  ASSERT_GE(result.summary.size(), 4u);  // the base mesh last
  for (std::size_t k = 0; k < result.summary.size(); ++k) {
    const RateDistortionRow& row = result.summary[k];
    IswDecodeOptions keep;
    keep.max_coefficients = row.wavelet_coefficients;
    const IswDecoded decoded = decode_isw(result.bytes, "mixing", keep);
    const PolygonMesh mesh = decoded.hierarchy->control_mesh(decoded.levels, reconstruct(decoded, SIZE_MAX));
    const double d = surface_error(mesh, result.extracted_mesh, kErrorSamples).d() / result.cell_size;
    EXPECT_NEAR(result.summary_surface_error[k], d, 1e-9 * d) << "row " << k << " at " << row.percent << "%";
  }
  EXPECT_GT(result.summary_surface_error.back(), result.summary_surface_error.front());
}

// The profile (issue #51): the stages' times add up to the whole conversion
// (the wall-clock time around it, less what convert_volume does between
// stages), and the peaks never fall from stage to stage, the last holding at
// least the fine control points' decode.
TEST(Convert, StageTimesAddUpToTheWholeAndPeaksGrow) {
  const Volume field = make_builtin_field("mixing", 48);
  const ConvertOptions options;
  const auto start = std::chrono::steady_clock::now();
  const ConvertResult result = convert_volume(field, "mixing", options);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("[ report ] stages %.3f s of %.3f s\n", result.seconds.total(), wall);
  EXPECT_LE(result.seconds.total(), wall);
  EXPECT_GE(result.seconds.total(), 0.95 * wall - 0.02) << "wall " << wall;
  const ConvertPeaks& p = result.peak_bytes;
  const double peaks[] = {p.extract, p.simplify, p.fit, p.analysis, p.encode, p.evaluate};
  for (std::size_t k = 1; k < std::size(peaks); ++k) EXPECT_LE(peaks[k - 1], peaks[k]) << "stage " << k;
  EXPECT_GE(p.evaluate, 24.0 * static_cast<double>(result.fine_vertices));
}

TEST(Convert, WarnsWhenTheFitLeavesPartsOfTheSurfaceOut) {
  const Volume torus = make_builtin_field("torus", 48);
  ConvertOptions options;
  options.fit = FitMethod::ShrinkWrap;  // its correction's fallbacks are counted below
  options.keep_extracted_mesh = true;
  options.summary_percents = {100};
  // Without the coverage pull, which would cover part of what these bases
  // leave out (on the finest level it reaches 8 cells): this test is about
  // the warnings and the point test, not the pull.
  options.shrink_wrap.coverage_pull = false;
  options.folded_fit = FoldedFit::Keep;  // from 9 base vertices over half the faces fold
  options.base.simplify.valence_flips = true;  // without, the paper's rules stop the torus at 10

  options.base.vertices = 18;
  const ConvertResult partial = convert_volume(torus, "torus", options);
  ASSERT_EQ(partial.base_vertices, 18u);
  std::vector<double> distances = coverage(partial);
  EXPECT_GT(percentile(distances, 0.99), 1.0);
  EXPECT_TRUE(warns(partial, kUncovered));
  // The cheap point test against the exact share: never less than the share
  // beyond kUncoveredCells, never more than the share beyond that less the
  // reach of a fine face (under half a cell here). Measured: 0.8880 against
  // 0.8867 and 0.9108.
  EXPECT_GE(partial.uncovered_share, share_over(distances, kUncoveredCells));
  EXPECT_LE(partial.uncovered_share, share_over(distances, kUncoveredCells - 0.5));
  EXPECT_GT(partial.uncovered_share, 0.2);

  options.base.vertices = 9;
  const ConvertResult coarse = convert_volume(torus, "torus", options);
  ASSERT_EQ(coarse.base_vertices, 9u);
  EXPECT_GT(coarse.fit.correction.from_extracted_surface, 0u);
  EXPECT_FALSE(warns(coarse, kOffTheIsosurface));
  EXPECT_EQ(coarse.fit_isosurface.far, 0u);
  EXPECT_TRUE(warns(coarse, kUncovered));
  EXPECT_TRUE(warns(coarse, kFolded));

  // Grown until it covers: 18 -> 36 base vertices.
  options.base.vertices = 18;
  options.base.growth = BaseGrowth::UntilCovered;
  const ConvertResult grown = convert_volume(torus, "torus", options);
  EXPECT_GT(grown.base_attempts, 1);
  EXPECT_EQ(grown.first_base_vertices, 18u);
  EXPECT_GT(grown.base_vertices, 18u);
  EXPECT_LE(grown.uncovered_share, kUncoveredWarning);
  EXPECT_FALSE(warns(grown, kUncovered));
  distances = coverage(grown);
  EXPECT_LE(share_over(distances, kUncoveredCells), kUncoveredWarning);
  options.base.growth = BaseGrowth::Fixed;

  options.base.vertices = 0;
  const ConvertResult exact = convert_volume(torus, "torus", options);
  EXPECT_TRUE(exact.warnings.empty());
  EXPECT_LE(double(exact.fit_isosurface.far), kFarPointsWarning * double(exact.fine_vertices));
  EXPECT_EQ(exact.uncovered_share, 0.0);
  distances = coverage(exact);
  EXPECT_LT(percentile(distances, 0.99), 0.5);
}

// The torus at 160^3 from 9 base vertices, 3 levels: the refined base spans
// the ring's hole and its tube, and many fine points end over 16 cells from
// any surface, beyond every search of the correction (the extracted
// surface's included). convert counts them and says so. The count is checked
// against the torus's exact distance (the builtin field is minor radius minus
// the distance to the core circle), not against the trilinear measure
// convert itself uses.
TEST(Convert, WarnsWhenFitPointsStayOffTheIsosurface) {
  constexpr std::size_t n = 160;
  const Volume torus = make_builtin_field("torus", n);
  ConvertOptions options;
  options.fit = FitMethod::ShrinkWrap;  // the normal fit leaves none of its points off (at most 0.18 cell)
  options.summary_percents = {100};
  options.base.vertices = 9;
  options.levels = 3;
  // Over kUnusableFolded of its fine faces fold: refused before coding
  // unless kept.
  try {
    convert_volume(torus, "torus", options);
    ADD_FAILURE() << "a fit folded over half refused no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::Unsupported);
    EXPECT_NE(std::string(error.what()).find("unusable"), std::string::npos) << error.what();
  }
  options.folded_fit = FoldedFit::Keep;
  const ConvertResult result = convert_volume(torus, "torus", options);
  EXPECT_GT(result.folded_share(), kUnusableFolded);
  // Shares in fixed notation with two decimals ("1e+02%" before).
  for (const std::string& warning : result.warnings)
    for (std::size_t at = warning.find('%'); at != std::string::npos; at = warning.find('%', at + 1))
      EXPECT_EQ(warning.substr(at - 3, 1), ".") << warning;
  ASSERT_EQ(result.base_vertices, 9u);
  const double size = double(n - 1), centre = 0.5 * size, major = 0.25 * size, minor = 0.1 * size;
  std::size_t exact_far = 0;
  double exact_max = 0;
  for (std::size_t v = 0; v < result.fine_vertices; ++v) {
    const Vec3 p = result.fit.positions[v];
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    const double x = (p.x - torus.origin.x) / torus.spacing.x - centre, y = (p.y - torus.origin.y) / torus.spacing.y - centre,
                 z = (p.z - torus.origin.z) / torus.spacing.z - centre;
    const double ring = std::sqrt(x * x + y * y) - major;
    const double distance = std::abs(minor - std::sqrt(ring * ring + z * z));  // in cells
    exact_far += distance > 1.0 ? 1 : 0;
    exact_max = std::max(exact_max, distance);
  }
  // Over 5% of the points (the warning's threshold is 0.5%), and the same
  // count within 2% of it: the first-order measure differs from the exact
  // distance only by the trilinear interpolation of a cone near the core
  // circle and the ring's axis.
  EXPECT_GT(double(exact_far), 0.05 * double(result.fine_vertices));
  EXPECT_NEAR(double(result.fit_isosurface.far), double(exact_far), 0.02 * double(exact_far));
  EXPECT_GT(result.fit_isosurface.max, 1.0);
  EXPECT_LE(result.fit_isosurface.max, 1.05 * exact_max);
  EXPECT_TRUE(warns(result, kOffTheIsosurface));
  EXPECT_TRUE(warns(result, "the fit leaves " + std::to_string(result.fit_isosurface.far) + " of the " +
                                std::to_string(result.fine_vertices) + " fine control points"));
  // Its folds come from the base mesh, not from features under a cell: the
  // warning names the base, and the same with the pre-filter, which leaves
  // most of them.
  EXPECT_TRUE(warns(result, kFolded));
  EXPECT_TRUE(warns(result, "the base mesh is too coarse"));
  EXPECT_FALSE(warns(result, "--smooth 1"));
  options.prepare.extract.smooth_sigma = 1.0;
  const ConvertResult smoothed = convert_volume(torus, "torus", options);
  EXPECT_GT(smoothed.folded_share(), kFoldedWarning);
  EXPECT_TRUE(warns(smoothed, "the base mesh is too coarse"));
}

// The folded share convert reports is the fit's own count after its last
// repair (the shrink-wrap's unfold runs on its fit; the normal fit has none);
// measured independently on the fitted fine mesh by the quality report, it
// is the same.
TEST(Convert, ReportsTheShareOfFoldedFineFaces) {
  const Volume field = make_builtin_field("mixing", 96);
  for (const FitMethod fit : {FitMethod::ShrinkWrap, FitMethod::Normal}) {
    ConvertOptions options;
    options.fit = fit;
    options.keep_extracted_mesh = true;
    options.summary_percents = {100};
    const ConvertResult result = convert_volume(field, "mixing", options);
    if (fit == FitMethod::ShrinkWrap) {
      ASSERT_FALSE(result.fit.unfold.skipped);
    }
    const IswDecoded decoded = decode_isw(result.bytes, "test");
    const BinnedSurfaceDistance reference(result.extracted_mesh);
    const FitQuality quality =
        measure_fit_quality(*decoded.hierarchy, decoded.hierarchy->levels(), result.fit.positions,
                            result.extracted_mesh, reference, field, options.prepare.extract.iso,
                            orientation_from_flip(options.prepare.extract.flip));
    EXPECT_GT(quality.folded_faces, 0u);
    EXPECT_EQ(result.fine_faces, quality.faces);
    EXPECT_EQ(result.fit.folded_faces, quality.folded_faces);
    EXPECT_DOUBLE_EQ(result.folded_share(), quality.folded_fraction);
  }
}

// The mixing layer sampled coarsely (40^3) is all necks and specks a cell
// across: 4% of the fine faces fold, and convert says so and names the
// remedy; with that one-voxel pre-filter none fold and it does not warn.
// The shrink-wrap's: the normal fit keeps 0.28% of its faces folded with the
// pre-filter (docs/MEASUREMENTS.md).
TEST(Convert, WarnsAboutFoldsWhichThePreFilterRemoves) {
  const Volume field = make_builtin_field("mixing", 40);
  ConvertOptions options;
  options.fit = FitMethod::ShrinkWrap;
  options.summary_percents = {100};
  const std::string kFolds = "fold against the field gradient";
  const ConvertResult raw = convert_volume(field, "mixing", options);
  EXPECT_GT(raw.folded_share(), kFoldedWarning);
  EXPECT_TRUE(warns(raw, kFolds));
  EXPECT_TRUE(warns(raw, "--smooth 1"));
  options.prepare.extract.smooth_sigma = 1.0;
  const ConvertResult smoothed = convert_volume(field, "mixing", options);
  EXPECT_LT(smoothed.folded_share(), 0.001);
  EXPECT_FALSE(warns(smoothed, kFolds));
}

// The stent CT at 300 (thin struts, noise): the fit leaves parts of the
// isosurface out, yet its folds sit on features under a cell across, and
// more levels make them worse; the one-voxel pre-filter removes them. The
// warning names --smooth 1 and not more levels (it named more levels,
// as for a base mesh too coarse for the surface). The shrink-wrap's: the
// normal fit keeps 1.4% folded with the pre-filter.
TEST(Convert, NamesThePreFilterForFoldsOnANoisyScan) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/stent_128x128x256.nrrd");
  ConvertOptions options;
  options.fit = FitMethod::ShrinkWrap;
  options.prepare.extract.iso = 300;
  options.base.growth = BaseGrowth::UntilCovered;  // as the command runs it
  options.summary_percents = {100};
  const ConvertResult raw = convert_volume(read_volume(path), path, options);
  ASSERT_GT(raw.folded_share(), kFoldedWarning);
  EXPECT_TRUE(warns(raw, kFolded));
  EXPECT_TRUE(warns(raw, "--smooth 1"));
  EXPECT_FALSE(warns(raw, "--levels"));
  options.prepare.extract.smooth_sigma = 1.0;
  const ConvertResult smoothed = convert_volume(read_volume(path), path, options);
  EXPECT_LT(smoothed.folded_share(), kFoldedWarning);
  EXPECT_FALSE(warns(smoothed, kFolded));
}

}  // namespace
}  // namespace isowave
