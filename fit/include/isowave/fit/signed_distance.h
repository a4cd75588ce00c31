#pragma once
// Signed-distance field of an isosurface on the volume's own grid, computed
// by breadth-first propagation of closest surface points (Bertram et al.
// 2000, Sec. 4.2):
//
// 1. Seeds: every grid node of a cell that contains the isosurface (a cell
//    whose corners are not all on one side; a node is "inside" when its
//    sample is finite and >= iso, as in extraction). Each seed's closest
//    surface point is estimated from the isovalue, its value and the field
//    gradient: the nearer of (a) the first-order point x - (f - iso) g / |g|^2
//    (g by central differences) refined by Newton steps on the trilinear
//    field along the gradient line (within sqrt(3) cells and the box; a
//    bracketed search when Newton does not settle and (b) is empty), and
//    (b) the isovalue crossings on the node's own grid edges (where
//    extraction puts its vertices). A seed with neither is left to its
//    neighbours.
// 2. A first-in-first-out queue starts with all seeds in index order. The
//    node at the front is removed and each of its 6 grid neighbours is
//    updated when the removed node's closest point is closer to it than the
//    neighbour's own: the neighbour takes over that point and its distance
//    and goes to the back of the queue (unless already queued). This runs
//    until the queue is empty. A node is typically updated a few times.
// 3. The sign comes from the scalar field: positive on the side the
//    extracted surface's normals point to (lower values; higher with flip).
//
// The surface must be the one the base mesh came from. When extraction
// dropped small components, pass the extracted mesh as options.surface: only
// cells that mesh passes through seed the queue, and the regions enclosed by
// dropped components alone (same-side nodes that reach neither an end of a
// grid edge the mesh crosses nor the box) take the sign of their
// surroundings, so the dropped components leave no zero crossing behind,
// also those that share cells with the kept surface.
//
// Narrow band: with band_cells = K > 0, a node is never updated to a distance
// beyond K cells, so propagation stops there; unreached nodes get +-far_value
// (K cells). Without a band every node connected to a seed is reached, and
// any other node (no surface anywhere) gets +-far_value (the box diagonal).
//
// Memory (N grid nodes, S seeds): during the run 4 bytes of squared distance,
// 4 bytes of closest-point index and 1 byte of flags per node, 12 bytes per
// seed point and the queue (at most N indices, usually far fewer); flat arrays
// because grids have tens of millions of nodes and a node object with a
// pointer or an embedded point would double the footprint. The result keeps
// only one float per node. The node arrays live on transparent huge pages
// (random access in the propagation). Time O(N + updates); seeding is
// parallel (TBB), propagation sequential; both are deterministic.
#include <cstddef>

#include "isowave/core/mesh.h"
#include "isowave/core/progress.h"
#include "isowave/core/volume.h"

namespace isowave {

struct SignedDistanceOptions {
  double iso = 0.0;
  // Same meaning as in extraction: with flip the surface normals point toward
  // higher values, so the distance is positive there.
  bool flip = false;
  // Half-width of the narrow band in cells (Volume::cell_size()); 0 computes
  // the whole grid. Must be finite and >= 0.
  double band_cells = 0.0;
  // Optional: the extracted mesh (world coordinates, vertices on grid edges
  // as extraction places them). Null: every cell containing the isosurface
  // seeds the queue.
  const PolygonMesh* surface = nullptr;
};

struct SignedDistanceStatistics {
  std::size_t nodes = 0;
  std::size_t seed_nodes = 0;          // nodes of cells containing the surface
  std::size_t projected_seeds = 0;     // seeds whose point came from the root search
  std::size_t first_order_seeds = 0;   // seeds that kept the first-order estimate
  std::size_t unseeded_crossing_nodes = 0;  // nodes on dropped components (with a surface mesh)
  std::size_t flipped_nodes = 0;       // nodes enclosed by dropped components, sign flipped
  std::size_t queue_pops = 0;
  std::size_t updates = 0;             // distance improvements (seed initialisation excluded)
  std::size_t reached_nodes = 0;       // nodes with a closest point
  std::size_t peak_queue = 0;
  std::size_t peak_bytes = 0;          // largest working set of the computation
  double seconds_seeding = 0;          // classification, seed points (parallel)
  double seconds_propagation = 0;      // the queue (sequential)
  double seconds_finishing = 0;        // enclosed regions, signs
};

struct SignedDistanceField {
  // Same dims, spacing and origin as the scalar field; values are signed
  // distances in world units (float), never NaN.
  Volume distance;
  double iso = 0.0;
  bool flip = false;
  double band_cells = 0.0;  // 0: whole grid
  double far_value = 0.0;   // |distance| of unreached nodes, world units
  SignedDistanceStatistics statistics;
};

// Throws Error(InvalidArgument) if the volume has fewer than 2 samples along
// an axis, a non-positive or non-finite spacing, iso is not finite or the
// band is negative or not finite, and Error(Unsupported) beyond 2^31 - 1
// nodes. A volume the surface does not cross yields +-far_value everywhere.
SignedDistanceField compute_signed_distance(const Volume& field, const SignedDistanceOptions& options = {},
                                            ProgressSink& progress = no_progress());

// The scalar field's samples with those on the other side of the distance
// field's sign (the regions enclosed by dropped components,
// SignedDistanceStatistics::flipped_nodes) mirrored across the isovalue
// (2 iso - f, at least one float step across it), written to out[0 ..
// field.sample_count()). The trilinear isosurface of the result is the
// field's without the closed components extraction dropped, so that the
// shrink-wrap's searches along the field (final correction, untangling) do
// not put points on them. Where such a sample is a corner of a cell the kept
// surface passes through, that cell's trilinear surface moves a little.
// `distance` must come from `field`.
// Returns how many samples changed. Parallel (TBB), O(samples).
std::size_t mirror_enclosed_samples(const Volume& field, const SignedDistanceField& distance, float* out);

// Gives the field's non-finite samples (outside, as extraction counts them)
// finite values below iso in out[0 .. field.sample_count()), so that the
// trilinear field, its isosurface and its gradient are defined next to them
// too: a sample with inside 6-neighbours gets 2 iso - (their mean), at
// least one float step below iso, which puts the isosurface near the
// midpoints of the grid edges between them, where extraction puts its
// vertices; the others get the field's lowest finite value (or that step
// below iso, if higher). Every sample keeps extraction's inside/outside
// class. Without this, points and faces in cells with a NaN corner have no
// value or gradient: the correction would have nothing to follow there, and
// every face there would count as folded. `out` holds the finite samples
// (the field's, or mirror_enclosed_samples's); only the entries of
// non-finite ones are written. Returns how many. Parallel (TBB),
// O(samples).
std::size_t fill_non_finite_samples(const Volume& field, double iso, float* out);

}  // namespace isowave
