#pragma once
// Quality of a fitted control mesh (one level of a shrink-wrapped hierarchy),
// the figures the targets are stated in. Distances are in cells
// (Volume::cell_size()).
//
// - isosurface: the first-order distance |f(x) - iso| / |grad f(x)| of each
//   vertex, f the trilinearly interpolated field (as in the final correction);
// - surface: exact distance of each vertex to the extracted triangle mesh;
// - coverage: exact distance of each extracted-mesh vertex to the fitted mesh
//   (quads split into two triangles), so gaps and missed features show;
// - folds: faces whose normal disagrees with the field's gradient at the
//   face centroid (orientation.h); zero-area faces count as folded;
// - evenness: each face's area divided by the mean face area of its patch
//   (the faces descending from one base face).
// Sharp (fixed) vertices are included in every figure.
#include <cstddef>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/volume.h"
#include "isowave/core/binned_surface_distance.h"
#include "isowave/fit/orientation.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// The fit target's maximum distance of the fine vertices from the extracted
// mesh, in cells (FitQuality::surface_far counts those beyond it).
inline constexpr double kSurfaceFarCells = 0.5;

// Whether a fine mesh with `fine_vertices` is too coarse to follow an
// isosurface extracted with `isosurface_vertices`: fewer than half as many.
// Such a fit stays inside the surface with many faces folded, and its folds
// come from the base mesh, not from features under a cell.
constexpr bool fine_mesh_too_coarse(std::size_t fine_vertices, std::size_t isosurface_vertices) {
  return 2 * fine_vertices < isosurface_vertices;
}

struct FitQuality {
  int level = 0;
  std::size_t vertices = 0;
  std::size_t faces = 0;
  std::size_t nonfinite_vertices = 0;

  double isosurface_rms = 0, isosurface_max = 0;
  std::size_t isosurface_undefined = 0;  // vertices off the isovalue with a zero or non-finite gradient (left out)
  // Vertices more than a cell off: where the field is nearly flat a few of
  // these can dominate the RMS.
  std::size_t isosurface_far = 0;

  double surface_rms = 0, surface_max = 0;
  // Vertices farther than the target's maximum (kSurfaceFarCells) from the
  // extracted mesh: how many points the maximum stands for.
  std::size_t surface_far = 0;

  double coverage_rms = 0, coverage_p99 = 0, coverage_max = 0;

  std::size_t folded_faces = 0;
  double folded_fraction = 0;  // of the faces, in [0, 1]

  // Face area relative to its patch's mean: percentiles and spread.
  double area_ratio_min = 0, area_ratio_p1 = 0, area_ratio_median = 0, area_ratio_p99 = 0, area_ratio_max = 0;
  double area_ratio_deviation = 0;  // standard deviation of the ratio
};

// First-order distance |f(x) - iso| / |grad f(x)| of points to the isosurface
// of the trilinearly interpolated field (as in the final correction), in
// cells: RMS and maximum over the points where it is defined (0 where the
// field equals iso; elsewhere a zero or non-finite gradient leaves it
// undefined: `undefined`), and how many lie farther than
// `far_cells`. Parallel, deterministic, O(points).
struct IsosurfaceDistance {
  double rms = 0, max = 0;
  std::size_t undefined = 0;
  std::size_t far = 0;
};
IsosurfaceDistance isosurface_distance(const std::vector<Vec3>& points, std::size_t count, const Volume& field,
                                       double iso, double far_cells);

// How far the extracted triangles themselves lie from the isosurface of the
// trilinear field (as isosurface_distance() measures a point) at 7 points of
// each triangle (centroid, edge midpoints and the points halfway between the
// centroid and each corner), in cells: RMS weighted by triangle area, and
// maximum. Marching cubes' flat triangles cut across the curved trilinear
// isosurface, so a fit whose points lie on that isosurface cannot come much
// nearer to them than this. Polygons count as fans of
// triangles; samples without a gradient are left out. Parallel,
// deterministic, O(triangles).
struct SurfaceDeviation {
  double rms = 0, max = 0;
};
SurfaceDeviation extracted_surface_deviation(const PolygonMesh& extracted, const Volume& field, double iso);

// How much of a surface a fitted mesh leaves out, cheaply: the share of the
// sampled `reference` points (every `stride`-th, stride >= 1) farther than
// `distance` from every one of the first `count` `fitted` points. A point
// test, so it can only overstate the share farther than `distance` from the
// fitted surface, by the points within a fitted face's reach of its corners
// (fine faces are mostly a fraction of a cell; where they are stretched over
// thin features it shows). Parallel and deterministic; O(count log count) to sort the fitted points into cubes of
// side `distance`, then 27 cube lookups per sample.
double share_farther_than(const std::vector<Vec3>& reference, std::size_t stride, const std::vector<Vec3>& fitted,
                          std::size_t count, double distance);

// Measures level `level` of `hierarchy` with control points `positions` (at
// least vertex_count(level)) against the extracted mesh (`extracted`, and
// `extracted_distance` built from it) and the scalar field. Parallel (TBB),
// deterministic. O(n) for the fitted mesh's bins, then a distance query per
// vertex each way (BinnedSurfaceDistance: exact, as CGAL's AABB tree).
// Folds are judged against faces of `orientation`.
FitQuality measure_fit_quality(const SubdivisionHierarchy& hierarchy, int level, const std::vector<Vec3>& positions,
                               const PolygonMesh& extracted, const BinnedSurfaceDistance& extracted_distance,
                               const Volume& field, double iso, Orientation orientation);

// The value below which `fraction` (in [0, 1]) of `values` lie (nearest rank);
// reorders `values`. 0 for an empty vector.
double percentile(std::vector<double>& values, double fraction);

}  // namespace isowave
