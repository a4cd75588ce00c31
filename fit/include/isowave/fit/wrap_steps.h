#pragma once
// The paper's two shrink-wrap steps (Bertram et al. 2000, Sec. 4.2, after
// Kobbelt et al.'s shrink-wrapping), applied to one level's control mesh:
//   relaxation - every vertex moves toward the centroid of its neighbours
//                (a boundary vertex: of its two boundary neighbours; fixed
//                vertices and vertices held on a box face do not relax: the
//                relaxation would only shrink a boundary curve on the face);
//   attraction - every vertex moves along the unit average normal of its
//                faces to the nearest zero crossing of the trilinear signed
//                distance field whose gradient agrees with that normal.
// Both are Jacobi updates (read `in`, write `out`, &in != &out) split across
// threads: results are identical for any thread count. Neither writes a
// non-finite position (such a vertex keeps its old one); both keep box-held
// vertices on their face and every vertex in the box (wrap_level_mesh.h).
#include <cstddef>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/fit/wrap_level_mesh.h"

namespace isowave {

// One relaxation round: out[v] = (1 - weight) in[v] + weight centroid, weight
// in (0, 1] (0.5 in the paper). `in` holds at least vertex_count positions;
// `out` is grown to that. O(vertices + edges).
void relax(const WrapLevelMesh& mesh, const Volume& box, double weight, const std::vector<Vec3>& in,
           std::vector<Vec3>& out);

struct AttractionOptions {
  // A vertex moves only to a crossing within reach: reach_edges (> 0) times
  // the mean length of its edges, but at least min_reach_cells (>= 0) cells.
  double reach_edges = 2.0;
  double min_reach_cells = 1.0;
};

struct AttractionStatistics {
  std::size_t movable = 0;       // vertices not fixed
  std::size_t attracted = 0;     // moved onto a crossing
  std::size_t out_of_reach = 0;  // no agreeing crossing within reach: left for a later round
  std::size_t no_direction = 0;  // degenerate normal
  double mean_move_cells = 0;    // over attracted vertices
  double max_move_cells = 0;
};

// One attraction round toward the zero set of `distance` (whose grid gives
// the box). The search along the normal starts with one Newton step (taken
// within 1e-3 cells of zero, or when it brackets the crossing), then steps by
// the distance value (at least 0.2 cells), the likelier side first. Sizes as
// relax(). O(vertices) plus a few trilinear samples per vertex near the surface.
AttractionStatistics attract(const WrapLevelMesh& mesh, const SignedDistanceField& distance,
                             const AttractionOptions& options, const std::vector<Vec3>& in, std::vector<Vec3>& out);

}  // namespace isowave
