#pragma once
// Private: the groups of the plane stream's tree by space, and their index
// (docs/FORMAT.md, "Version 2.2"). Minor versions 0 and 1 cut the roots in
// index order (split_tree(tree, groups)); minor version 2 groups them so that
// a reader finds a region's coefficients (issue #48, item 5):
//   - the base faces in Morton (Z-order) order of their centroids, computed in
//     the frame base's integers (BPTS), which the decoder has before any plane;
//   - every root owned by one base face: a base control point by the first
//     face (by index) that uses it, a level-1 f vertex by its face, a level-1
//     e vertex by the smaller of its edge's faces;
//   - the face order cut into runs, one group per run (the file stores the
//     runs: the encoder chooses them, the decoder only follows them).
// The GIDX section holds the runs, each group's reach (how far the complete
// decode's fine control points lie from their base faces' corners, so that a
// reader knows which faces may meet a region before decoding any plane) and
// CRC-32s of the packet table and of each group's packets, so that a reader
// that seeks to one group's packets can check them without the whole
// section's bytes.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"
#include "coefficient_tree.h"
#include "isw_models.h"
#include "isw_sections.h"

namespace isowave::detail {

// The encoder's target of tree nodes per group (a run ends once it holds
// this many): small enough that a region reads little beyond itself, large
// enough that each group's contexts learn (docs/MEASUREMENTS.md).
constexpr std::size_t kSpatialGroupNodes = std::size_t{1} << 15;
// No bound on the groups of a file this library wrote (rewrite_isw()).
constexpr std::uint64_t kMaxStreamGroups = std::uint64_t{1} << 32;

// Base faces in Morton order of their centroids (the corners' integer
// coordinates `base_q`, summed and divided by the corner count, rounded
// down, then shifted into 21 bits per axis), ties by index. Integer
// arithmetic only, so that encoder and decoder agree on any host.
// Cost: O(faces log faces).
struct FaceOrder {
  std::vector<std::uint32_t> faces;  // in Morton order
  std::vector<std::uint64_t> keys;   // their Morton keys (63 bits), ascending
};
FaceOrder morton_face_order(const PolygonMesh& base, const std::vector<QuantizedVector>& base_q);

// Per root of `tree` (entries [0, tree.roots_end)): the base face that owns
// it, as above. A base without faces owns nothing (every root face 0).
std::vector<std::uint32_t> root_faces(const SubdivisionHierarchy& hierarchy, const CoefficientTree& tree);

// The encoder's runs: octree cells of the Morton order (a root's subtree
// counting with its owner), split until they hold at most `target` nodes
// (or one key), consecutive cells joined while a run stays within `target`;
// faces per run. Runs of whole cells are compact in space, which a run cut
// anywhere in the order is not: a region then reads fewer groups.
std::vector<std::uint32_t> cut_face_runs(const CoefficientTree& tree, const std::vector<std::uint32_t>& root_face,
                                         const FaceOrder& order, std::size_t target);

// Per base face, its group (the run holding it in `face_order`); per root,
// its group (its owner's). Requires the runs to sum to the face count.
std::vector<std::uint32_t> face_groups(const std::vector<std::uint32_t>& face_order,
                                       const std::vector<std::uint32_t>& runs);
std::vector<std::uint32_t> root_groups(const std::vector<std::uint32_t>& root_face,
                                       const std::vector<std::uint32_t>& face_group);

// GIDX: LEB128 group count G, LEB128 faces per group, per group f32 reach
// (world units, >= 0: every fine control point of the group's faces, in the
// complete decode, lies within that distance per axis of the box of its base
// face's frame-base corners), u32 CRC-32 of PLNS's payload before its
// packets, per group u32 CRC-32 of its packets in stream order.
struct GroupIndex {
  std::vector<std::uint32_t> runs;  // faces per group, each >= 1
  std::vector<float> reach;         // per group
  std::uint32_t table_crc = 0;
  std::vector<std::uint32_t> group_crc;
  std::size_t count() const { return runs.size(); }
};
void put_group_index(std::string& out, const GroupIndex& index);
// A GIDX payload of `groups.size()` groups (the writer's own) with its CRCs replaced.
std::string with_crcs(std::string_view payload, std::uint32_t table_crc, const std::vector<std::uint32_t>& groups);
// Error(Format) through `reader` unless the runs are positive and sum to
// `base_faces` and every reach is finite and >= 0.
GroupIndex read_group_index(PayloadReader& reader, std::size_t base_faces);

// The box of base face f's corners in `frame_base`, grown by `reach`.
void face_box(const PolygonMesh& base, const std::vector<Vec3>& frame_base, std::size_t f, double reach, Vec3& lo,
              Vec3& hi);
// The reaches of `index` (runs set) from the fine control points `fine`
// (the complete decode's) and the frame base. O(fine vertices).
void set_group_reach(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& frame_base,
                     const std::vector<Vec3>& fine, const std::vector<std::uint32_t>& face_group, GroupIndex& index);

// CRC-32 of group g's packets (packet j = k G + g, in stream order) of
// `packets`; the same for every group at once.
std::vector<std::uint32_t> group_crcs(const std::vector<std::string_view>& packets, std::size_t groups);
std::uint32_t bytes_crc(std::string_view bytes);

}  // namespace isowave::detail
