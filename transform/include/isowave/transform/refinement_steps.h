#pragma once
// How SubdivisionHierarchy gets its refinement steps (an implementation
// detail, public so that a test can compare the two builders).
//
// The base level's edges and neighbourhood orders are completed from the face
// lists as OpenSubdiv's Vtr::Level completes them, and the finer levels follow
// Vtr::QuadRefinement's numbering, all in flat arrays and the finer levels in
// parallel. That numbering fixes the coefficient order of .isw files, so the
// result must equal, array for array, what OpenSubdiv's uniform refinement
// gives: build_refinement_steps_with_opensubdiv() is that reference.
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/transform/hierarchy.h"

namespace isowave::detail {

// Both take a base mesh that passed require_manifold() and 0 <= levels <=
// SubdivisionHierarchy::kMaxLevels. build_refinement_steps() throws
// Error(InvalidArgument) before refining if the finest level would not fit
// 32-bit indices, Error(Topology) for a vertex or face beyond OpenSubdiv's
// valence limit (65535). Cost: O(fine vertices), the finer levels parallel
// (TBB).
std::vector<RefinementStep> build_refinement_steps(const PolygonMesh& base, int levels);
// The reference: Far::TopologyRefiner::RefineUniform, read level by level
// through Far::TopologyLevel. Slower, single-threaded; for tests.
std::vector<RefinementStep> build_refinement_steps_with_opensubdiv(const PolygonMesh& base, int levels);

}  // namespace isowave::detail
