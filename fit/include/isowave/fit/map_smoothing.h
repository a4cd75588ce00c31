#pragma once
// Smoothing of the simplifier's surface map (simplify/surface_map.h) before
// the parametrization-based fit reads it (issue #33, item 1): the map the
// collapses leave is bijective on vertices but uneven, and a few input
// triangles' images turn over; the fine points then crowd, thin out and
// fold there. MAPS smooths its parametrization the same way (Lee et al.,
// SIGGRAPH 1998): each input vertex's parameter point moves toward
// a weighted mean of its neighbours' parameter points, inside the base mesh.
//
// A round moves input vertices toward the mean of their neighbours with
// Floater's mean-value weights of the input surface's 3D geometry (Floater,
// CAGD 2003; positive for every triangle, so the mean lies inside the
// neighbours' hull: a shape-preserving, low-distortion parametrization),
// all unfolded isometrically into the plane of the moving vertex's base
// triangle (across an edge, or round a shared base vertex the way that puts
// the neighbour nearest, as the inverse map unfolds: surface_map_inverse.h). A move that leaves the base triangle walks on
// across base edges into the neighbouring triangles; at the base mesh's
// boundary it stops. Every round (Untangle and Relax) first moves the
// vertices of inverted input triangles (image not positively oriented in the
// moving vertex's plane), Relax then every other free vertex that moved, or
// whose neighbour moved, in the round before, if all its neighbours lie in
// its base triangle or the three across its edges; a move is kept only if
// it turns over no input triangle round the vertex that was not turned
// over, or lowers their count, in the plane of its base triangle and, where
// it lands in another, in that one's plane too (tried at the full step, a
// half and a quarter).
//
// Why the restrictions: isometric unfoldings round a base vertex whose
// angles do not sum to 2 pi disagree from one base triangle's plane to the
// next. Where input triangles are large against the base triangles (a few
// input vertices per base triangle), a vertex relaxed in its own plane round
// such a corner leaves gaps in its neighbours' planes, and the inverse map
// (surface_map_inverse.h) finds more parameter points in no image.
//
// Fixed: input vertices on the surface's boundary or not on a disk of
// triangles, and those mapped onto a base vertex (the simplification's
// survivors, as in MAPS). Within a round, the vertices move colour class by
// colour class (a greedy colouring of the input's edge graph in index
// order): no two neighbours move at once, so the acceptance test is exact,
// and the result is identical for any thread count (TBB).
#include <cstddef>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/simplify/surface_map.h"

namespace isowave {

enum class SmoothingMode {
  Untangle,  // move only the corners of inverted input triangles
  Relax,     // then every free vertex whose neighbours lie in its base triangle or across its edges
};

struct SmoothingOptions {
  SmoothingMode mode = SmoothingMode::Relax;
  int max_rounds = 10;     // rounds at most; 0 returns at once (all statistics 0)
  double min_move = 1e-2;  // stop once no vertex moved farther (share of the mean base edge)
};

struct SmoothingStatistics {
  // Input triangles whose image is not positively oriented in the plane of
  // their first corner's base triangle (the others unfolded into it).
  std::size_t inverted_before = 0, inverted_after = 0;
  std::size_t free_vertices = 0;  // input vertices that may move
  int rounds = 0;                 // rounds run
  double mean_move = 0;           // per free vertex over all rounds, share of the mean base edge
  double seconds = 0;             // wall clock
};

// Smooths `map` (built by the simplifier from `surface` onto the base mesh
// whose vertices are base_positions) in place: vertex_triangle and
// vertex_uv change, the triangles do not. Preconditions (assertions): the
// map's sizes and indices fit the surface and base_positions, barycentric
// coordinates in [0, 1] (as parametrized_fit() checks); the surface's faces
// are valid (validate_indices); faces of more than 3 corners are fanned from
// their first corner. Cost per round: O(surface corners) times the base
// triangles walked per neighbour (a few); memory about 40 bytes per input
// vertex and 100 per input triangle.
SmoothingStatistics smooth_surface_map(simplify::SurfaceMap& map, const PolygonMesh& surface,
                                       const std::vector<Vec3>& base_positions, const SmoothingOptions& options = {});

}  // namespace isowave
