#pragma once
// Base-mesh construction, paper Sec. 4.1 (Bertram et al. 2000): memoryless
// edge collapse driven by a bucket priority queue, followed by an
// edge-removal pass that merges triangles into quads and pentagons.
//
// Input: a consistently oriented 2-manifold triangle mesh (boundaries, many
// components, any genus, optional sharp vertices). Output: a polygon mesh of
// triangles, quads and pentagons with the input's genus, component count and
// boundary-loop count, consistently oriented, plus sharp flags. Vertex
// valences are 3..8 (2..8 on the boundary) wherever the input allows: a
// collapse never creates a valence outside that range, so only input vertices
// already outside it (and never touched) can remain so.
//
// Collapse rules (Sec. 4.1 and Hoppe 1996):
//  - the edge with the highest priority log(1/E) is collapsed first; E from
//    (4.1)-(4.3), see collapse_error.h; priorities are bucketed (about 1e5
//    buckets over [log 1e-10, log 1e10]), FIFO inside a bucket;
//  - link condition; no face normal turning beyond options.collapse_min_normal_dot;
//    no zero-area triangle;
//  - valences after the collapse: new vertex N_i + N_j - 4 (boundary edge:
//    N_i + N_j - 3) in 3..8, 2..8 on the boundary; a and b lose one and stay >= 3
//    (>= 2 on the boundary). A closed component therefore never drops below a
//    tetrahedron (the only closed surface with 4 vertices, all of valence 3,
//    admits no collapse that keeps valences >= 3);
//  - never an edge with two sharp endpoints; the new vertex is the edge
//    midpoint, or the sharp endpoint when one is sharp;
//  - boundaries stay curves: boundary edges collapse along the boundary (to
//    the midpoint), an interior edge joining two boundary vertices never
//    collapses, an interior edge with one boundary endpoint collapses onto that
//    endpoint, and every boundary loop keeps at least 3 vertices.
// After each collapse, E_acc of the edges around the new vertex becomes the
// maximum of its value and E of the five destroyed edges, and the edges of the
// Fig. 8 stencil (every edge of every triangle at the new vertex, a and b) are
// re-evaluated. The popped edge is re-evaluated before it collapses (its
// neighbourhood may have changed outside the stencil): an edge found illegal
// is dropped, one whose priority fell is re-queued. Each collapse is
// O(valence^2) plus the bucket scan, no global rescans.
//
// Edge removal (after the collapses): repeatedly delete the interior edge of
// highest removal priority whose endpoints both have valence >= 4, whose two
// faces merge into a face of at most 5 sides, have unit normals with a dot
// product >= options.edge_removal_min_normal_dot, and share only this edge,
// with no sharp endpoint (Sec. 3.4 treats edges at sharp vertices as sharp).
// Removal priority (our formulation of the paper's qualitative rule):
//   dot(n_0, n_1) + (merged face is a quad ? 1 : 0) + 0.25 * #(endpoints of valence > 4)
// so quads come before pentagons, similar normals before disparate ones, and
// high-valence endpoints before valence-4 ones.
#include <array>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/progress.h"
#include "isowave/simplify/surface_map.h"

namespace isowave::simplify {

enum class SurfaceMapping { None, Build };

struct SimplifyOptions {
  // Stop collapsing at this many vertices or fewer; 0: as far as the rules
  // allow. At or above the input count no collapse happens (edge removal runs).
  std::size_t target_vertices = 0;
  bool edge_removal = true;  // merge triangles into quads and pentagons afterwards
  // Edge removal needs dot(n_0, n_1) >= this (paper: "for example .5"); in [-1, 1].
  double edge_removal_min_normal_dot = 0.5;
  // Collapse face-flip test: every surviving ring triangle needs
  // dot(n_old, n_new) >= this; in [-1, 1).
  double collapse_min_normal_dot = 0.0;
  // Not in the paper (false reproduces it): a boundary-edge collapse also
  // pays for moving the boundary curve within the surface, max over the
  // endpoints' other boundary edges of |(p - v) . m| (m the edge's unit
  // normal within its triangle); (4.2)'s weight applies to max(delta_e1, that).
  // (4.1) alone sees no cost in shrinking a loop on a flat stretch (an
  // isosurface grazing a box face) to a sliver the fit cannot open again.
  bool boundary_curve_error = true;
  // Not in the paper, off by default: input vertices above max_valence are
  // flipped down first, and when the paper's rules stall (typically at mean
  // valence ~7 on high-genus surfaces) an edge blocked only by its new
  // vertex's valence first flips up to 4 edges at its endpoints (nearly flat
  // quads, flip_min_normal_dot), undone if the collapse is still illegal.
  // The base is up to 16% smaller, but the fits lie farther from noisy
  // isosurfaces: without flips their floors are 6-48% lower there and their
  // files 3-17% smaller at equal D (docs/MEASUREMENTS.md, "Valence flips and
  // the fits' floor"). Without flips, an input vertex above max_valence that
  // no collapse removes stays in the base (SimplifyReport::vertices_outside_valence_range).
  bool valence_flips = false;
  // A flip needs all pairs of the old and new triangles' unit normals to have
  // a dot product >= this; in [-1, 1].
  double flip_min_normal_dot = 0.7;
  // With valence_flips, flip rounds, >= 0: each queues every edge the relaxed
  // valence rule admits; they stop early when one gains under 1% of the vertices.
  int max_flip_rounds = 1;
  int max_valence = 8;  // 3..32
  // Not in the paper (0 reproduces it): no base vertex may hold more than
  // this multiple of the input's area per target vertex (CollapseRules::
  // max_vertex_area), so that base faces cover comparable parts of the
  // surface, as a uniform refinement of them needs; in [0, 1e6].
  double max_vertex_area_share = 0;
  // How a collapse updates its Fig. 8 stencil. false (the paper): every
  // stencil edge is re-evaluated at once. true (not in the paper): the edges
  // at the new vertex at once, the others keep their queued priority until
  // popped (and are evaluated then); one that had left the queue comes back
  // at its last priority when the valence rules admit it. Faster, slightly
  // different base mesh.
  bool lazy_stencil = true;
  // Collapse order in the two-thread phase and the flip rounds, in
  // [1, 1e20]. 1 (the paper): one edge at a time in priority order. > 1
  // (not in the paper): every queued edge whose error is within this factor
  // of the best one, in memory (Morton) order, each re-evaluated and requeued
  // if its priority fell below the batch. The serial loop of the paper's
  // rules always keeps the paper's order.
  double batch_error_factor = 10;
  // Collapse on two threads first, each inside one half of the mesh
  // (collapse_loops.cpp), then finish serially; the flip rounds too. Same
  // rules, a slightly different order, deterministic. Used from
  // parallel_min_vertices input vertices on.
  bool parallel = true;
  std::size_t parallel_min_vertices = 200000;
  // Called once, on the calling thread, when the rest of the run is serial
  // (after the two-thread collapse phase, or as the collapse starts when it
  // runs serially; on every run that does not throw), so that a caller can
  // start other work on the core that is left idle. Must not throw.
  std::function<void()> serial_phase_begins;
  std::uint32_t bucket_count = 100000;  // >= 1
  // Distance from every input vertex to the base mesh surface (BinnedSurfaceDistance).
  bool compute_distance = true;
  // Whether simplify() also builds the map from the input onto the base mesh
  // (SimplifyResult::map; MAPS, surface_map.h): about 30 bytes per input
  // vertex and a relocation of the mapped points at every collapse and flip.
  SurfaceMapping surface_map = SurfaceMapping::None;
  // Test hook: check every corner-table invariant after each collapse (O(n)
  // per collapse: small meshes only); a failure throws std::logic_error.
  bool validate_every_collapse = false;
};

struct SimplifyReport {
  std::size_t input_vertices = 0, input_faces = 0;
  std::size_t input_components = 0, input_boundary_loops = 0;
  long long input_genus = 0;
  std::size_t target_vertices = 0;  // after clamping to the input size
  // Sum over components of the fewest vertices the rules allow: closed genus g:
  // max(4, 6g - 6) (valence <= 8 forces 2E <= 8V); with b boundary loops:
  // max(3b, ceil((6g - 6 + 3b) / 2)). Not necessarily reachable.
  std::size_t lower_bound_vertices = 0;
  std::size_t input_valence_flips = 0;  // flips lowering input vertices above max_valence
  std::size_t collapses = 0;            // all of them, with and without flips
  std::size_t parallel_collapses = 0;   // of those, on two threads (see SimplifyOptions::parallel)
  std::size_t parallel_flip_round_collapses = 0;  // of those, in the flip rounds
  std::size_t vertices_after_paper_collapse = 0;  // where the paper's rules alone stalled
  std::size_t flip_rounds = 0, collapses_after_flips = 0, flips = 0, flips_undone = 0, flip_attempts_failed = 0;
  std::size_t vertices_after_collapse = 0, triangles_after_collapse = 0;
  std::size_t edges_removed = 0;
  std::size_t output_vertices = 0, output_edges = 0, output_faces = 0;
  bool target_reached = false;
  std::string stop_reason;  // why collapsing stopped
  // Popped edges rejected by the re-evaluation, by Legality (see collapse_mesh.h).
  std::array<std::size_t, 11> rejected_at_pop{};  // kLegalityCount
  std::vector<std::size_t> face_size_histogram;  // [s] = faces with s sides
  std::vector<std::size_t> valence_histogram;    // [k] = vertices of valence k
  std::size_t vertices_outside_valence_range = 0;
  // Seconds per phase.
  double seconds_check = 0, seconds_build = 0, seconds_queue = 0, seconds_collapse = 0, seconds_edge_removal = 0,
         seconds_output = 0, seconds_distance = 0;
  double seconds_parallel = 0;     // the part of seconds_collapse spent on two threads before the serial loop
  double seconds_flip_rounds = 0;  // the part of seconds_collapse spent after the paper's rules stalled
  double seconds_total() const {
    return seconds_check + seconds_build + seconds_queue + seconds_collapse + seconds_edge_removal + seconds_output +
           seconds_distance;
  }
  // Distance from the input vertices to the base mesh surface (polygons fan-
  // triangulated), in input units; valid when distance_computed.
  bool distance_computed = false;
  double distance_max = 0, distance_rms = 0;
};

struct SimplifyResult {
  PolygonMesh base;  // sharp flags set iff the input had them
  SurfaceMap map;    // with SurfaceMapping::Build; empty otherwise
  SimplifyReport report;
};

// Builds the base mesh. Throws Error(InvalidArgument) for options outside
// their ranges, Error(Format) for non-finite coordinates or bad indices,
// Error(Unsupported) for a face that is not a triangle, Error(Topology) for
// input that is not a consistently oriented 2-manifold or has unreferenced
// vertices (see require_manifold; drop them with remove_unreferenced_vertices
// first). Degenerate (zero-area) input triangles are accepted: they get no
// normal in (4.1)-(4.2) and no flip test, and no collapse creates a new one.
// Time O(n log n) for the Morton sort, O(n) for the rest (the manifold checks
// are part of the parallel corner-table build); peak memory about 380 bytes
// per input vertex including the input (every bucket queue keeps its links
// in the edge records).
SimplifyResult simplify(const PolygonMesh& triangles, const SimplifyOptions& options = {},
                        ProgressSink& progress = no_progress());

// One line per figure, for the CLI and the benchmark.
std::string format_report(const SimplifyReport& report);

}  // namespace isowave::simplify
