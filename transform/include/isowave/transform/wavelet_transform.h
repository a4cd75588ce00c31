#pragma once
// The lifted bicubic subdivision-surface wavelet transform (Bertram et al.
// 2000, Sec. 3.3-3.4), in place over the coarse-to-fine layout of
// SubdivisionHierarchy: one array whose first vertex_count(0) entries are base
// control points and whose entries [vertex_count(l-1), vertex_count(l)) are
// the level-l wavelet coefficients (f details, then e details). Control
// points and coefficients are 3-vectors in the mesh's world units.
//
// Both directions run level by level, each lifting step split across threads
// (TBB); every output is a fixed-order gather, so results are bit-identical
// for any thread count. Cost per direction: O(fine vertices).
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// Analysis (decomposition rules 3.10): `data` holds the level-L control points
// on entry (at least vertex_count(L) entries) and the base control points plus
// all wavelet coefficients on return.
void analyze(const SubdivisionHierarchy& hierarchy, std::vector<Vec3>& data);

// Synthesis (reconstruction rules 3.8) from the base up to `to_level` (default
// the finest): on entry `data` holds base control points and coefficients (at
// least vertex_count(to_level) entries; coefficients of finer levels are left
// untouched), on return its first vertex_count(to_level) entries are the
// control points of level `to_level`.
void synthesize(const SubdivisionHierarchy& hierarchy, std::vector<Vec3>& data, int to_level = -1);

// One level of synthesis, in place: on entry the first vertex_count(level - 1)
// entries of `data` are control points of level - 1 and the next ones up to
// vertex_count(level) the level's coefficients; on return the first
// vertex_count(level) entries are the control points of `level`.
void synthesize_level(const SubdivisionHierarchy& hierarchy, int level, std::vector<Vec3>& data);

// The subdivision operator S applied `to_level` times (synthesis with every
// wavelet coefficient zero): control points of level `to_level` from the base
// control points (vertex_count(0) entries).
std::vector<Vec3> subdivide(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_points,
                            int to_level = -1);

// One level of S: on entry the first vertex_count(level - 1) entries of `data`
// are control points of level - 1; on return the first vertex_count(level)
// entries are those of `level` (its wavelet coefficients taken as zero).
// Shrink-wrap fitting refines with this, level by level.
void subdivide_level(const SubdivisionHierarchy& hierarchy, int level, std::vector<Vec3>& data);

// Per entry of the coarse-to-fine array, the squared L2 norm over the fine
// control points of its wavelet: the synthesis to the finest level of the
// unit vector at that entry (one component), exactly (to rounding), by
// following its support through the lifting steps; 0 for base entries.
// Greedy truncation weighs coefficients by it (codec/importance.h). Cost:
// each wavelet's support at every level it crosses, summed: O(levels x fine
// vertices x the finest supports), many syntheses' worth; parallel; a
// double and two 32-bit marks per fine vertex per thread.
std::vector<double> wavelet_squared_norms(const SubdivisionHierarchy& hierarchy);

// The transpose of one level of synthesis. Synthesis of `level` is a linear
// map from (level-(level-1) control points, level-`level` coefficients) to
// level-`level` control points, in place over the first vertex_count(level)
// entries; this applies its transpose in place: on entry `data` holds a
// vector g over the level's control points, on return the entries hold
// S^T g over the coarser control points and the level's coefficients, so that
// <synthesis(x), g> = <x, S^T g> for every x. Least-squares fits through
// synthesis (fit/normal_fit.h) take their gradients with it. Assumes no face
// holds the same edge twice (require_manifold). Cost: O(vertex_count(level)),
// parallel, bit-identical for any thread count.
void synthesize_level_transpose(const SubdivisionHierarchy& hierarchy, int level, std::vector<Vec3>& data);

}  // namespace isowave
