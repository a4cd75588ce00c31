#pragma once
// Isosurface extraction from a dense volume: the first step of the pipeline
// (Bertram et al. 2000, Sec. 4: "using common algorithms, unstructured,
// triangulated meshes of high resolution are obtained"). Every later stage
// assumes a clean 2-manifold, so the contouring guarantees topology:
//
// - Inside/outside: a sample is inside when it is finite and >= iso. NaN and
//   Inf samples are outside. One vertex per grid edge whose two samples
//   differ in this classification, at the linear interpolation of the two
//   values, kept at least 1/1000 of the edge away from both samples so that
//   samples exactly at the isovalue never produce zero-area triangles (an
//   edge with a non-finite sample gets its midpoint).
// - Per cell, the crossing points on each of the 6 cube faces are joined by
//   segments; a face with four crossings (ambiguous) joins its two inside
//   corners when the bilinear saddle value is inside (asymptotic decider:
//   product of the inside pair of corner values minus iso >= product of the
//   outside pair), a rule both cells sharing the face evaluate identically.
//   The segments of a cell form disjoint closed loops. Each loop is
//   triangulated without a diagonal between two vertices on a common cube
//   face (such a diagonal would lie on the face, where the neighbouring cell
//   could use it too): a fan when a suitable apex exists, otherwise any
//   triangulation of allowed diagonals, otherwise (a tunnel-like loop where
//   none exists; rare, seen on noisy data) a fan around one extra vertex
//   at the loop's centroid. Each segment is then in exactly one
//   triangle of each of its (at most two) cells and no other edge is shared
//   between cells, so the result is a 2-manifold whose only boundary edges
//   lie on the faces of the volume box. The cell interior is not examined
//   (no interior tunnels as in marching cubes 33): within a cell the surface
//   is one disk per loop. All of this case analysis is a table built once
//   (256 sign cases x 64 face decisions).
// - Orientation: triangle normals (counter-clockwise) point toward lower
//   values, or toward higher values with `flip`.
// - Vertices are in world coordinates (origin + spacing * index). Vertices on
//   the twelve edges of the volume box, where the surface's boundary curve
//   turns a corner, are flagged sharp (PolygonMesh::sharp; empty if none).
//
// Parallel (TBB) over fixed slabs of z-layers whose buffers are concatenated
// in slab order, so the output is identical for any number of threads.
// Time O(samples + output), memory: the output mesh plus one copy of it in the
// slab buffers and a few slices of per-edge vertex indices. Everything hot is
// a flat array (per-plane edge-to-vertex indices, per-slab positions and
// triangle indices) rather than per-cell or per-vertex objects: a 256^3
// volume has 16.7 million cells and millions of output vertices, and
// contiguous arrays keep the sweep memory-bound and free of small allocations.
#include <cstddef>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/core/progress.h"
#include "isowave/core/volume.h"
#include "isowave/extract/topology_tolerance.h"

namespace isowave {

// Contouring only: no clean-up and no report. Triangles only. Requires at
// least 2 samples along each axis (Error(InvalidArgument) otherwise) and
// fewer than 2^31 output vertices (Error(Unsupported) otherwise). An empty
// mesh when the surface does not cross the volume. If `centroid_vertices` is
// given, it receives the number of extra loop-centre vertices.
PolygonMesh contour_volume(const Volume& volume, double iso, bool flip = false,
                           std::size_t* centroid_vertices = nullptr);

struct IsosurfaceOptions {
  double iso = 0.0;
  bool flip = false;  // normals toward higher values
  // Clean-ups, both off by default:
  // drop connected components with fewer vertices than this (0 or 1: keep all);
  std::size_t min_component_vertices = 0;
  // standard deviation, in voxels along each axis, of a separable Gaussian
  // applied to the field before contouring (0: none).
  double smooth_sigma = 0.0;
  // Topology tolerance T, cells: handles, tunnels, specks and bubbles under
  // T removed from the (smoothed) field before component removal
  // (topology_tolerance.h; 0: the paper's exact topology).
  double topology_tolerance = 0.0;
};

// Topology counts (faces = triangles) plus area and component sizes.
struct SurfaceStatistics : TopologySummary {
  double area = 0.0;  // world units squared
  // component_size_histogram[b] = components with 10^b <= vertices < 10^(b+1).
  std::vector<std::size_t> component_size_histogram;
};

struct IsosurfaceReport {
  double iso = 0.0;
  bool flipped = false;
  std::size_t nonfinite_samples = 0;  // in the input volume (treated as outside)
  double smooth_sigma = 0.0;          // 0 if the field was not smoothed
  std::size_t min_component_vertices = 0;
  double topology_tolerance = 0.0;  // cells
  TopologyCleanup topology;         // what the tolerance changed
  // D (surface_error.h, 100,000 samples a side), cells, and the area change
  // (world units squared) from the contour before the tolerance to the one
  // after it; 0 when it changed nothing.
  double topology_d = 0.0;
  double topology_area_change = 0.0;
  // Contour of the field as given (before smoothing and component removal).
  SurfaceStatistics before;
  // The returned mesh.
  SurfaceStatistics after;
  // What component removal dropped (from the contour of the smoothed field).
  std::size_t dropped_components = 0;
  std::size_t dropped_vertices = 0;
  std::size_t dropped_triangles = 0;
  double dropped_area = 0.0;
  std::size_t sharp_vertices = 0;     // of the returned mesh
  std::size_t centroid_vertices = 0;  // extra loop-centre vertices of the contour
};

struct Isosurface {
  PolygonMesh mesh;
  IsosurfaceReport report;
};

// Contours `volume` at options.iso, applies the requested clean-ups and
// reports (see IsosurfaceReport). Throws Error(InvalidArgument) for a
// non-finite iso, a negative or non-finite smooth_sigma or
// topology_tolerance, and what contour_volume() and clean_topology() throw.
// The report's topology counts need an O(n log n) pass over the mesh
// (summarize_topology), about as long as the contouring. The pre-filter and
// the topology tolerance each work on a copy of the volume.
Isosurface extract_isosurface(const Volume& volume, const IsosurfaceOptions& options = {},
                              ProgressSink& progress = no_progress());

// The same, with the pre-filter and the topology tolerance applied to
// `field` itself: afterwards it is the field the returned surface is the
// isosurface of (what the fit must search), and no copy is made.
Isosurface extract_isosurface_in_place(Volume& field, const IsosurfaceOptions& options = {},
                                       ProgressSink& progress = no_progress());

// The building blocks of extract_isosurface(), for tests and other stages.

// Separable Gaussian of standard deviation sigma voxels (> 0), truncated at
// 3 sigma, clamped at the volume faces; non-finite samples are left out of
// the weighted average (and stay non-finite only if nothing finite is within
// reach). O(samples * sigma).
Volume gaussian_smoothed(const Volume& volume, double sigma);

struct ComponentRemoval {
  std::size_t components = 0;
  std::size_t vertices = 0;
  std::size_t faces = 0;
  double area = 0.0;
};
// Drops every component with fewer than min_vertices vertices (and their
// vertices, keeping the order of the rest). O(n).
ComponentRemoval remove_small_components(PolygonMesh& mesh, std::size_t min_vertices);

// Drops every component whose vertices span less than `extent` (world
// units) along every axis: the mesh-side part of the topology tolerance, for
// meshes without their field (handles need the field). O(n log n).
ComponentRemoval remove_components_under(PolygonMesh& mesh, double extent);

// Sum of face areas (polygons fanned from their first vertex).
double surface_area(const PolygonMesh& mesh);

// Counts for a mesh that passed require_manifold() (an empty mesh gives zeros).
SurfaceStatistics surface_statistics(const PolygonMesh& mesh);

}  // namespace isowave
