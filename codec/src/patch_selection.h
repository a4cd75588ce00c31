#pragma once
// Private: what a region or view decode of a 2.2 file builds instead of the
// whole hierarchy (issue #48, item 5; docs/FORMAT.md, "Version 2.2"):
//   1. the seed faces: base faces whose corners' box, grown by their group's
//      reach (GIDX), meets the region or may lie in the camera's view
//      frustum: every fine control point inside the region (in the view)
//      belongs to one;
//   2. the patch: the seeds and 2 kExactRings rings (their fine control
//      points, and the local frames of the entries those depend on, are
//      then the whole hierarchy's), and every face of the groups within
//      kExactRings rings of a seed with one ring more (the faces their tree
//      nodes lie on: a group's roots are owned by its faces, and a level-1
//      e vertex's descendants lie on the two faces of its base edge);
//   3. the groups holding an entry that a seed face's fine control point
//      depends on (region.h's entries_for_points() in the patch; the patch
//      grows by the groups found beyond those of step 2, which the lifting
//      steps' reach leaves none on every file measured);
//   4. the plane decoder's tree over those groups' nodes only, in the whole
//      tree's order, so that their packets decode as in a complete decode.
#include <cstdint>
#include <optional>
#include <vector>

#include "isowave/codec/camera.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/region_of_interest.h"
#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/transform/patch_hierarchy.h"
#include "coefficient_tree.h"

namespace isowave::detail {

// What the seeds meet: a region, or (without one) a view frustum.
struct PatchTarget {
  const RegionOfInterest* region = nullptr;
  const Camera* frustum = nullptr;
  bool meets(const Vec3& lo, const Vec3& hi) const {
    return region ? region->meets_box(lo, hi) : !frustum->box_outside(lo, hi);
  }
};

struct PatchSelection {
  std::vector<std::uint32_t> seeds;    // base faces, ascending (step 1)
  std::optional<PatchHierarchy> patch;  // step 2; none without seeds
  CoefficientTree tree;                 // the patch's
  std::vector<std::uint32_t> group;     // per patch entry: its group in the whole tree
  std::vector<std::uint8_t> selected;   // per group: decoded (step 3)
};

// Steps 1-3 for `target` over `base` (positions: the frame base, BPTS) with
// its groups (`face_group`, per base face; `reach`, per group), `levels`
// levels; step 2 takes the groups within `candidate_rings` rings (fewer
// make step 3 grow the patch, as a test forces). Cost: the patch's
// hierarchy and one transposed synthesis over it (more when it grows).
PatchSelection select_patch(const PolygonMesh& base, const BaseIncidence& incidence,
                            const std::vector<std::uint32_t>& face_group, const std::vector<float>& reach,
                            const PatchTarget& target, int levels, int candidate_rings = kExactRings);

// Step 4: the nodes of the selected groups, ascending by their entry in
// the whole array (`node_entry`, the patch's entry of each), their tree
// (parents and levels as in the whole tree) and groups (offsets over every
// group, the unselected empty), and their classes.
struct SelectedTree {
  CoefficientTree tree;
  TreeGroups groups;
  std::vector<std::uint8_t> node_class;
  std::vector<std::uint32_t> node_entry;  // per node: its patch entry
};
SelectedTree selected_tree(const PatchSelection& selection, const CoefficientClasses& layout);

}  // namespace isowave::detail
