#pragma once
// Shrink-wrap fitting of a subdivision hierarchy to an isosurface (Bertram et
// al. 2000, Sec. 4.2, after Kobbelt et al.'s shrink-wrapping): starting from
// the base mesh, each level gets a few rounds of
//   relaxation  - every vertex moves to the average of its old position and
//                 the centroid of its neighbours; a vertex on two sharp
//                 (boundary) edges averages only its neighbours along them;
//                 sharp vertices, and those held on a box face (see
//                 Boundaries), do not relax;
//   attraction  - every vertex moves along the unit average normal of its
//                 faces to the nearest zero crossing of the signed-distance
//                 field (trilinear) whose field gradient agrees with that
//                 normal; a vertex whose crossing is farther than the reach
//                 (tied to the level's edge length) stays for later rounds;
// and is then refined to the next level with the wavelet subdivision
// operator S (subdivide_level), up to level L. Finally (optional, on by
// default) every level-L vertex moves along the scalar-field gradient onto
// the isosurface of the trilinearly interpolated field (with fallbacks for
// the few without a root there, see CorrectionStatistics), and folds left on
// level L are repaired locally (untangle(), not in the paper; also on every
// coarser level, against the signed-distance field: coarse_untangle_rounds).
// With the extracted surface (ShrinkWrapOptions::surface), the fine levels
// are also pulled toward the parts of it they leave out; on level L that
// comes after the untangling, and only unfold() (not in the paper either:
// folds a few faces wide that untangle() cannot open) follows it.
//
// Small closed components (droplets a few cells across, mostly tetrahedra;
// see ShrinkWrapOptions::small_component_vertices) are fitted differently,
// not in the paper: their vertices relax within their tangent planes and are
// attracted and corrected along rays from the component's centroid.
//
// Boundaries: the extracted surface's boundary lies on the faces of the
// volume box. A boundary vertex within one cell of a box face is kept on that
// face (snapped, attracted and corrected within the face plane, not relaxed:
// along its boundary curve the relaxation only shrinks the curve, which the
// attraction does not restore where it is narrower than a cell), so it
// slides along its boundary curve. Every vertex is kept inside the box.
//
// Every step is a Jacobi update (reads the previous positions, writes new
// ones) split across threads (TBB), so results are identical for any thread
// count. No step ever writes a non-finite position: a vertex whose update is
// not finite keeps its old position.
//
// Cost per round: O(vertices of the level) plus the line searches (a few
// trilinear samples each; near the surface usually two, see attract()).
// Memory: the level's connectivity (about 60 bytes per vertex), two position
// buffers, single-precision face normals (12 bytes per face), all sized for
// level L from the start and reused by the coarser levels, and on level L a
// copy of the scalar field and a few flags per vertex and face for
// untangle() (which moves its selected vertices through the second position
// buffer) and, when it runs, unfold() (3 bytes per vertex, 1 per face).
// Large buffers live on transparent huge pages, faulted in on all threads.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/progress.h"
#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

enum class WrapRole : std::uint8_t {
  Free = 0,      // interior vertex
  Boundary = 1,  // on two boundary edges: follows its boundary curve
  Fixed = 2,     // sharp: never moves
};

// Connectivity of one level's control mesh as the shrink-wrap needs it, as
// flat arrays (compressed rows): millions of vertices at the finest level,
// visited in parallel many times per round.
struct WrapLevelMesh {
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  int level = 0;
  std::size_t vertex_count = 0;
  // Neighbours of vertex v: neighbours[neighbour_offsets[v] .. neighbour_offsets[v+1]).
  std::vector<std::uint32_t> neighbour_offsets, neighbours;
  // Faces (the control mesh's, same order) and, per vertex, its faces.
  std::vector<std::uint32_t> face_offsets, face_vertices;
  std::vector<std::uint32_t> vertex_face_offsets, vertex_faces;
  std::vector<WrapRole> role;
  // Per vertex: its two neighbours along boundary edges (kNone if interior).
  std::vector<std::uint32_t> boundary_neighbours;
  // Per vertex: the box face it is held on, axis * 2 + (0 low, 1 high), or -1.
  std::vector<std::int8_t> box_face;

  std::size_t face_count() const { return face_offsets.size() - 1; }
};

// Connectivity of level `level` of the hierarchy; box faces are assigned from
// `positions` (at least vertex_count(level) of them) and the volume's box: a
// boundary vertex is held on the nearest face within one cell. One on a box
// edge is held on a face in which the isosurface `iso` of the volume's field
// comes within two cells of it (across the edge), so that it can follow the
// isosurface's boundary curve there; of two such faces the one its
// neighbours lie along. With iso NaN, or no isosurface that near: the last
// of its faces in the order x low, x high, y low, ... O(vertices of the
// level) for level >= 1 and O(n log n) for the base.
WrapLevelMesh make_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, int level,
                                   const std::vector<Vec3>& positions, const Volume& box,
                                   double iso = std::numeric_limits<double>::quiet_NaN());

// Moves box-held vertices onto their face and every vertex into the box.
void constrain_to_box(const WrapLevelMesh& mesh, const Volume& box, std::vector<Vec3>& positions);

// One relaxation round (see above): out[v] = (1 - weight) in[v] + weight
// centroid, weight in (0, 1], 0.5 in the paper. Sizes: vertex_count.
void relax(const WrapLevelMesh& mesh, const Volume& box, double weight, const std::vector<Vec3>& in,
           std::vector<Vec3>& out);

struct AttractionOptions {
  // A vertex moves only if its crossing is within reach: reach_edges times
  // the mean length of its edges, but at least min_reach_cells cells.
  double reach_edges = 2.0;
  double min_reach_cells = 1.0;
};

struct AttractionStatistics {
  std::size_t movable = 0;       // vertices not fixed
  std::size_t attracted = 0;     // moved onto a crossing
  std::size_t out_of_reach = 0;  // left for later (no agreeing crossing within reach)
  std::size_t no_direction = 0;  // degenerate normal
  double mean_move_cells = 0;    // over attracted vertices
  double max_move_cells = 0;
};

// Unit average normal of the faces around each vertex (zero where undefined).
std::vector<Vec3> vertex_normals(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions);

// One attraction round (see above) toward the zero set of `distance`. Near
// the surface the search starts with one Newton step along the normal (value
// and gradient at the vertex): its end is taken when the field is within
// 1e-3 cells of zero there, or brackets the crossing for the refinement;
// otherwise (and for the other side) the line is stepped by the distance
// value, at least 0.2 cells. A vertex's edge lengths (for the reach) are read
// only when a search goes past min_reach_cells.
AttractionStatistics attract(const WrapLevelMesh& mesh, const SignedDistanceField& distance,
                             const AttractionOptions& options, const std::vector<Vec3>& in, std::vector<Vec3>& out);

struct CorrectionStatistics {
  std::size_t movable = 0;
  std::size_t corrected = 0;  // now on the interpolated isosurface
  std::size_t failed = 0;     // no root within reach or no gradient: left in place
  std::size_t from_nearest_point = 0;  // of the corrected: see correction_from_nearest_point
  // Of the corrected: vertices without a root that found one from the
  // centroid of their neighbours (once those were corrected; up to five
  // Jacobi rounds). Engine CT (base 1/16 of its isosurface, 3 levels): 59 of
  // 214 failures, isosurface RMS 0.0109 -> 0.0065 cells, the far ones
  // among them; miranda 18,322 of 32,695, 0.0785 -> 0.0734.
  std::size_t from_neighbours = 0;
  // Of the corrected (in the shrink-wrap, and in correct_to_isosurface()
  // when asked): vertices still without a root after all that, moved to the
  // nearest root within three times the range along the 26 directions to a
  // cube's neighbours (within the face's plane for one held on a box face)
  // at which no more of their faces are tangled than before (a last resort:
  // for at most 1% of the vertices, at least 10,000). Miranda (its
  // 90,086-vertex base, 3 levels): 5,803 of 6,749 failures, isosurface RMS
  // 0.0291 -> 0.0083 cells (most of it from the 301 points over a cell off,
  // 1.5-5 cells from the surface, which the fit left there).
  std::size_t from_wide_search = 0;
  // Of the corrected (in the shrink-wrap, with ShrinkWrapOptions::surface):
  // vertices still without a root a cell or more from the extracted surface
  // (by the signed-distance field), moved to its nearest point within 16
  // cells and from there onto the isosurface. Base faces that span voids
  // leave such points: refined, their new points fall up to 8 cells from
  // any surface, beyond the distance field's band, and where the field is
  // flat no search along it finds a root. Their faces' folds are not
  // checked (the untangling follows): a point left in a void is the larger
  // error. Mouse embryo (base 1/16 of its isosurface, 3 levels): 86 points,
  // isosurface RMS 0.668 -> 0.0021 cells (max 655 -> 0.73 by the
  // first-order measure), 9.81 -> 5.11 cells at most from the extracted
  // mesh, folded faces 94,978 -> 94,962; 0.04 s. Miranda: 20 points, RMS
  // 0.0083 -> 0.0051, no measurable time.
  std::size_t from_extracted_surface = 0;
  // Of the corrected: free vertices within a cell of a box face whose root
  // lies outside the box along the gradient (and, with
  // correction_from_nearest_point, from the nearest point), found instead
  // along the gradient's part parallel to that face. Mixing at 96^3: 38 of
  // the 78 failures (free vertices pressed onto the x = 0 and x = 95 faces),
  // isosurface RMS 0.0109 -> 0.0073 cells. Failing that, and for vertices
  // held on a face, the nearest root within the face's plane (16
  // directions): engine CT (base 1/16 of its isosurface, 3 levels), where
  // the fit lay on the z = 0 face across the cut through the material and
  // the gradient there is normal to the face: failures 185 -> 5, isosurface
  // RMS 0.0026 -> 0.0001 cells, maximum distance to the extracted mesh 1.56
  // -> 0.59 cells.
  std::size_t along_box_face = 0;
  double mean_move_cells = 0;
  double max_move_cells = 0;
};

// The final correction: each movable vertex moves along the gradient of the
// trilinearly interpolated field (box-held ones along its projection into
// their face) to where the field equals iso (within about 1e-4 cells, by
// Newton steps along that line), searching at most max_move_cells cells; a
// free vertex without a root there retries along the gradient's part
// parallel to a box face within a cell (along_box_face), and a vertex still
// without one from the centroid of its neighbours (from_neighbours); with
// `wide_search` (faces oriented as `flip` says, see untangle()), last by the
// wide search (from_wide_search); with `surface` and `surface_distance`
// (the extracted surface and its signed-distance field, on the field's
// grid), last from the extracted surface (from_extracted_surface); in place.
// Here and in untangle() and unfold() the field's non-finite samples are
// filled as the shrink-wrap fills them (fill_non_finite_samples; in a copy
// of the field, made only when it has any).
CorrectionStatistics correct_to_isosurface(const WrapLevelMesh& mesh, const Volume& field, double iso,
                                           double max_move_cells, std::vector<Vec3>& positions,
                                           bool wide_search = false, bool flip = false,
                                           const PolygonMesh* surface = nullptr,
                                           const Volume* surface_distance = nullptr);

struct UntangleStatistics {
  std::size_t tangled_before = 0;  // faces whose normal disagrees with the field gradient
  std::size_t tangled_after = 0;
  int rounds = 0;
};

// Not in the paper: repairs folds the fit could not avoid (features thinner
// than the mesh, attraction onto a neighbouring sheet). Each round finds the
// faces whose normal disagrees with the field gradient at their centroid
// (normals should point toward lower values, higher with flip), moves the
// corners of those faces to the centroid of their neighbours (boundary ones
// along their boundary; moving the corners' other neighbours as well cost
// miranda 0.8 s more for 0.6% more tangled faces left, and moved the counts
// left on other fields by -20% (mixing at 96^3: 79 -> 63) to +28% (engine
// CT: 126 -> 162 of 1.1 M faces)) and back onto the
// isosurface along the gradient (at most max_move_cells; a vertex without a
// root there stays). A moved vertex around which more faces are tangled than
// before then goes back: without this a round made nearly as many tangles as
// it removed and the repair stalled (three rounds on mixing at 96^3: 1,263 ->
// 1,082 tangled faces, with it -> 737; miranda 701k -> 671k, with it and the
// coarse rounds 642k -> 431k). A round that still does not reduce the number
// of tangled faces is dropped and ends the repair. In place; a round costs
// O(corners and their faces) plus byte scans of the level.
UntangleStatistics untangle(const WrapLevelMesh& mesh, const Volume& field, double iso, bool flip, int rounds,
                            double max_move_cells, std::vector<Vec3>& positions);

struct UnfoldStatistics {
  std::size_t tangled_before = 0;  // faces whose normal disagrees with the field gradient
  std::size_t tangled_after = 0;
  std::size_t moved = 0;  // vertex moves, all rounds
  int rounds = 0;         // rounds that moved a vertex
  // shrink_wrap() only: more than unfold_max_tangled_fraction of the faces
  // were tangled after untangle(); both counts are then untangle()'s.
  bool skipped = false;
};

// Not in the paper: repairs the folds untangle() leaves. Its centroid step
// cannot open a fold several faces wide (a strip of faces lying inverted on
// the surface, all their corners' gradients against them): the centroid
// lies inside the fold, and the rounds stop (mixing at 96^3: 331 faces left
// after any number of rounds). Here each movable corner of a tangled face
// tries a few places: the centroid of its neighbours and its own place
// mirrored through it, the points half-way and nine tenths of the way to
// each neighbour, and the centroids of its faces (a vertex held on a
// boundary curve: the centroid, the mirrored place and the midpoints along
// the curve), each moved onto the isosurface as by the correction (at most
// max_move_cells), and takes the one that most lowers the cost of the faces
// around it (10 per tangled face, plus minus the cosine between its normal
// and the field gradient) plus its squared move in cells; a vertex with no
// such place stays, and is tried again once a vertex of its faces has
// moved. The corners are coloured so that two sharing a face differ; colour
// by colour they move in parallel (Gauss-Seidel across colours, the same
// for any thread count). Until a round moves none, at most `rounds`. In
// place. Costs one scan of the level's faces, then per round O(corners x
// (valence + faces around) x trilinear samples); mixing at 96^3: 450 -> 78
// tangled faces in 10 rounds, 0.02 s.
UnfoldStatistics unfold(const WrapLevelMesh& mesh, const Volume& field, double iso, bool flip, int rounds,
                        double max_move_cells, std::vector<Vec3>& positions);

struct ShrinkWrapOptions {
  int iterations = 3;              // relaxation + attraction rounds on levels 0 .. L-1
  // Rounds on level L. One: on miranda a second changed neither the tangles
  // nor the wavelet RMSE and cost a second; the correction follows anyway.
  int final_level_iterations = 1;
  double relaxation_weight = 0.5;  // paper: average of old position and neighbour centroid
  // Not in the paper: closed base components (no boundary, box-held or
  // sharp vertex) with at most small_component_vertices vertices, all within
  // small_component_cells cells of their centroid: droplets a few cells
  // across or less, mostly tetrahedra. On them the paper's steps fold: the
  // relaxation shrinks a tetrahedron to a third of its size per round, and
  // the attraction along the normals of valence-3 corners, which point
  // anywhere but at the surface, flattens and turns it inside out (mixing at
  // 96^3: a fifth of those droplets' fine faces tangled). Their free
  // vertices instead relax only within the plane normal to their vertex
  // normal (levels 0 .. L-1), and are attracted on every level, and
  // corrected on level L, along the ray from the component's centroid
  // through the vertex to the first crossing of the trilinear field, when
  // the centroid is inside (otherwise as in the paper). 0 vertices: off. A
  // base simplified as far as the rules allow makes every closed genus-0
  // component a tetrahedron, large ones included: hence the size limit.
  std::size_t small_component_vertices = 8;
  double small_component_cells = 3.0;
  AttractionOptions attraction;
  // The extracted isosurface the distance field was built from, for the
  // coverage pull and for the final correction's stranded points (see
  // CorrectionStatistics::from_extracted_surface). nullptr: neither runs.
  const PolygonMesh* surface = nullptr;
  // Not in the paper: the coverage pull (see fit/src/coverage_pull.h). With
  // `surface`, on each level whose edges average at most pull_max_edge_cells cells,
  // every extracted vertex farther than pull_covered_cells from the fit pulls
  // its nearest control point (within pull_reach_cells; on level L
  // final_pull_reach_cells) toward it; a point held on a box face moves
  // within that face (pulled only off the box up to 2026-11-26, the engine's
  // default convert left 471 extracted vertices over 2 cells from the decoded
  // surface where the isosurface meets the z = 0 face in thin strips, now
  // 93; miranda coverage RMS 0.782 -> 0.762 cells, p99 3.46 -> 3.38,
  // tangled 6.59% -> 6.59%). Below L it runs after the last round,
  // and the next attraction puts the pulled points back on the isosurface.
  // On level L (with the final correction) it runs after the correction
  // and untangle() (only the unfold follows), and the pulled points are
  // corrected onto the isosurface; one without a root there, or around which
  // more faces are tangled than at its old place, goes back (27,971 of
  // 71,826 on miranda).
  // Pulled before them, as up to 2026-11-25, the untangling's smoothing took
  // back part of what the pull covered. Miranda, pulled last against pulled
  // after level L's round, both within 4 cells (bench_fit --final-quality
  // --rmse): coverage RMS 1.198 -> 0.994 cells, p99 5.71 -> 4.94; tangled
  // 6.60% -> 6.58%; isosurface RMS 0.079 both; Table 1 rows 14.59 / 28.44 /
  // 49.45 / 87.62 -> 15.26 / 30.76 / 53.41 / 90.24% of a cell (the fuller
  // fit has more detail; without the return for tangles coverage 0.891 /
  // 4.56 but 7.01% tangled and rows 16.50 / 33.69 / 58.02 / 94.88). Mixing
  // at 96^3: coverage max 1.55 -> 1.13 cells, the rest within 0.001, the
  // Table 1 rows of the other test surfaces within 0.1% of a cell. Earlier
  // figures, pull on level L before the correction against no pull at all
  // (miranda, bench_fit, 89,969-vertex base, L = 3): coverage RMS 1.62 ->
  // 1.20 cells, p99 6.98 -> 5.76, for 1 s on each of levels 2 and 3. The
  // Table 1 rows, measured
  // against the fit, rise (12.55 / 24.74 / 43.16 / 78.78 -> 14.58 / 28.46 /
  // 49.52 / 87.47% of a cell): the fuller fit has more detail. Per byte the
  // decoded surface is better: `convert` at 20% 5.76 MB, coverage RMS 1.21
  // cells, against 5.65 MB and 1.61 without; at 5% 2.03 MB and 1.37 against
  // 2.00 MB and 1.70 (the decoded points 0.13 / 0.26 cell RMS from the
  // extracted surface against 0.12 / 0.24). Genus3, hydrogen, viscous fingers
  // and mixing at 96^3: within 0.01 cell (mixing's coverage max 1.59 ->
  // 1.37), tangles unchanged. Pulling the coarser levels too covered a little
  // more of miranda but folded mixing (its base mesh pulled: 0.31% -> 1.34%
  // tangled), hence the edge-length limit.
  bool coverage_pull = true;
  double pull_max_edge_cells = 1.0;
  double pull_covered_cells = 1.0;
  double pull_reach_cells = 4.0;
  // The pull's reach on level L (pulled last, see above). Miranda (bench_fit
  // --final-quality --rmse), 4 -> 8 cells: coverage RMS 0.994 -> 0.780
  // cells, p99 4.94 -> 3.44; tangled 6.58% both; isosurface RMS 0.079 both;
  // Table 1 rows 15.26 / 30.76 / 53.41 / 90.24 -> 15.35 / 31.05 / 54.27 /
  // 91.42% of a cell; level L's pull 1.2-1.5 s -> 1.5-1.7 s in a busy hour.
  // The same reach on the coarser levels as well covered a little more
  // (0.754 / 3.24) but left more points off the isosurface (RMS 0.089) and
  // cost 0.4 s more on level 2. Mixing at 96^3: unchanged.
  double final_pull_reach_cells = 8.0;
  bool final_correction = true;
  double correction_max_cells = 2.0;
  // Not in the paper: a free vertex whose gradient line has no root within
  // correction_max_cells starts again from a nearby point of the signed-
  // distance field's zero set, within 1.5 times that distance (3 cells, the
  // default band): the nearer of those reached by Newton steps along its
  // gradient and by steps of the distance along its unit gradient (where the
  // gradient is short, near the medial axis between two sheets, Newton's
  // steps overshoot). Mixing at 96^3 (2,400-vertex base): 142 of the 224
  // failures corrected, isosurface RMS 0.0149 -> 0.0125 cells (most of the
  // rest are free vertices pressed onto a box face); 0.0240 -> 0.0133 at
  // 64^3, 0.0063 -> 0.0034 at 128^3. Miranda: failures 129,000 -> 37,000,
  // distance to the extracted mesh RMS 0.113 -> 0.103 cells, +0.08 s (with
  // Newton steps alone, within 2 cells). The second step rule and the
  // longer reach (2026-11-26): miranda failures 14,253 -> 7,567, isosurface
  // RMS 0.0724 -> 0.0252 cells, distance to the extracted mesh 0.0994 ->
  // 0.0938; mixing (bench base, 2,400 vertices) 13 -> 5, isosurface RMS
  // 0.0022 -> 0.0006, max 0.795 -> 0.215.
  bool correction_from_nearest_point = true;
  // Rounds of untangle() on level L after the correction (0: none). Each
  // round keeps helping (mixing at 96^3, no coarse rounds: 3 rounds 0.53%
  // tangled, 5 0.45%, 10 0.40%; miranda with five coarse rounds: 5 rounds
  // 662k -> 424k faces) but costs about 0.5 s on miranda: three.
  int untangle_rounds = 3;
  // Not in the paper: rounds of untangle() on levels 0 .. L-1 after their
  // attraction, against the signed-distance field (its zero set and its
  // gradient). Half the folds left on level L are inherited from a few dozen
  // coarse faces that lie folded over thin sheets and filaments (the
  // simplified base already has 62 of 2,126 faces tangled on mixing); a
  // subdivided fold is not repaired on level L. Mixing at 96^3 (with three
  // rounds on level L): tangled 0.53% -> 0.34% with two, 0.31% with five.
  // Miranda (both changes to untangle()): tangled 10.0% -> 6.4%, wavelet
  // RMSE rows (20/10/5%/base) 12.61/24.50/43.71/89.73 -> 12.54/24.72/43.13/
  // 78.68% of a cell, untangle time 1.6 -> 2.9 s (0.7 s of it coarse).
  int coarse_untangle_rounds = 2;
  // Rounds of unfold() on level L, last, after the pull (0: none); skipped
  // when more than unfold_max_tangled_fraction of the faces are tangled
  // (as untangle() left them, or counted after the pull without it). The
  // unfold repairs folds a few faces wide at a cost of about 15 us per
  // vertex move; where a fit is tangled throughout, by features
  // thinner than its base mesh can follow, it would cost seconds and raise
  // the wavelet RMSE more. Measured 2026-11-25 (base 1/16 of the isosurface,
  // 3 levels; tangled before -> after, time, RMSE at 20% of the
  // coefficients in % of a cell): mixing at 96^3 0.32% -> 0.06%, 0.02 s,
  // 4.41 -> 4.50; engine CT 0.042% -> 0.015%, 0.06 s, 1.68 -> 1.69;
  // aneurism 1.19% -> 0.22%, 0.20 s, 6.52 -> 6.85; heptane 1.22% -> 0.20%,
  // 0.23 s, 5.38 -> 5.63. Skipped: HCCI 4.1% (forced: 0.79%, 1.27 s,
  // 10.42 -> 11.36), stent 5.2% (0.98%, 1.27 s, 12.36 -> 13.81) and
  // miranda 6.6% (2.0%, 12.5 s, 15.35 -> 16.99, before the mirrored and
  // near-neighbour places).
  int unfold_rounds = 10;
  double unfold_max_tangled_fraction = 0.02;
  // Keep a copy of every level's fitted positions (for per-level reports).
  bool keep_levels = false;
};

struct WrapLevelStatistics {
  int level = 0;
  std::size_t vertices = 0;
  std::size_t boundary_vertices = 0;  // held on a box face
  std::size_t fixed_vertices = 0;
  AttractionStatistics last_attraction;
  double seconds = 0;  // the whole level, the phases below included
  double seconds_setup = 0;       // refinement to this level and its connectivity
  double seconds_relaxation = 0;  // all rounds
  double seconds_attraction = 0;  // all rounds
  double seconds_correction = 0;  // level L only
  double seconds_untangle = 0;    // untangle() on level L, coarse_untangle_rounds below
  double seconds_pull = 0;        // all rounds
  double seconds_unfold = 0;      // level L only
  double mean_edge_cells = 0;     // after refinement, before the rounds (measured with `surface` only; from at most about 2^18 vertices)
  std::size_t uncovered_samples = 0;  // the level's pull (0 if it did not pull)
  std::size_t pulled_vertices = 0;
  std::size_t pulled_back = 0;  // level L: pulled points returned (no root on the isosurface, or folding)
};

struct ShrinkWrapResult {
  // Level-L control points in the hierarchy's order: ready for analyze().
  std::vector<Vec3> positions;
  // With keep_levels: level_positions[l] for l in [0, L) after fitting level l.
  std::vector<std::vector<Vec3>> level_positions;
  std::vector<WrapLevelStatistics> levels;
  CorrectionStatistics correction;  // zeros when the correction is off
  UntangleStatistics untangle;
  // Unless skipped, its tangled_after counts the level-L faces tangled in
  // the result; zeros when the unfold is off.
  UnfoldStatistics unfold;
  // Level-L faces tangled in the result as last counted: the unfold's
  // count, or, when it was skipped or off, untangle()'s (before the pull,
  // which changes few), or without untangle() a count after the pull.
  std::size_t tangled_faces = 0;
};

// Fits the hierarchy to the zero set of `distance` (computed from `field`,
// whose grid it must share) starting from the base control points.
// Throws Error(InvalidArgument) if base_positions has fewer than
// vertex_count(0) entries or a non-finite one, or one more than a cell
// outside the volume's box, or one on a boundary of the base more than a
// cell from the box's faces (extracted isosurfaces have boundaries only
// there), if the base faces against the field (most
// vertex normals toward higher values, or lower ones with distance.flip),
// the grids differ, or an option is out of range (iterations 0..100, weight
// in (0, 1], reaches > 0).
ShrinkWrapResult shrink_wrap(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                             const SignedDistanceField& distance, const Volume& field,
                             const ShrinkWrapOptions& options = {}, ProgressSink& progress = no_progress());

}  // namespace isowave
