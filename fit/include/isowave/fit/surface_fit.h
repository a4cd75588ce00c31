#pragma once
// The one entry of the fit stage (Bertram et al. 2000, Sec. 4.2; issues #33
// and #47): a base mesh's fine control points fitted to the isosurface by
// the method asked for, at the levels the rule picks (levels by error), with
// the method's own repairs, and the figures a conversion reports of the fit.
// A new fit adds a method here and a room beside normal_fit.cpp, not a branch
// in the pipeline.
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/progress.h"
#include "isowave/core/surface_error.h"
#include "isowave/core/volume.h"
#include "isowave/fit/fit_quality.h"
#include "isowave/fit/normal_fit.h"
#include "isowave/fit/orientation.h"
#include "isowave/fit/parametrized_fit.h"
#include "isowave/fit/shrink_wrap.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/simplify/surface_map.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// How the fine control points are fitted to the isosurface.
enum class FitMethod {
  ShrinkWrap,       // the paper's shrink-wrap (Sec. 4.2; fit/shrink_wrap.h)
  Parametrization,  // surface points at the parameter positions of a MAPS map (fit/parametrized_fit.h)
  Normal,           // detail as scalars along the coder's frame normals (fit/normal_fit.h)
};

// Where the parametrization puts the fine points (FitMethod::Parametrization).
enum class FinePoints {
  OnExtractedSurface,  // the map's points, on the marching-cubes triangles
  // Those moved along the field gradient onto the isosurface of the trilinear
  // field (correct_to_isosurface, within kFinePointMoveCells): off the
  // marching-cubes mesh's own error, nearer the isosurface than it. A move
  // that folds a face is taken back, and the corners of faces still folded
  // move to unfold them (unfold(), kFineUnfoldRounds).
  OnTrilinearIsosurface,
};

// Which levels fit_surface() tries.
struct LevelRule {
  int fixed_levels = 0;          // 1..6: that level alone; 0: by error
  double max_error_cells = 0;    // by error: the bound on D, cells (>= 0)
  double max_fine_vertices = 0;  // by error: never a level whose fine mesh has more vertices (but level 1)
};

// One level a fit tried (issue #33, item 4): its fitted fine mesh before
// quantization (the parametrization's before its points move onto the
// trilinear isosurface; the shrink-wrap's after its own correction) against
// the extracted isosurface.
struct LevelReport {
  int levels = 0;
  std::size_t fine_vertices = 0;
  // RMS distances of D (surface_error.h), cells: fine mesh -> isosurface and
  // isosurface -> fine mesh.
  double forward_rms_cells = 0, backward_rms_cells = 0;
  double d_cells() const { return forward_rms_cells > backward_rms_cells ? forward_rms_cells : backward_rms_cells; }
  // Share of the fine faces folded against the field gradient, as the fit
  // counts them (count_folded_faces; the shrink-wrap's ShrinkWrapResult::folded_faces).
  double folded_share = 0;
  // Fine face areas (vector areas) over their mean.
  double stretch_min = 0, stretch_median = 0, stretch_max = 0;
  double seconds = 0;  // wall clock: the level's fit and these figures
};

// The parametrization's fine points move at most this far (cells) onto the
// trilinear isosurface, in at most this many unfold rounds (FinePoints).
inline constexpr double kFinePointMoveCells = 0.5;
inline constexpr int kFineUnfoldRounds = 10;
// SurfaceFit::uncovered_share counts the isosurface farther than this (cells)
// from every fine control point.
inline constexpr double kUncoveredCells = 2.0;
// About the peak bytes per fine control point of a fit or a conversion, with
// the volume, the distance field and the extracted mesh (an upper bound of
// the peaks in docs/MEASUREMENTS.md).
inline constexpr double kFitBytesPerFineVertex = 300;

// What every fit reads. Pointers must outlive the call.
struct SurfaceFitInput {
  const Volume* field = nullptr;          // the field the surface was extracted from
  double iso = 0;                         // its isovalue
  Orientation orientation = Orientation::TowardLower;
  const PolygonMesh* isosurface = nullptr;         // the extracted mesh (world units)
  const SurfaceErrorReference* reference = nullptr;  // D's reference: samples of the extracted mesh
  double cell_size = 1;                            // world units per cell (> 0)
  // FitMethod::ShrinkWrap: the signed-distance field of `field`.
  const SignedDistanceField* distance = nullptr;
  // FitMethod::Parametrization: the simplification's map of the isosurface
  // onto the base (simplify::SurfaceMapping::Build).
  const simplify::SurfaceMap* map = nullptr;
  // FitMethod::Normal: the directions of a hierarchy's coefficients (the
  // coder's frame normals, which the fit cannot name: codec comes later).
  std::function<NormalDirections(const SubdivisionHierarchy&)> directions;
};

struct SurfaceFitOptions {
  FitMethod method = FitMethod::Normal;
  LevelRule levels;
  FinePoints fine_points = FinePoints::OnTrilinearIsosurface;  // FitMethod::Parametrization
  ShrinkWrapOptions shrink_wrap;  // `surface` is set to the input's isosurface
  // FitMethod::Normal; `surface`, `orientation`, `coverage_pull` (from
  // shrink_wrap's) and `start` are set from the input.
  NormalFitOptions normal;
};

struct SurfaceFit {
  // The hierarchy over the base: control_mesh(levels, points.positions) is the fitted fine mesh.
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  ShrinkWrapResult points;  // positions: the fitted fine control points (every method); folded_faces
  ParametrizedFitStatistics parametrization;  // FitMethod::Parametrization
  // FitMethod::Normal: per level fitted (1..L), the non-normal coefficients
  // and the base the directions came from (the coder's frame base).
  std::vector<NormalFitLevelStatistics> normal_levels;
  std::size_t non_normal_coefficients = 0;
  std::vector<Vec3> frame_base;
  std::vector<LevelReport> level_reports;  // every level tried, in order; the last is `levels`
  int levels = 0;
  std::size_t fine_vertices = 0, fine_faces = 0;
  // The fine control points against the isosurface of the field (first order, cells).
  IsosurfaceDistance isosurface;
  // The share of the extracted isosurface's vertices (sampled: every
  // stride-th, at most 100,000) farther than kUncoveredCells cells from every
  // fine control point (share_farther_than): what the fit left out.
  double uncovered_share = 0;
};

// Fits `base` (its positions the start) by options.method at the levels of
// options.levels: L = fixed_levels, or L = 1, 2, ... until the first whose D
// against input.reference is at most max_error_cells, L = 6, or the last
// before a fine mesh of more than max_fine_vertices; each level tried is in
// level_reports, and a level's predecessor is released before the next is
// fitted (the normal fit continues it). Throws Error(InvalidArgument) for a
// level whose fine mesh would not fit in this machine's memory (about
// kFitBytesPerFineVertex per fine control point, checked before it is
// built), and what the method throws. Cost per level: the method's fit, D
// (about linear in the fine faces plus the reference's samples) and a pass
// over the fine faces.
SurfaceFit fit_surface(const PolygonMesh& base, const SurfaceFitInput& input, const SurfaceFitOptions& options,
                       ProgressSink& progress = no_progress());

}  // namespace isowave
