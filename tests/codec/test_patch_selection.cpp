// A region decode's patch (codec/src/patch_selection.h) against the whole
// hierarchy: the groups it selects are those of the entries the seed faces'
// fine control points depend on, found in the whole hierarchy (also when
// the patch must grow to hold them), and its tree is the whole tree's nodes
// of those groups, in the whole order, with the whole tree's parents,
// levels and groups.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "isowave/codec/region.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/patch_hierarchy.h"
#include "coefficient_tree.h"
#include "patch_selection.h"
#include "plane_groups.h"
#include "support/test_meshes.h"

namespace isowave::detail {
namespace {

// A jittered 30 x 20 grid with some quads split into triangles, in groups
// of runs of 37 faces (any partition is a valid one), each with a reach.
struct Case {
  PolygonMesh base;
  std::vector<std::uint32_t> face_group;
  std::vector<float> reach;
};

Case make_case(int levels) {
  Case c;
  const PolygonMesh grid = test::quad_grid(30, 20);
  std::mt19937 rng(5);
  c.base.positions = grid.positions;
  for (std::size_t f = 0; f < grid.face_count(); ++f) {
    const std::uint32_t* v = grid.face_begin(f);
    if (rng() % 5 == 0) {
      c.base.add_face({v[0], v[1], v[2]});
      c.base.add_face({v[0], v[2], v[3]});
    } else {
      c.base.add_face({v[0], v[1], v[2], v[3]});
    }
  }
  test::jitter(c.base, 0.2, 3);
  for (std::size_t f = 0; f < c.base.face_count(); ++f) c.face_group.push_back(static_cast<std::uint32_t>(f / 37));
  c.reach.assign(c.face_group.back() + 1, 0.1f * static_cast<float>(levels));
  return c;
}

// The whole hierarchy's answer: the groups of the entries the fine control
// points of the faces meeting the region depend on, and the groups' nodes.
struct Reference {
  std::vector<std::uint8_t> selected;
  std::vector<std::uint32_t> nodes;  // ascending
  CoefficientTree tree;
};

Reference reference(const Case& c, const RegionOfInterest& region, int levels) {
  const SubdivisionHierarchy h(c.base, levels);
  Reference r;
  r.tree = build_coefficient_tree(h);
  const TreeGroups split =
      split_tree(r.tree, root_groups(root_faces(h, r.tree), c.face_group), c.reach.size());
  std::vector<std::uint32_t> group(r.tree.nodes);
  for (std::size_t g = 0; g < split.count(); ++g)
    for (std::uint32_t k = split.offsets[g]; k < split.offsets[g + 1]; ++k) group[split.members[k]] = static_cast<std::uint32_t>(g);
  std::vector<std::uint8_t> points(h.fine_vertex_count(), 0);
  for (std::size_t f = 0; f < c.base.face_count(); ++f) {
    Vec3 lo, hi;
    face_box(c.base, c.base.positions, f, c.reach[c.face_group[f]], lo, hi);
    if (region.meets_box(lo, hi)) for_each_fine_point(h, f, [&](std::size_t v) { return points[v] = 1; });
  }
  const std::vector<std::uint8_t> needed = entries_for_points(h, points);
  r.selected.assign(c.reach.size(), 0);
  for (std::size_t k = 0; k < needed.size(); ++k)
    if (needed[k]) r.selected[group[k]] = 1;
  for (std::size_t k = 0; k < group.size(); ++k)
    if (r.selected[group[k]]) r.nodes.push_back(static_cast<std::uint32_t>(k));
  return r;
}

void expect_matches(const Case& c, const RegionOfInterest& region, int levels, int candidate_rings) {
  SCOPED_TRACE("L=" + std::to_string(levels) + " candidate rings " + std::to_string(candidate_rings));
  const Reference r = reference(c, region, levels);
  const BaseIncidence incidence = base_incidence(c.base);
  const PatchSelection s = select_patch(c.base, incidence, c.face_group, c.reach, PatchTarget{&region, nullptr}, levels, candidate_rings);
  EXPECT_EQ(s.selected, r.selected);
  EXPECT_GT(std::count(s.selected.begin(), s.selected.end(), 1), 0);
  EXPECT_LT(std::count(s.selected.begin(), s.selected.end(), 1), static_cast<long>(s.selected.size()));
  const CoefficientClasses layout(SubdivisionHierarchy(c.base, levels));
  const SelectedTree t = selected_tree(s, layout);
  const std::vector<std::uint32_t>& entries = s.patch->entries();
  std::vector<std::uint32_t> nodes;
  for (const std::uint32_t k : t.node_entry) nodes.push_back(entries[k]);
  ASSERT_EQ(nodes, r.nodes);
  // Parents, levels and classes as in the whole tree.
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const std::uint32_t whole_parent = r.tree.parent[nodes[i]];
    if (whole_parent == UINT32_MAX) EXPECT_EQ(t.tree.parent[i], UINT32_MAX) << i;
    else EXPECT_EQ(nodes[t.tree.parent[i]], whole_parent) << i;
    EXPECT_EQ(t.node_class[i], layout.of(nodes[i]));
  }
  for (std::size_t l = 0; l < r.tree.level_ends.size(); ++l)
    EXPECT_EQ(t.tree.level_ends[l], std::lower_bound(nodes.begin(), nodes.end(), r.tree.level_ends[l]) - nodes.begin());
  // Each selected group's nodes, none of the others'.
  for (std::size_t g = 0; g < t.groups.count(); ++g)
    for (std::uint32_t k = t.groups.offsets[g]; k < t.groups.offsets[g + 1]; ++k) EXPECT_TRUE(s.selected[g]);
}

TEST(PatchSelection, SelectsTheGroupsAndNodesTheWholeHierarchyNames) {
  for (int levels = 1; levels <= 3; ++levels) {
    const Case c = make_case(levels);
    for (const char* box : {"4,4,-5,9,8,5", "0,0,-5,30,2,5", "14.5,9.5,-5,15.5,10.5,5"}) {
      SCOPED_TRACE(box);
      const RegionOfInterest region = parse_region(box, false, "--roi");
      expect_matches(c, region, levels, kExactRings);
      expect_matches(c, region, levels, 0);  // the patch grows to the groups found beyond
    }
  }
}

}  // namespace
}  // namespace isowave::detail
