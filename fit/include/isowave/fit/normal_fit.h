#pragma once
// The normal fit (issue #47): wavelet detail that is one scalar along a known
// normal, as in normal meshes (Guskov et al. 2000) and MPEG V-DMC, for the
// approximating bicubic scheme as variational normal meshes (Friedel et al.
// 2004) do it for Loop: the output control points, not the control polygon's
// prediction, are fitted to the surface.
//
// The representation and the fit:
//  - each coefficient is s_i n_i, n_i the unit direction the coder will use
//    (`directions`, from the base as the first level's fit leaves it: the
//    frame base), the base points free 3-vectors;
//  - level by level, every entry up to the level (the base and the scalars
//    of levels 1..j) is solved for at once, with a little damping, so that synthesis puts every
//    control point of level j on the isosurface of the trilinear field in
//    the least-squares sense: lifted wavelets have almost no mean, so the
//    smooth part of a level's error can only come from coarser entries.
// Each control point's target is where its line along n pierces the
// isosurface (the nearest crossing within a reach proportional to the level's
// edge length); the residual is its distance to the isosurface's tangent
// plane there (point-to-plane), minimized by Gauss-Newton rounds, each a
// conjugate-gradient solve through the synthesis and its transpose
// (synthesize_level_transpose). A coefficient whose point's line has no
// admissible crossing within the reach (after the normal rounds) becomes
// non-normal: a free 3-vector aimed along the field gradient, or at the
// extracted surface's nearest point; so do the coefficients on boundary
// curves (box faces), whose points are held in their face's plane. A
// crossing is admissible inside the volume's box, where the line leaves the
// region its surface encloses (not the far side of a thin sheet).
//
// Deterministic for any thread count (fixed-block reductions).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/progress.h"
#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/orientation.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

struct NormalFitResult;

struct NormalFitOptions {
  // Gauss-Newton rounds per level, 1..50; after the first max(1, rounds / 2)
  // the level's coefficients whose lines miss become free.
  int rounds = 4;
  int cg_iterations = 16;  // conjugate-gradient steps per round, 1..500
  // The piercing search's reach: this many times the level's mean edge
  // length, at least min_reach_cells cells; finite and > 0. A round's step
  // is shortened so that no point moves farther.
  double reach_edges = 1.0;
  double min_reach_cells = 1.0;
  // The extracted isosurface (kept by pointer): a point whose lines miss the
  // isosurface aims at its nearest point. nullptr: such a point has no target.
  const PolygonMesh* surface = nullptr;
  // With `surface`: on levels whose edges average at most a cell, every
  // extracted vertex farther than a cell from the level's points pulls the
  // nearest within 4 cells toward it (the shrink-wrap's coverage pull, as
  // point-to-point residuals; not in a pass's last round).
  bool coverage_pull = true;
  // Which way the base mesh's normals point (extraction's): a normal line
  // pierces only where it leaves the region its surface encloses.
  Orientation orientation = Orientation::TowardLower;
  // A fit of the same base positions to fewer levels (kept by pointer; its
  // `coefficients`, `non_normal` and `levels` are read): this fit starts from
  // its entries and fits only the finer levels, as levels by error tries one
  // level more. nullptr: from the base.
  const NormalFitResult* start = nullptr;
};

// Per level fitted, 1..L.
struct NormalFitLevelStatistics {
  int level = 0;
  std::size_t vertices = 0;       // control points of the level
  std::size_t coefficients = 0;   // the level's f and e coefficients
  std::size_t non_normal = 0;     // of those, the free ones
  std::size_t unpierced = 0;      // control points with no target at all (only without `surface`)
  double rms_cells = 0;           // RMS distance of the level's control points to their targets' tangent planes
  double max_cells = 0;
  double seconds = 0;
};

struct NormalFitResult {
  std::vector<Vec3> positions;  // level-L control points, ready for analyze()
  // The base the directions came from (the base after the first level's
  // fit; the base positions given with one level): the coder's frame base
  // (IswEncodeOptions::frame_base).
  std::vector<Vec3> frame_base;
  // The coarse-to-fine array fitted (base points, then each coefficient, a
  // multiple of its direction unless non-normal): analyze() of `positions`
  // up to rounding.
  std::vector<Vec3> coefficients;
  // Per coefficient entry [vertex_count(0), fine): 1 if non-normal.
  std::vector<std::uint8_t> non_normal;
  std::vector<NormalFitLevelStatistics> levels;
  std::size_t non_normal_count() const;
};

// The unit direction of every entry of the coarse-to-fine array (fine vertex
// count entries) for base control points `base`: the coder's local-frame
// normals (codec: isw_frame_normals). Called with the base positions given
// and again with the frame base; the coder must send the last as its frame base.
using NormalDirections = std::function<std::vector<Vec3>(const std::vector<Vec3>& base)>;

// Fits `hierarchy` to the isosurface `iso` of `field` from `base_positions`.
// Throws Error(InvalidArgument) for too few base positions, a non-finite one,
// a field with fewer than 2 samples along an axis, directions of the wrong
// size, an option out of range, or a start that is not a fit of the same
// base positions to fewer levels. Memory: about 400 bytes per control point
// of the finest level (the conjugate gradients' five vectors are 120), and
// the extracted surface's bins. Cost: per level j fitted, rounds x
// (cg_iterations + 2) syntheses up to level j and as many transposes, and a
// root search per control point and round.
NormalFitResult normal_fit(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                           const Volume& field, double iso, const NormalDirections& directions,
                           const NormalFitOptions& options = {}, ProgressSink& progress = no_progress());

}  // namespace isowave
