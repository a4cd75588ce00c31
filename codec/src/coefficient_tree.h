#pragma once
// Private: the parent-child tree of the coefficient array that the embedded
// coder's significance contexts follow (SPIHT's spatial orientation trees on
// the subdivision hierarchy). Every level-l quad is (v, e, f, e') and every
// level-l edge has exactly one e endpoint, so for l >= 1:
//   - the f detail of a level-l face opens level l + 1 under the face's f corner;
//   - the e detail of a level-l edge opens level l + 1 under the edge's e endpoint.
// Every level-(l+1) coefficient thus has exactly one parent at level l. Roots:
// the base control points (no children) and the level-1 coefficients.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "isowave/transform/hierarchy.h"

namespace isowave::detail {

struct CoefficientTree {
  std::size_t nodes = 0;      // the hierarchy's fine vertex count: one node per entry
  std::size_t roots_end = 0;  // entries [0, roots_end) are roots: base and level 1
  std::vector<std::uint32_t> level_ends;  // entries of level l end at level_ends[l] (l = 0..L)
  // Parent of node i >= roots_end (always a smaller index), or UINT32_MAX for
  // roots. The plane coder derives the children in its own node order.
  std::vector<std::uint32_t> parent;
};

// Cost: O(fine vertices) time and 4 bytes per entry.
CoefficientTree build_coefficient_tree(const SubdivisionHierarchy& hierarchy);

// The nodes in `groups` independent parts (docs/FORMAT.md, PLNS): the roots
// in index order cut into runs of about equal subtree size, each with all its
// descendants. Group g's members, ascending (so parents before children):
// members[offsets[g] .. offsets[g + 1]]. Requires groups >= 1; groups may
// exceed the roots (then some are empty). Cost: O(nodes), 12 bytes per node.
struct TreeGroups {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> members;
  std::size_t count() const { return offsets.size() - 1; }
};
TreeGroups split_tree(const CoefficientTree& tree, std::size_t groups);
// The same with each root's group given (`root_group`, tree.roots_end
// values below `groups`; version 2.2's groups by space, plane_groups.h).
TreeGroups split_tree(const CoefficientTree& tree, const std::vector<std::uint32_t>& root_group, std::size_t groups);

}  // namespace isowave::detail
