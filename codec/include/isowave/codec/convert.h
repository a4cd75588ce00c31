#pragma once
// The whole conversion of paper Sec. 4-5 for one volume and isovalue:
// extraction -> base mesh -> signed distance -> shrink-wrap -> analysis ->
// quantization and coding into an .isw file, with the figures users need
// (sizes, stage timings, RMSE at several coefficient percentages).
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/progress.h"
#include "isowave/core/volume.h"
#include "isowave/extract/isosurface.h"
#include "isowave/fit/fit_quality.h"
#include "isowave/fit/shrink_wrap.h"
#include "isowave/simplify/simplify.h"

namespace isowave {

struct ConvertOptions {
  double iso = 0.0;
  bool flip = false;
  std::size_t min_component_vertices = 0;  // extraction clean-up (0: off)
  double smooth_sigma = 0.0;               // extraction pre-filter in voxels (0: off)
  // Subdivision levels; 0 picks the level whose fine mesh has about as many
  // vertices as the extracted isosurface (the paper: 1.19 M fine control
  // points for a 0.98 M-vertex isosurface).
  int levels = 0;
  // Base mesh size: base_vertices if non-zero, else base_ratio times the
  // extracted vertex count.
  std::size_t base_vertices = 0;
  double base_ratio = 0.0625;
  // While more than kUncoveredWarning of the isosurface lies more than
  // kUncoveredCells cells from every fine control point, simplify again to
  // twice the base mesh's vertex count and fit again (at most kBaseAttempts
  // tries in all, and while the base stays under a quarter of the
  // isosurface's vertices), if the levels are automatic (levels == 0). The CLI
  // turns it on when no base size is given.
  bool grow_base_until_covered = false;
  // Valence-lowering flips when the paper's collapse rules stall (see
  // SimplifyOptions::valence_flips): a smaller base mesh on high-genus surfaces.
  bool valence_flips = true;
  // Quantization step in cells (see IswEncodeOptions::step); the expected
  // RMSE it adds is about half of it.
  double step_cells = 0.01;
  // Narrow band of the signed-distance field in cells (0: the whole grid).
  double distance_band_cells = 3.0;
  ShrinkWrapOptions shrink_wrap;
  // Give the shrink-wrap the extracted surface for its coverage pull
  // (ShrinkWrapOptions::surface).
  bool coverage_pull = true;
  // Percentages for the error summary (the base-mesh row is added).
  std::vector<double> summary_percents{100, 20, 10, 5};
  // Keep the extracted triangle mesh in the result (for comparisons).
  bool keep_extracted_mesh = false;
  // Decode the encoded bytes once more and require exactly the coded
  // coefficients in the coded order (a self-check; the round-trip tests
  // check the coder). The summary never needs it: it is made from what the
  // encoder stored. The chunk decoding is serial: about 1.5 s on miranda.
  bool verify_file = false;
};

// Wall-clock seconds per stage. The signed-distance field is computed
// alongside the base mesh; `distance` is only the wait for it afterwards, so
// that the stages add up to the whole conversion.
struct ConvertTimings {
  double extract = 0, simplify = 0, distance = 0, fit = 0, analysis = 0, encode = 0, evaluate = 0;
  double total() const { return extract + simplify + distance + fit + analysis + encode + evaluate; }
};


// Share of the fine control points that may lie more than a cell off the
// isosurface before convert_volume() warns (see ConvertResult::fit_isosurface).
inline constexpr double kFarPointsWarning = 0.005;
// Share of the isosurface that may lie more than kUncoveredCells cells from
// every fine control point before convert_volume() warns.
inline constexpr double kUncoveredCells = 2.0;
inline constexpr double kUncoveredWarning = 0.01;
// More than this share of folded fine faces (ConvertResult::tangled_share)
// adds a warning without a pre-filter: on noisy scans and fine-grained fields
// (stent, HCCI, MRI, embryo, miranda: 3-5%) the folds sit on necks, tunnels
// and specks under a cell across, which smooth_sigma = 1 removes (stent
// 5.1% -> 0.29%, HCCI 4.4% -> 0.12%). Where the fit did not follow the
// surface (the far-points or uncovered warning, or fewer than half as many
// fine points as extracted vertices), the warning, with or without a
// pre-filter, names a larger base mesh or more levels instead.
inline constexpr double kFoldedWarning = 0.01;
inline constexpr int kBaseAttempts = 3;

struct ConvertResult {
  std::string bytes;  // the .isw file
  PolygonMesh extracted_mesh;  // with keep_extracted_mesh
  IsosurfaceReport extraction;
  simplify::SimplifyReport simplification;
  ShrinkWrapResult fit;  // positions: the fitted fine control points
  int levels = 0;
  std::size_t extracted_vertices = 0, base_vertices = 0, fine_vertices = 0, fine_faces = 0;
  double cell_size = 1;
  ConvertTimings seconds;
  // The fitted fine control points against the isosurface of the field they
  // were fitted to (first order, cells). More than kFarPointsWarning of them
  // farther than a cell away adds a warning.
  IsosurfaceDistance fit_isosurface;
  // The share of the extracted isosurface's vertices (sampled) farther than
  // kUncoveredCells cells from every fine control point (share_farther_than):
  // what the fit left out. More than kUncoveredWarning adds a warning.
  double uncovered_share = 0;
  // The share of the fine faces whose normal disagrees with the field
  // gradient (ShrinkWrapResult::tangled_faces): folds of the parameterization.
  double tangled_share() const;
  // Tries at the base mesh (ConvertOptions::grow_base_until_covered) and the
  // first one's vertex count; base_vertices is the last one's.
  int base_attempts = 1;
  std::size_t first_base_vertices = 0;
  // error_table() of the file written, as `isowave stats` reports it: rows
  // against the full-resolution decode; the quantization error separately.
  std::vector<RateDistortionRow> summary;
  QuantizationError quantization;
  std::vector<std::string> warnings;  // e.g. a base mesh kept large by the topology
};

// Converts one isosurface of `volume`. `source` names the input in the file's
// metadata. Throws Error for invalid options, an empty isosurface, and what
// the stages throw.
ConvertResult convert_volume(const Volume& volume, const std::string& source, const ConvertOptions& options,
                             ProgressSink& progress = no_progress());

// Fine control point count of `levels` subdivisions of `base` (no refinement).
std::size_t fine_vertex_count(const PolygonMesh& base, int levels);

}  // namespace isowave
