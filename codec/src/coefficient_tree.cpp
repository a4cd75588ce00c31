#include "coefficient_tree.h"

#include <algorithm>
#include <cassert>

namespace isowave::detail {

namespace {

// The parent (a level-`level` vertex) of every coefficient of level + 1.
void link_level(const SubdivisionHierarchy& hierarchy, int level, std::vector<std::uint32_t>& parent) {
  const RefinementStep& into = hierarchy.step(level);     // level - 1 -> level: where level's f and e vertices lie
  const RefinementStep& next = hierarchy.step(level + 1);  // level -> level + 1
  const std::uint32_t f_first = into.first_face_vertex(), e_first = into.first_edge_vertex();
  const std::uint32_t e_end = into.child_vertex_count();
  for (std::uint32_t face = 0; face < next.parent_face_count; ++face) {
    std::uint32_t owner = UINT32_MAX;
    for (std::uint32_t k = next.face_offsets[face]; k < next.face_offsets[face + 1]; ++k) {
      const std::uint32_t v = next.face_vertices[k];
      if (v >= f_first && v < e_first) owner = v;
    }
    assert(owner != UINT32_MAX);
    parent[next.first_face_vertex() + face] = owner;
  }
  for (std::uint32_t edge = 0; edge < next.parent_edge_count; ++edge) {
    const std::uint32_t a = next.edge_vertices[2 * edge], b = next.edge_vertices[2 * edge + 1];
    const std::uint32_t owner = a >= e_first && a < e_end ? a : b;
    assert(owner >= e_first && owner < e_end);
    parent[next.first_edge_vertex() + edge] = owner;
  }
}

}  // namespace

CoefficientTree build_coefficient_tree(const SubdivisionHierarchy& hierarchy) {
  CoefficientTree tree;
  const int levels = hierarchy.levels();
  tree.nodes = hierarchy.fine_vertex_count();
  tree.roots_end = hierarchy.vertex_count(levels >= 1 ? 1 : 0);
  for (int level = 0; level <= levels; ++level)
    tree.level_ends.push_back(static_cast<std::uint32_t>(hierarchy.vertex_count(level)));
  tree.parent.assign(tree.nodes, UINT32_MAX);
  for (int level = 1; level < levels; ++level) link_level(hierarchy, level, tree.parent);
  return tree;
}

TreeGroups split_tree(const CoefficientTree& tree, std::size_t groups) {
  assert(groups >= 1);
  // Subtree sizes (children have larger indices than their parents).
  std::vector<std::uint32_t> size(tree.nodes, 1);
  for (std::size_t i = tree.nodes; i-- > tree.roots_end;) size[tree.parent[i]] += size[i];
  std::vector<std::uint32_t> root_group(tree.roots_end, 0);
  std::uint64_t before = 0;
  for (std::size_t r = 0; r < tree.roots_end; ++r) {
    root_group[r] = static_cast<std::uint32_t>(std::min<std::uint64_t>(groups - 1, before * groups / tree.nodes));
    before += size[r];
  }
  return split_tree(tree, root_group, groups);
}

TreeGroups split_tree(const CoefficientTree& tree, const std::vector<std::uint32_t>& root_group, std::size_t groups) {
  assert(groups >= 1 && root_group.size() == tree.roots_end);
  std::vector<std::uint32_t> group(tree.nodes, 0);
  std::copy(root_group.begin(), root_group.end(), group.begin());
  for (std::size_t i = tree.roots_end; i < tree.nodes; ++i) group[i] = group[tree.parent[i]];
  TreeGroups result;
  result.offsets.assign(groups + 1, 0);
  for (std::size_t i = 0; i < tree.nodes; ++i) ++result.offsets[group[i] + 1u];
  for (std::size_t g = 0; g < groups; ++g) result.offsets[g + 1] += result.offsets[g];
  result.members.resize(tree.nodes);
  std::vector<std::uint32_t> fill(result.offsets.begin(), result.offsets.end() - 1);
  for (std::size_t i = 0; i < tree.nodes; ++i) result.members[fill[group[i]]++] = static_cast<std::uint32_t>(i);
  return result;
}

}  // namespace isowave::detail
