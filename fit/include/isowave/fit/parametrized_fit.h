#pragma once
// The parametrization-based fit (issue #33; Lee, Sweldens, Schroeder, Cowsar,
// Dobkin, MAPS, SIGGRAPH 1998, as Progressive Geometry Compression builds its
// semi-regular meshes): the level-L control points are the points of the
// input surface at the parameter positions of the hierarchy's refinement of
// each base face, read through the simplifier's map (simplify/surface_map.h).
//
// Parameter domain: base face f of n corners has a chart, the regular n-gon
// with unit edges, corner k (the face's vertex k) at angle 2 pi k / n,
// counter-clockwise like the face. The map's triangles of f split the chart;
// adjacent charts agree along their shared base edge (both linear with unit
// speed), so a point on a base edge or vertex has one surface point. Each
// refinement puts the f vertex of a face at the mean of its corners and the e
// vertex of an edge at the mean of its ends, in the chart (the dyadic
// positions); v vertices keep their parent's position.
//
// Inverse map: a parameter point (base triangle T, u, v) goes back through
// the map's history (the simplifier records one: fit/src/history_inverse.h),
// operation by operation, to the input triangle it comes from: the exact
// inverse of the map the collapse charts compose, a bijection. A map without
// a history (built by hand) is inverted approximately instead: the point is
// located among the input triangles with a vertex mapped into T or spanning
// T around one of its corners, unfolded isometrically into T's plane
// (fit/src/surface_map_inverse.h). Either way the surface point is a
// barycentric combination of an input triangle's vertices, so it lies on the
// surface. Results are identical for any thread count (TBB).
#include <cstddef>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/progress.h"
#include "isowave/core/vec3.h"
#include "isowave/simplify/surface_map.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

struct ParametrizedFitStatistics {
  std::size_t fine_vertices = 0;    // control points of level L
  // Parameter points the inverse found in no triangle (the unfolded input
  // triangles, or through the history a chart's triangles, beyond rounding);
  // the triangle whose smallest barycentric coordinate is largest gave the
  // point, clamped onto it. 0 expected with a history.
  std::size_t fallback_points = 0;
  double seconds = 0;  // wall clock
};

struct ParametrizedFitResult {
  // Level-L control points in the hierarchy's order: ready for analyze().
  std::vector<Vec3> positions;
  ParametrizedFitStatistics statistics;
};

// Fits the hierarchy's level L = hierarchy.levels() to `surface` through
// `map` (built by the simplifier from `surface` onto the base mesh whose
// topology is hierarchy.base() and positions base_positions). Throws
// Error(InvalidArgument) when the map does not fit: array sizes differ from
// the surface's vertex count or from each other, an index is out of range, a
// base face of n corners does not have exactly n - 2 triangles that use only
// its corners (each once per triangle, all of them, positively oriented and
// tiling its chart), or a barycentric coordinate is not finite or outside
// [0, 1] by more than 1e-6, or its history is inconsistent (check_history);
// or when base_positions has fewer than vertex_count(0) entries or a
// non-finite one. Throws Error(Format) for a
// surface with an index out of range or a non-finite position
// (validate_indices). Faces of the surface with more than 3 corners are fanned
// from their first corner. Reports progress as one stage.
// Cost: with a history, O(history) to check it and, per fine vertex, the
// operations between its base triangle and the input (a few dozen), about 40
// bytes per fine vertex besides the result; without, O(fine vertices +
// surface corners), at most about 60 bytes per fine vertex and 60 per surface
// triangle (surface_map_inverse.h).
ParametrizedFitResult parametrized_fit(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                                       const PolygonMesh& surface, const simplify::SurfaceMap& map,
                                       ProgressSink& progress = no_progress());

}  // namespace isowave
