#pragma once
// Private: the embedded bit-plane coder of .isw 2.0 and 2.1 (docs/FORMAT.md, PLNS;
// issue #34). Every node of the coefficient tree carries three non-negative
// integer magnitudes (its components in step units) and their signs. The
// nodes form independent groups (split_tree), each coded on its own. Plane b
// (from the top plane down to 0) is one packet per level and group, levels
// first (coarse levels of every group before finer ones), each one scan over
// the group's open nodes of that level in index order (the roots, and the
// children of nodes whose descendants were found significant, which lie in
// finer levels). For each open node:
//   refinement: bit b of every component significant before the plane;
//   significance: whether a not-yet-significant component reaches 2^b (one
//     decision for the node, then one per component, then the sign of each
//     new one);
//   (2.1, minor version 1: at a wavelet coefficient's first significance, a
//     flag "some tangential component is non-zero"; without it only the
//     normal component is ever coded, and with it plane 0 implies the
//     tangential bits a non-zero magnitude forces;)
//   descendants: for a node with children whose descendants were all below
//     2^(b+1), whether some descendant reaches 2^b, which opens its children
//     (set partitioning as in SPIHT, Said and Pearlman 1996, with the
//     zerotree of Shapiro's EZW).
// Contexts (adaptive, kept across planes, one set per group): coefficient
// class, the parent's and the node's own significance, the component, the
// parent's sign. A decoder stopped anywhere (a cut packet) keeps every unit it
// completed; a component's value is then the middle of the interval its known
// bits leave. Cost: O(nodes) per plane for encoder and decoder; at most 32
// planes. Index order keeps the scan's memory access sequential.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "coefficient_tree.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/vec3.h"

namespace isowave::detail {

// Largest coded magnitude, and so at most 32 planes.
constexpr std::uint32_t kMaxMagnitude = 0xFFFFFFFFu;

// Independent groups of the tree (split_tree), each with its own packets and
// contexts, so that a decoder may decode them in parallel: one group per
// kNodesPerGroup nodes, at most kMaxGroups.
constexpr std::size_t kNodesPerGroup = std::size_t{1} << 17;
constexpr std::size_t kMaxGroups = 64;
constexpr std::size_t kMaxSegments = 32;  // levels + 1
inline std::size_t plane_groups(std::size_t nodes) {
  return std::min(kMaxGroups, std::max<std::size_t>(1, (nodes + kNodesPerGroup / 2) / kNodesPerGroup));
}

// A component's value in step units when its magnitude's bits from plane
// `low` up are known (`known`, the bits below clear): 0 while none is set,
// else the middle of the interval the known bits leave. The decoder's rule,
// and the encoder's for what a prefix ending at a plane decodes to.
inline double known_value(std::uint32_t known, int low) {
  return known == 0 ? 0.0 : double(known) + (low <= 0 ? 0.5 : double(1u << (low - 1)));
}

struct PlaneSymbols {
  // Per node: 3 magnitudes (step units) and the sign bits (bit k: component k negative).
  std::vector<std::uint32_t> magnitude;
  std::vector<std::uint8_t> negative;
  // Per node: its context class in [0, classes) (the coefficient class).
  std::vector<std::uint8_t> node_class;
  int classes = 1;
};

// The top plane (bit length of the largest magnitude, minus 1; -1 when all
// are zero) and, for each plane from the top down to `lowest_plane` (>= 0),
// one packet per level and group: packet j is group j mod G of level
// (j / G) mod S of plane top - j / (G S), S = levels + 1 segments, each
// flushed by RangeEncoder::finish_trimmed(). The groups are coded in parallel.
struct PlanePackets {
  int top_plane = -1;
  std::size_t segments = 1;
  std::vector<std::string> packets;
};
// `minor_version` selects the coding: 0 as 2.0, 1 (and later) adds the
// non-normal flags of 2.1. `account`, if given, receives the estimated bits
// by what they code (components 1 and 2 tangential; a node of class 0 is a
// base control point).
PlanePackets encode_planes(const CoefficientTree& tree, const PlaneSymbols& symbols, const TreeGroups& groups,
                           int minor_version, int lowest_plane = 0, IswPlaneBits* account = nullptr);
// The same with split_tree(tree, groups), the groups of minor versions 0 and 1.
inline PlanePackets encode_planes(const CoefficientTree& tree, const PlaneSymbols& symbols, std::size_t groups,
                                  int minor_version, int lowest_plane = 0, IswPlaneBits* account = nullptr) {
  return encode_planes(tree, symbols, split_tree(tree, groups), minor_version, lowest_plane, account);
}

// The decoder's state after any prefix of the packets.
class PlaneDecoder {
 public:
  // `node_class` and `classes` as in PlaneSymbols; `minor_version` as in
  // encode_planes(); top_plane in [-1, 31]; `groups` as the encoder's. Keeps
  // no reference to its arguments.
  PlaneDecoder(const CoefficientTree& tree, const std::vector<std::uint8_t>& node_class, int classes,
               int minor_version, int top_plane, const TreeGroups& groups);
  // With split_tree(tree, groups), groups in [1, kMaxGroups].
  PlaneDecoder(const CoefficientTree& tree, const std::vector<std::uint8_t>& node_class, int classes,
               int minor_version, int top_plane, std::size_t groups)
      : PlaneDecoder(tree, node_class, classes, minor_version, top_plane, split_tree(tree, groups)) {}
  ~PlaneDecoder();

  // Decodes the packets in the encoder's order, the groups in parallel; a
  // `last_cut` last packet stops at the first decision its missing bytes
  // could change. Any bytes decode (to some values) in O(nodes x planes):
  // the section's CRC is what detects damage. With `selected` (one flag per
  // group), only those groups decode (the others' packets are not read and
  // their values stay zero). Call once.
  void decode(const std::vector<std::string_view>& packets, bool last_cut,
              const std::vector<std::uint8_t>* selected = nullptr);
  // Planes complete in every group decoded.
  int planes_done() const;

  // Per node, its three components in step units (0 where not significant),
  // into `out` (of one entry per node, every entry written).
  void values(std::vector<Vec3>& out) const;

 private:
  struct State;  // the tree in group order, magnitudes and flags
  struct Group {
    std::vector<std::uint16_t> models;
    std::vector<std::uint64_t> open;  // one bit per position of the group
    int planes_done = 0;
    bool decoded = true;
    // Where a cut stopped: the plane (-1: none), the position, and the mask
    // of that node's components refined in the plane.
    int cut_plane = -1;
    std::uint32_t cut_position = 0;
    std::uint8_t cut_refined = 0;
  };
  void decode_group(std::size_t g, const std::vector<std::string_view>& packets, bool last_cut);
  void group_values(std::size_t g, std::vector<Vec3>& out) const;

  int top_plane_;
  std::unique_ptr<State> state_;
  std::vector<Group> group_state_;
};

}  // namespace isowave::detail
