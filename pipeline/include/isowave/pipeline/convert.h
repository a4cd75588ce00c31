#pragma once
// The whole conversion of paper Sec. 4-5 for one volume and isovalue:
// preparation (pre-filter, extraction, signed distance; prepare.h) -> base
// mesh -> shrink-wrap -> analysis -> quantization and coding into an .isw
// file, with the figures users need (sizes, stage timings, RMSE at several
// coefficient percentages) and warnings where the fit did not follow the
// surface.
#include <memory>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/progress.h"
#include "isowave/core/volume.h"
#include "isowave/extract/isosurface.h"
#include "isowave/fit/surface_fit.h"
#include "isowave/pipeline/prepare.h"
#include "isowave/simplify/simplify.h"

namespace isowave {

// How the base mesh's size follows the fit.
enum class BaseGrowth {
  Fixed,  // one base mesh of the requested size
  // While more than kUncoveredWarning of the isosurface lies more than
  // kUncoveredCells cells from every fine control point, simplify again to
  // twice the base's vertex count and fit again: at most kBaseAttempts tries,
  // while the base stays under a quarter of the isosurface's vertices, and
  // only with automatic levels (with fixed levels a larger base multiplies
  // the fine mesh).
  UntilCovered,
};

struct BaseMeshOptions {
  // Target vertex count (>= 4); 0: `ratio` times the extracted vertex count.
  std::size_t vertices = 0;
  double ratio = 0.0625;  // in (0, 1]
  BaseGrowth growth = BaseGrowth::Fixed;
  // The simplifier's rules (Sec. 4.1, edge removal);
  // convert_volume() sets target_vertices, compute_distance and
  // serial_phase_begins itself.
  simplify::SimplifyOptions simplify;
};

// What convert_volume() does with a fit whose fine faces mostly fold
// (more than kUnusableFolded of them): its surface is a crumpled sheet, and
// a file of it is unusable.
enum class FoldedFit {
  Refuse,  // throw Error(Unsupported) naming the remedy, before coding
  Keep,    // code it anyway (the warning stays)
};

// What the .isw 2.0 file's size follows (issue #34): at most one target;
// none writes the whole embedded stream, down to ConvertOptions::step_cells.
struct RateTarget {
  double max_error_cells = 0;   // > 0: the shortest stream prefix whose D (against the extracted isosurface) is within this
  std::uint64_t max_bytes = 0;  // > 0: the file's size limit in bytes
  double bits_per_vertex = 0;   // > 0: the size limit in bits per extracted isosurface vertex
};

struct ConvertOptions {
  // Isovalue, orientation, clean-up, pre-filter and the distance band.
  PrepareOptions prepare;
  BaseMeshOptions base;
  // Subdivision levels 1..6; 0 picks them, for both fits: the fewest levels
  // whose fitted fine mesh lies within max_error_cells of the extracted
  // isosurface (D, surface_error.h), or the most before a fine mesh beyond
  // max_auto_fine_vertices().
  int levels = 0;
  // The automatic levels' bound on D in cells (>= 0); 0: kLevelErrorShare
  // (kCorrectedLevelErrorShare where the fine points end on the trilinear
  // isosurface: the shrink-wrap's correction, FinePoints::OnTrilinearIsosurface)
  // of the marching-cubes mesh's own distance from the trilinear isosurface
  // (extracted_surface_deviation), at least kLevelErrorFloorCells. D is
  // measured against the extracted mesh, on the fit as LevelReport says.
  double max_error_cells = 0;
  // The normal fit by default: the lowest BD-rate against Draco on the
  // shared volumes (docs/MEASUREMENTS.md, issue #47 item 4).
  FitMethod fit = FitMethod::Normal;
  FinePoints fine_points = FinePoints::OnTrilinearIsosurface;
  // The shrink-wrap (Sec. 4.2); convert_volume() sets `surface` to the extracted mesh.
  ShrinkWrapOptions shrink_wrap;
  // FitMethod::Normal; convert_volume() sets `surface`, `orientation` and
  // `coverage_pull` (from shrink_wrap's) itself.
  NormalFitOptions normal;
  // The step of the last bit plane in cells (IswEncodeOptions::step / cell
  // size, > 0): the finest the stream goes; `rate` cuts it shorter.
  double step_cells = 0.01;
  RateTarget rate;
  // Percentages for the error summary (the base-mesh row is added).
  std::vector<double> summary_percents{100, 20, 10, 5};
  FoldedFit folded_fit = FoldedFit::Refuse;
  // Keep the extracted triangle mesh in the result (for comparisons).
  bool keep_extracted_mesh = false;
};

// Wall-clock seconds per stage. The signed-distance field is computed
// alongside the base mesh; `distance` is only the wait for it afterwards, so
// that the stages add up to the whole conversion. `fit` includes building
// D's reference, and `analysis` putting the fitted surface in the base
// coder's order.
struct ConvertTimings {
  double extract = 0, simplify = 0, distance = 0, fit = 0, analysis = 0, encode = 0, evaluate = 0;
  double total() const { return extract + simplify + distance + fit + analysis + encode + evaluate; }
};

// The process's peak resident bytes at the end of each stage
// (core/peak_memory.h; 0 where the system does not say). The allocator keeps
// freed memory for reuse (huge_page_vector.h), so the figures never fall: a
// stage's growth over the stage before is what it added. The distance field,
// built during simplify, counts there. Process-wide: with several
// conversions at once (a batch's --jobs) each figure includes the others'.
struct ConvertPeaks {
  double extract = 0, simplify = 0, fit = 0, analysis = 0, encode = 0, evaluate = 0;
};

// Share of the fine control points that may lie more than a cell off the
// isosurface before convert_volume() warns (see ConvertResult::fit_isosurface).
inline constexpr double kFarPointsWarning = 0.005;
// Share of the isosurface that may lie more than kUncoveredCells cells from
// every fine control point before convert_volume() warns.
inline constexpr double kUncoveredWarning = 0.01;
// More than this share of the isosurface left out means the base mesh spans
// whole parts of it: a fold warning then names a larger base mesh, not the
// pre-filter.
inline constexpr double kUncoveredCoarse = 0.1;
// More than this share of folded fine faces (ConvertResult::folded_share)
// adds a warning naming the remedy: a larger base mesh where it is too coarse
// for the surface (the fine mesh under half the isosurface's vertices, points
// left off it, over kUncoveredCoarse of it left out), else a one-voxel
// pre-filter (--smooth 1): the folds then sit on features under a cell
// across (necks, tunnels, specks of noisy scans).
inline constexpr double kFoldedWarning = 0.01;
// More than this share of folded fine faces makes the fit unusable (FoldedFit).
inline constexpr double kUnusableFolded = 0.5;
inline constexpr int kBaseAttempts = 3;
// The automatic levels' default bound (ConvertOptions::max_error_cells). On
// the extracted surface, the fit's sampling error adds to the marching-cubes
// mesh's own about in quadrature: 0.75 of it keeps the sum within 1.25 of it.
// Corrected onto the trilinear isosurface, the fit's error is its sampling
// error alone: the marching-cubes mesh's own is the bound.
inline constexpr double kLevelErrorShare = 0.75;
inline constexpr double kCorrectedLevelErrorShare = 1.0;
// The automatic levels stop before a fine mesh of more than this many times
// the isosurface's vertices: the shrink-wrap's D stalls beyond it, while each
// level of the parametrization about halves its D (docs/MEASUREMENTS.md);
// and, for both, before one of more than kMaxAutoFineVertices (about 2.4 GB
// for the fit, kFitBytesPerFineVertex).
inline constexpr double kMaxFineShare = 4.0;
inline constexpr double kParametrizationMaxFineShare = 16.0;
inline constexpr double kMaxAutoFineVertices = 8e6;
// The parametrization's base mesh: no base vertex holds more than this
// multiple of the isosurface's area per target vertex
// (SimplifyOptions::max_vertex_area_share), so that a uniform refinement of
// the base faces samples the surface evenly; the base keeps at least the
// target divided by it.
inline constexpr double kParametrizationAreaShare = 0.5;
// Samples each way for the D convert measures (levels, summary rows):
// enough for a few per mille of noise where no rare far point dominates.
inline constexpr std::size_t kErrorSamples = 50000;
inline constexpr double kLevelErrorFloorCells = 0.01;
// The step at which the file sends the base control points before the
// planes (IswEncodeOptions::frame_step), in cells: the local frames' base.
inline constexpr double kFrameStepCells = 0.125;
// With a maximum error for the file (RateTarget::max_error_cells), the
// automatic levels' bound is this share of it: the quantization of the cut
// stream adds the rest (errors add about in quadrature).
inline constexpr double kLevelShareOfMaxError = 0.9;

// The largest fine mesh the automatic levels may reach for `fit` on an
// isosurface of `extracted_vertices` (the constants above).
double max_auto_fine_vertices(FitMethod fit, std::size_t extracted_vertices);

struct ConvertResult {
  std::string bytes;  // the .isw file
  PolygonMesh extracted_mesh;  // with keep_extracted_mesh
  IsosurfaceReport extraction;
  simplify::SimplifyReport simplification;
  ShrinkWrapResult fit;  // positions: the fitted fine control points (both fits)
  // With FitMethod::Parametrization: the fit's figures.
  ParametrizedFitStatistics parametrization;
  // With FitMethod::Normal: per level fitted (1..L), and the non-normal
  // coefficients of the last fit.
  std::vector<NormalFitLevelStatistics> normal_levels;
  std::size_t non_normal_coefficients = 0;
  // Per level 1..L: the share of the wavelet coefficients' energy (sum of
  // squares) along the normals of the file's local frames (1 for a level of
  // zero detail).
  std::vector<double> normal_share;
  // The plane stream's estimated bits by what they code, before any cut
  // (IswPlaneValues::plane_bits()); its tangential_share() is the share spent
  // on the coefficients' tangential components.
  IswPlaneBits plane_bits;
  // With FitMethod::Normal: the base its directions came from, which the
  // file sends as its frame base (IswEncodeOptions::frame_base); else empty.
  std::vector<Vec3> frame_base;
  // Every level the fit tried on the last base mesh, in order; the last is `levels`.
  std::vector<LevelReport> level_reports;
  double max_error_cells = 0;  // the bound the automatic levels used (0 with fixed levels)
  // The hierarchy over the base mesh: control_mesh(levels, fit.positions) is the fitted fine mesh.
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  int levels = 0;
  std::size_t extracted_vertices = 0, base_vertices = 0, fine_vertices = 0, fine_faces = 0;
  double cell_size = 1;
  ConvertTimings seconds;
  ConvertPeaks peak_bytes;
  // The fitted fine control points against the isosurface of the field they
  // were fitted to (first order, cells). More than kFarPointsWarning of them
  // farther than a cell away adds a warning.
  IsosurfaceDistance fit_isosurface;
  // The share of the extracted isosurface's vertices (sampled) farther than
  // kUncoveredCells cells from every fine control point (share_farther_than):
  // what the fit left out. More than kUncoveredWarning adds a warning.
  double uncovered_share = 0;
  // The share of the fine faces whose normal disagrees with the field
  // gradient (ShrinkWrapResult::folded_faces): folds of the parameterization.
  double folded_share() const;
  // Tries at the base mesh (BaseGrowth::UntilCovered) and the first one's
  // vertex count; base_vertices is the last one's.
  int base_attempts = 1;
  std::size_t first_base_vertices = 0;
  // error_table() of the file written, as `isowave stats` reports it: rows
  // against the full-resolution decode; the quantization error separately.
  std::vector<RateDistortionRow> summary;
  // Per summary row: D (surface_error.h, kErrorSamples each way) of
  // the decoded surface against the extracted isosurface, in cells: what a
  // user gets back, which the rows' control-point errors do not show.
  std::vector<double> summary_surface_error;
  QuantizationError quantization;
  // D (world units) at prefixes of the plane stream: every plane boundary up
  // to the cut, and the cut (the file's RDTB); and D of the file's whole stream.
  std::vector<IswRatePoint> rate_table;
  double file_error = 0;
  std::vector<std::string> warnings;  // one line each, e.g. a base mesh kept large by the topology
};

// Converts one isosurface of `volume` (moved in: the pre-filtered field
// replaces it). `source` names the input in the file's metadata and in
// errors. Throws Error(InvalidArgument) for invalid options or a fine mesh
// larger than this machine's memory (checked before it is built),
// Error(EmptyResult) for an empty isosurface, Error(Unsupported) for an unusable fit (FoldedFit::Refuse),
// and what the stages throw. Memory: about kFitBytesPerFineVertex per fine
// control point.
ConvertResult convert_volume(Volume volume, const std::string& source, const ConvertOptions& options,
                             ProgressSink& progress = no_progress());

}  // namespace isowave
