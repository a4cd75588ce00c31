#pragma once
// Shrink-wrap fitting of a subdivision hierarchy to an isosurface (Bertram et
// al. 2000, Sec. 4.2). Starting from the base mesh, each level gets a few
// rounds of relaxation and attraction (wrap_steps.h) and is then refined to
// the next with the wavelet subdivision operator S (subdivide_level), up to
// level L. Level L is then corrected onto the isosurface of the trilinear
// scalar field (correction.h), and its folds repaired (fold_repair.h). Not in
// the paper: folds on the coarser levels are repaired against the
// signed-distance field; small closed components (droplets) are fitted along
// rays from their centroid; with the extracted surface, the fine levels are
// pulled toward the parts of it they leave out (the coverage pull).
//
// Every pass is a Jacobi update or colour-by-colour (TBB), so results are
// identical for any thread count, and none writes a non-finite position.
// Cost per round: O(vertices of the level) plus a few trilinear samples per
// vertex. Memory: the finest level's connectivity (about 60 bytes per
// vertex), two position buffers and single-precision face normals (12 bytes
// per face), a copy of the scalar field, and on level L a few flags per
// vertex and face; large buffers live on transparent huge pages.
#include <cstddef>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/progress.h"
#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/correction.h"
#include "isowave/fit/fold_repair.h"
#include "isowave/fit/orientation.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/fit/wrap_level_mesh.h"
#include "isowave/fit/wrap_steps.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// Lengths in cells (the volume's cell_size()) unless said otherwise.
struct ShrinkWrapOptions {
  int iterations = 3;                // relaxation + attraction rounds on levels 0 .. L-1, 0..100
  int final_level_iterations = 1;    // the same on level L, 0..100
  double relaxation_weight = 0.5;    // (0, 1]; the paper's 0.5 averages old position and centroid
  AttractionOptions attraction;
  // Droplets: closed base components (no boundary, box-held or sharp vertex)
  // of at most droplet_vertices vertices, all within droplet_cells of their
  // centroid. Their free vertices relax within their tangent planes and are
  // attracted and corrected along rays from the component's centroid, where
  // the paper's steps would fold them. droplet_vertices 0: off; cells >= 0.
  std::size_t droplet_vertices = 8;
  double droplet_cells = 3.0;
  // The extracted isosurface the distance field was built from (kept by
  // pointer), for the coverage pull and CorrectionStatistics::from_extracted_surface.
  // nullptr: neither runs.
  const PolygonMesh* surface = nullptr;
  // Coverage pull (fit/src/coverage_pull.h), with `surface`, on levels whose
  // edges average at most pull_max_edge_cells (>= 0): each extracted vertex
  // over pull_covered_cells (> 0) from the fit pulls its nearest control
  // point within pull_reach_cells (on level L final_pull_reach_cells; both
  // >= covered). Below L after the level's last round; on level L after
  // the correction and untangle(), the pulled points then corrected onto
  // the isosurface (one without a root, or folding more faces, goes back).
  bool coverage_pull = true;
  double pull_max_edge_cells = 1.0;
  double pull_covered_cells = 1.0;
  double pull_reach_cells = 4.0;
  double final_pull_reach_cells = 8.0;
  bool final_correction = true;       // correct level L onto the isosurface (correction.h)
  double correction_max_cells = 2.0;  // the correction's and the fold repair's reach, > 0
  // A free vertex without a root within reach starts again from a nearby
  // zero of the signed-distance field (CorrectionStatistics::from_nearest_point).
  bool correction_from_nearest_point = true;
  int untangle_rounds = 3;         // untangle() on level L after the correction, 0..100
  int coarse_untangle_rounds = 2;  // untangle() on levels 0 .. L-1 against the distance field, 0..100
  // unfold() on level L, last (0..100 rounds); skipped when more than
  // unfold_max_folded_fraction (in [0, 1]) of the faces fold, where it would
  // cost seconds and raise the wavelet RMSE.
  int unfold_rounds = 10;
  double unfold_max_folded_fraction = 0.02;
  bool keep_levels = false;  // keep every coarser level's fitted positions (ShrinkWrapResult::level_positions)
};

// One level's counts and times (seconds, wall clock).
struct WrapLevelStatistics {
  int level = 0;
  std::size_t vertices = 0;
  std::size_t boundary_vertices = 0;  // held on a box face
  std::size_t fixed_vertices = 0;
  AttractionStatistics last_attraction;
  double seconds = 0;             // the whole level, the phases below included
  double seconds_setup = 0;       // refinement to this level and its connectivity
  double seconds_relaxation = 0;  // all rounds
  double seconds_attraction = 0;  // all rounds
  double seconds_correction = 0;  // level L only
  double seconds_untangle = 0;    // untangle() on level L, coarse_untangle_rounds below
  double seconds_pull = 0;        // all rounds
  double seconds_unfold = 0;      // level L only
  double mean_edge_cells = 0;     // after refinement (with `surface` only; from at most about 2^18 vertices)
  std::size_t uncovered_samples = 0;  // the level's pull (0 if it did not pull)
  std::size_t pulled_vertices = 0;
  std::size_t pulled_back = 0;  // level L: pulled points returned (no root on the isosurface, or folding)
};

struct ShrinkWrapResult {
  // Level-L control points in the hierarchy's order: ready for analyze().
  std::vector<Vec3> positions;
  // With keep_levels: level_positions[l] for l in [0, L) after fitting level l.
  std::vector<std::vector<Vec3>> level_positions;
  std::vector<WrapLevelStatistics> levels;
  CorrectionStatistics correction;  // zeros when the correction is off
  UntangleStatistics untangle;
  UnfoldStatistics unfold;  // unless skipped, folded_after counts level L's folded faces; zeros when off
  // Level-L faces folded in the result as last counted: the unfold's count,
  // or when it was skipped or off untangle()'s (before the pull, which
  // changes few), or without untangle() a count after the pull.
  std::size_t folded_faces = 0;
};

// Fits the hierarchy to the zero set of `distance` (computed from `field`,
// on the same grid) starting from the base control points. Throws
// Error(InvalidArgument) if base_positions has fewer than vertex_count(0)
// entries, a non-finite one, one more than a cell outside the volume's box,
// or one on a boundary of the base more than a cell from the box's faces;
// if most base vertex normals disagree with distance.flip's orientation;
// if the grids differ or have fewer than 2 samples along an axis; or if an
// option is out of its range above. Reports progress as one stage.
ShrinkWrapResult shrink_wrap(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                             const SignedDistanceField& distance, const Volume& field,
                             const ShrinkWrapOptions& options = {}, ProgressSink& progress = no_progress());

}  // namespace isowave
