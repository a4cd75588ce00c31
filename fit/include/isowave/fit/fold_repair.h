#pragma once
// Repair of folds (not in the paper): faces whose normal disagrees with the
// field gradient at their centroid (orientation.h), left where the fit meets
// features thinner than its mesh or is attracted onto a neighbouring sheet.
// untangle() smooths the corners of folded faces; unfold() opens the folds a
// few faces wide that untangle() cannot. Both move vertices only onto the
// isosurface of the trilinear field (as correct_to_isosurface(), at most
// max_move_cells > 0 cells; a vertex without a root there stays), work in
// place on at least vertex_count positions, fill the field's non-finite
// samples as correct_to_isosurface() does, and give the same result for any
// thread count.
#include <cstddef>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/orientation.h"
#include "isowave/fit/wrap_level_mesh.h"

namespace isowave {

struct UntangleStatistics {
  std::size_t folded_before = 0;  // folded faces
  std::size_t folded_after = 0;
  int rounds = 0;  // rounds kept
};

// Up to `rounds` (>= 0) rounds. Each moves the corners of the folded faces to
// the centroid of their neighbours (boundary ones along their boundary) and
// back onto the isosurface along the gradient; a moved vertex around which
// more faces fold than before goes back. A round that does not lower the
// number of folded faces is undone and ends the repair. A round costs
// O(corners and their faces) plus byte scans of the level.
UntangleStatistics untangle(const WrapLevelMesh& mesh, const Volume& field, double iso, Orientation orientation,
                            int rounds, double max_move_cells, std::vector<Vec3>& positions);

struct UnfoldStatistics {
  std::size_t folded_before = 0;  // folded faces
  std::size_t folded_after = 0;
  std::size_t moved = 0;  // vertex moves, all rounds
  int rounds = 0;         // rounds that moved a vertex
  // shrink_wrap() only: more than unfold_max_folded_fraction of the faces
  // were folded after untangle(); both counts are then untangle()'s.
  bool skipped = false;
};

// Up to `rounds` (>= 0) rounds, until one moves no vertex. Each movable
// corner of a folded face tries a few places (its neighbours' centroid and
// its place mirrored through it, the points half-way and nine tenths of the
// way to each neighbour, its faces' centroids; along its boundary curve for a
// boundary vertex), each put onto the isosurface, and takes the one that most
// lowers the cost of its faces (10 per folded face plus minus the cosine
// between its normal and the gradient) plus its squared move in cells. The
// corners are coloured so that two sharing a face differ and move colour by
// colour (Gauss-Seidel across colours). One scan of the level's faces, then
// per round O(corners x (valence + faces around) x trilinear samples).
UnfoldStatistics unfold(const WrapLevelMesh& mesh, const Volume& field, double iso, Orientation orientation,
                        int rounds, double max_move_cells, std::vector<Vec3>& positions);

// The faces of `mesh`, with control points `positions` (at least
// mesh.vertex_count), whose normal disagrees with the gradient of `field` at
// their centroid (orientation.h): the folds a fit reports. Parallel,
// deterministic; one gradient sample per face.
std::size_t count_folded_faces(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, const Volume& field,
                               Orientation orientation);

// Takes back the moves from `before` to `positions` (both at least
// mesh.vertex_count) of the corners of every face folded (count_folded_faces'
// test) at `positions` but not at `before`, round after round until no such
// face is left, so that a pass moving points folds no face it did not find
// folded. Returns the number of vertices taken back. Each round one parallel
// scan of the faces; a round takes back at least one move, and in practice
// 2-4 rounds suffice.
std::size_t take_back_folding_moves(const WrapLevelMesh& mesh, const Volume& field, Orientation orientation,
                                    const std::vector<Vec3>& before, std::vector<Vec3>& positions);

}  // namespace isowave
