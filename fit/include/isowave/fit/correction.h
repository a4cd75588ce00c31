#pragma once
// The shrink-wrap's final correction (Bertram et al. 2000, Sec. 4.2: the
// finest level's vertices move onto the isosurface of the trilinearly
// interpolated scalar field), with fallbacks, not in the paper, for the few
// vertices whose gradient line has no root within reach.
#include <cstddef>
#include <optional>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/orientation.h"
#include "isowave/fit/wrap_level_mesh.h"

namespace isowave {

// Counts over the movable vertices; moves in cells.
struct CorrectionStatistics {
  std::size_t movable = 0;
  std::size_t corrected = 0;  // now on the interpolated isosurface (the fallbacks below included)
  std::size_t failed = 0;     // no root found by any means: left in place
  // From a nearby zero of the signed-distance field within 1.5 ranges (shrink_wrap() only,
  // ShrinkWrapOptions::correction_from_nearest_point).
  std::size_t from_nearest_point = 0;
  // From the centroid of their neighbours, once those were corrected (up to five Jacobi rounds).
  std::size_t from_neighbours = 0;
  // The nearest root within three ranges along the 26 directions to a cube's neighbours (16 in
  // the face plane for a box-held vertex) at which no more of its faces fold than before; for
  // at most 1% of the vertices (at least 10,000), the first by index.
  std::size_t from_wide_search = 0;
  // Vertices a cell or more from the extracted surface (by its distance field): from its nearest
  // point within 16 cells. Their faces' folds are not checked.
  std::size_t from_extracted_surface = 0;
  // Free vertices within a cell of a box face whose root lies outside the box: along the
  // gradient's part parallel to that face; failing that (and for box-held vertices) the nearest
  // root in the face's plane (16 directions).
  std::size_t along_box_face = 0;
  double mean_move_cells = 0;
  double max_move_cells = 0;
};

// The fallbacks correct_to_isosurface() runs after the neighbours' centroid.
struct CorrectionFallbacks {
  // The wide search (CorrectionStatistics::from_wide_search), judging folds
  // against faces of this orientation; nullopt: off.
  std::optional<Orientation> wide_search;
  // The extracted surface and its signed-distance field on the field's grid
  // (CorrectionStatistics::from_extracted_surface); both or neither.
  const PolygonMesh* surface = nullptr;
  const Volume* surface_distance = nullptr;
};

// Moves each movable vertex along the gradient of the trilinear field (a
// box-held one along its projection into its face) to where the field equals
// iso, within about 1e-4 cells (Newton steps, then a bracketed search),
// searching at most max_move_cells (> 0) cells; then the fallbacks above, in
// the order of CorrectionStatistics. In place; positions holds at least
// vertex_count entries. The field's non-finite samples are filled as the
// shrink-wrap fills them (fill_non_finite_samples, in a copy made only when
// there are any). O(vertices x a few samples), the wide search up to 624
// samples per vertex it runs for.
CorrectionStatistics correct_to_isosurface(const WrapLevelMesh& mesh, const Volume& field, double iso,
                                           double max_move_cells, std::vector<Vec3>& positions,
                                           const CorrectionFallbacks& fallbacks = {});

}  // namespace isowave
