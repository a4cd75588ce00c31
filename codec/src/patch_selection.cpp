#include "patch_selection.h"

#include <algorithm>
#include <numeric>

#include "isowave/codec/region.h"
#include "plane_groups.h"

namespace isowave::detail {

namespace {

// Per patch entry: its group in the whole tree (plane_groups.h's owners: a
// base control point's first face, a level-1 f vertex's face, a level-1 e
// vertex's smaller face; a finer entry its tree parent's group).
std::vector<std::uint32_t> entry_groups(const PatchHierarchy& patch, const CoefficientTree& tree,
                                        const BaseIncidence& incidence, const std::vector<std::uint32_t>& face_group) {
  const std::vector<std::uint32_t>& entries = patch.entries();
  const std::size_t vertices = incidence.vertex_face_offsets.size() - 1, faces = face_group.size();
  std::vector<std::uint32_t> group(entries.size());
  for (std::size_t k = 0; k < tree.roots_end; ++k) {
    const std::size_t g = entries[k];
    std::uint32_t owner = 0;
    if (g < vertices) {
      owner = incidence.vertex_faces[incidence.vertex_face_offsets[g]];
    } else if (g < vertices + faces) {
      owner = static_cast<std::uint32_t>(g - vertices);
    } else {
      const std::size_t e = g - vertices - faces;
      owner = std::min(incidence.edge_faces[2 * e], incidence.edge_faces[2 * e + 1]);
    }
    group[k] = face_group[owner];
  }
  for (std::size_t k = tree.roots_end; k < entries.size(); ++k) group[k] = group[tree.parent[k]];
  return group;
}

// Step 1.
std::vector<std::uint8_t> seed_faces(const PolygonMesh& base, const std::vector<std::uint32_t>& face_group,
                                     const std::vector<float>& reach, const PatchTarget& target) {
  std::vector<std::uint8_t> seeds(base.face_count(), 0);
  for (std::size_t f = 0; f < seeds.size(); ++f) {
    Vec3 lo, hi;
    face_box(base, base.positions, f, reach[face_group[f]], lo, hi);
    seeds[f] = target.meets(lo, hi);
  }
  return seeds;
}

// Step 3: the groups of the entries the seeds' fine control points depend on.
std::vector<std::uint8_t> groups_for_seeds(const PatchSelection& s, const std::vector<std::uint8_t>& is_seed,
                                           std::size_t groups) {
  const SubdivisionHierarchy& h = s.patch->hierarchy();
  std::vector<std::uint8_t> points(h.fine_vertex_count(), 0);
  for (std::size_t f = 0; f < s.patch->faces().size(); ++f)
    if (is_seed[s.patch->faces()[f]]) for_each_fine_point(h, f, [&](std::size_t v) { return points[v] = 1; });
  const std::vector<std::uint8_t> needed = entries_for_points(h, points);
  std::vector<std::uint8_t> selected(groups, 0);
  for (std::size_t k = 0; k < needed.size(); ++k)
    if (needed[k]) selected[s.group[k]] = 1;
  return selected;
}

}  // namespace

PatchSelection select_patch(const PolygonMesh& base, const BaseIncidence& incidence,
                            const std::vector<std::uint32_t>& face_group, const std::vector<float>& reach,
                            const PatchTarget& target, int levels, int candidate_rings) {
  PatchSelection s;
  const std::vector<std::uint8_t> is_seed = seed_faces(base, face_group, reach, target);
  for (std::size_t f = 0; f < is_seed.size(); ++f)
    if (is_seed[f]) s.seeds.push_back(static_cast<std::uint32_t>(f));
  s.selected.assign(reach.size(), 0);
  if (s.seeds.empty()) return s;  // no patch: nothing to decode
  std::vector<std::uint8_t> near = is_seed, candidates(reach.size(), 0);
  for (const std::uint32_t f : grow_patch(base, incidence, near, candidate_rings)) candidates[face_group[f]] = 1;
  std::vector<std::uint8_t> rings = is_seed;
  grow_patch(base, incidence, rings, 2 * kExactRings);
  for (;;) {
    std::vector<std::uint8_t> in_patch(base.face_count(), 0);
    for (std::size_t f = 0; f < in_patch.size(); ++f) in_patch[f] = candidates[face_group[f]];
    grow_patch(base, incidence, in_patch, 1);
    for (std::size_t f = 0; f < in_patch.size(); ++f) in_patch[f] |= rings[f];
    s.patch.emplace(base, incidence, grow_patch(base, incidence, in_patch, 0), levels);
    s.tree = build_coefficient_tree(s.patch->hierarchy());
    s.group = entry_groups(*s.patch, s.tree, incidence, face_group);
    s.selected = groups_for_seeds(s, is_seed, reach.size());
    bool beyond = false;
    for (std::size_t g = 0; g < candidates.size(); ++g)
      if (s.selected[g] && !candidates[g]) {
        candidates[g] = 1;
        beyond = true;
      }
    if (!beyond) return s;
  }
}

SelectedTree selected_tree(const PatchSelection& selection, const CoefficientClasses& layout) {
  const SubdivisionHierarchy& h = selection.patch->hierarchy();
  const std::vector<std::uint32_t>& entries = selection.patch->entries();
  const CoefficientTree& local = selection.tree;
  const std::vector<std::uint32_t>& group = selection.group;
  const std::vector<std::uint8_t>& selected = selection.selected;
  // The nodes in the whole order (by an array over the whole entries: a sort costs more).
  SelectedTree out;
  std::vector<std::uint32_t> at(layout.fine(), UINT32_MAX);
  for (std::size_t k = 0; k < entries.size(); ++k)
    if (selected[group[k]]) at[entries[k]] = static_cast<std::uint32_t>(k);
  for (const std::uint32_t k : at)
    if (k != UINT32_MAX) out.node_entry.push_back(k);
  const std::size_t n = out.node_entry.size();
  std::vector<std::uint32_t> node_of(entries.size(), UINT32_MAX);
  for (std::size_t i = 0; i < n; ++i) node_of[out.node_entry[i]] = static_cast<std::uint32_t>(i);
  // The tree: nodes in the whole order, so roots first and levels in runs.
  CoefficientTree& t = out.tree;
  t.nodes = n;
  const int levels = h.levels();
  const auto nodes_below = [&](std::size_t whole_end) {
    return static_cast<std::uint32_t>(std::partition_point(out.node_entry.begin(), out.node_entry.end(),
                                                           [&](std::uint32_t k) { return entries[k] < whole_end; }) -
                                      out.node_entry.begin());
  };
  for (int l = 0; l <= levels; ++l)
    t.level_ends.push_back(nodes_below(l == 0 ? layout.base() : layout.range(2 * l).second));
  t.roots_end = t.level_ends[levels >= 1 ? 1 : 0];
  t.parent.resize(n);
  out.node_class.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t k = out.node_entry[i];
    t.parent[i] = k < local.roots_end ? UINT32_MAX : node_of[local.parent[k]];
    out.node_class[i] = static_cast<std::uint8_t>(layout.of(entries[k]));
  }
  // The groups: every group's nodes in order, the unselected empty.
  std::vector<std::uint32_t> root_group(t.roots_end);
  for (std::size_t i = 0; i < t.roots_end; ++i) root_group[i] = group[out.node_entry[i]];
  out.groups = split_tree(t, root_group, selected.size());
  return out;
}

}  // namespace isowave::detail
