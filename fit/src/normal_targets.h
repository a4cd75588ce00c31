#pragma once
// Private to the normal fit: where each control point of a level aims (the
// point at which its line pierces the isosurface, and the isosurface's
// tangent plane there), and the box-face planes that hold boundary points.
#include <cstdint>
#include <vector>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/vec3.h"
#include "isowave/fit/trilinear.h"
#include "isowave/fit/wrap_level_mesh.h"
#include "coverage_pull.h"

namespace isowave::detail {

// Per control point of a level: the residual of a move d is
// plane_normal . d - plane_offset (the tangent plane at the target; a zero
// normal: no target), plus, for a point held on a box face, d[box_axis] -
// box_offset (the face's plane).
struct LevelTargets {
  std::vector<Vec3> plane_normal;
  std::vector<double> plane_offset;
  std::vector<std::int8_t> box_axis;  // -1: free of the box
  std::vector<double> box_offset;
  // Points the coverage pull moves (add_coverage_pull): their residual is
  // the move minus pull_offset instead of the plane's.
  std::vector<Vec3> pull_offset;
  std::vector<std::uint8_t> pulled;
  std::vector<std::uint8_t> off_line;  // 1: the point's line missed; aimed along the field gradient or at the nearest surface point
  std::size_t unpierced = 0;
};

// The nearest crossing of the isosurface `iso` along p + t d (d a unit world
// vector) with |t| <= reach at which the field's slope along d has the sign
// `facing` (either sign for 0): sampled every `step` both ways, then refined
// to `tolerance` (world units), only inside the volume's box. Returns false
// when there is none. With d the surface's normal, `facing` excludes the far
// side of a thin sheet. reach and step finite and > 0.
bool pierce(const TrilinearGrid& grid, double iso, const Vec3& p, const Vec3& d, double facing, double reach,
            double step, double tolerance, double& t);

// Targets for every control point of `mesh` at `positions`: along
// directions[v] (unit, the surface's normal: a crossing of slope sign
// `facing` along it; zero: the field gradient), or, where that line does
// not pierce within `reach`, along the field gradient, and failing that the
// nearest point of `surface` (the extracted mesh; nullptr: no target). A
// box-held point pierces within its face's plane. Parallel, deterministic.
LevelTargets level_targets(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions,
                           const std::vector<Vec3>& directions, const TrilinearGrid& grid, const Volume& box,
                           double iso, double facing, double reach, const BinnedSurfaceDistance* surface);

// The coverage pull (coverage_pull.h) from the points at `positions`: each
// extracted vertex farther than the pull's `covered` from them picks its
// nearest point within `reach`, which then aims at the mean of its pickers.
void add_coverage_pull(CoveragePull& pull, const WrapLevelMesh& mesh, const std::vector<Vec3>& positions,
                       double reach, LevelTargets& targets);

// Mean edge length of the level mesh (from at most about 65,536 vertices).
double mean_edge_length(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions);

}  // namespace isowave::detail
