#pragma once
// The exact inverse of the simplifier's surface map through its history
// (simplify/surface_map.h, SurfaceMapHistory): a point of a base triangle is
// carried back operation by operation. In the chart of the operation that
// made its triangle it is a planar point; among the triangles that operation
// consumed it lies in exactly one (both sets tile the same convex polygon),
// which gives its barycentric coordinates there; and so on until it reaches
// an input triangle, whose vertices' barycentric combination is the surface
// point. The map is thus a bijection between the input surface and the base
// triangles, piecewise linear on the overlay of the charts; no point falls
// outside it and every point of the input surface has a preimage.
// Private to the parametrization-based fit (parametrized_fit.h).
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/simplify/surface_map.h"
#include "surface_map_inverse.h"

namespace isowave {

// Throws Error(InvalidArgument) unless `history` is consistent: offsets
// non-decreasing and in range, chart corners within their operation's chart,
// every consumed triangle older than the operation's own (so that every walk
// ends), every operation with a consumed triangle of positive area (so that
// every step lands somewhere), input corners below `surface_vertices`, finite
// chart positions, one base version per map triangle. O(history size).
void check_history(const simplify::SurfaceMapHistory& history, std::size_t map_triangles,
                   std::size_t surface_vertices);

// The surface points at `queries` (preconditions: check_history passed,
// every query's triangle below history.base_version.size()). A point that
// rounding puts outside every consumed triangle (smallest barycentric weight
// under -1e-6) takes the nearest one, clamped, and counts as a fallback.
// Parallel (TBB); each result depends on its query only. Cost per query: the
// number of operations between its base triangle and the input (about the
// logarithm of the input's size per collapse region) times their size.
InverseMapResult inverse_map_by_history(const simplify::SurfaceMapHistory& history,
                                        const std::vector<Vec3>& surface_positions,
                                        const std::vector<MapPoint>& queries);

}  // namespace isowave
