#pragma once
// Private: the embedded bit-plane coder of .isw 2.0 (docs/FORMAT.md, PLNS;
// issue #34). Every node of the coefficient tree carries three non-negative
// integer magnitudes (its components in step units) and their signs. Plane b
// (from the top plane down to 0) is one packet of adaptive binary decisions:
//   sorting pass: for each node of the active list (roots first, then nodes
//     whose parent's descendants became significant, in the order they were
//     found): whether a not-yet-significant component reaches 2^b (one
//     decision for the node, then one per component, then the sign of each
//     new one); then, for a node with children whose descendants were all
//     below 2^(b+1), whether some descendant reaches 2^b, which activates its
//     children within the same pass (set partitioning as in SPIHT, Said and
//     Pearlman 1996, with the zerotree of Shapiro's EZW);
//   refinement pass: bit b of every component significant before the plane.
// Contexts (adaptive, kept across planes): coefficient class, the parent's
// and the node's own significance, the component, the parent's sign. A
// decoder stopped anywhere (a cut packet) keeps every unit it completed; a
// component's value is then the middle of the interval its known bits leave.
// Cost: O(nodes) per plane for encoder and decoder; at most 32 planes.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "coefficient_tree.h"

namespace isowave::detail {

// Largest coded magnitude, and so at most 32 planes.
constexpr std::uint32_t kMaxMagnitude = 0xFFFFFFFFu;

struct PlaneSymbols {
  // Per node: 3 magnitudes (step units) and the sign bits (bit k: component k negative).
  std::vector<std::uint32_t> magnitude;
  std::vector<std::uint8_t> negative;
  // Per node: its context class in [0, classes) (the coefficient class).
  std::vector<std::uint8_t> node_class;
  int classes = 1;
};

// The top plane (bit length of the largest magnitude, minus 1; -1 when all
// are zero) and one packet per plane from the top down to `lowest_plane`
// (>= 0), each flushed by RangeEncoder::finish_trimmed().
struct PlanePackets {
  int top_plane = -1;
  std::vector<std::string> packets;
};
PlanePackets encode_planes(const CoefficientTree& tree, const PlaneSymbols& symbols, int lowest_plane = 0);

// The decoder's state after any number of packets, complete or cut.
class PlaneDecoder {
 public:
  // `node_class` and `classes` as in PlaneSymbols; top_plane in [-1, 31].
  PlaneDecoder(const CoefficientTree& tree, std::vector<std::uint8_t> node_class, int classes, int top_plane);

  // Decodes the next plane's packet; a `cut` packet stops at the first
  // decision its missing bytes could change. Returns false when it stopped
  // there (then no further packet may be decoded) or when every plane is
  // done. Any bytes decode (to some values) in O(nodes): the section's CRC
  // is what detects damage.
  bool decode_packet(std::string_view packet, bool cut);
  int planes_done() const { return planes_done_; }  // complete packets decoded
  bool stopped() const { return stopped_; }

  // Per node, the three components in step units (0 where not significant).
  void values(std::vector<double>& out) const;

 private:
  const CoefficientTree& tree_;
  std::vector<std::uint8_t> node_class_;
  int classes_;
  int top_plane_;
  int planes_done_ = 0;
  bool stopped_ = false;
  std::vector<std::uint32_t> magnitude_;
  std::vector<std::uint8_t> flags_;
  std::vector<std::uint32_t> active_, next_, lsp_;
  std::vector<std::uint16_t> models_;
  // Where a cut stopped: the plane, the significant components refined in
  // it, and the list length before it.
  int cut_plane_ = -1;
  std::size_t refined_ = 0, lsp_before_ = 0;
};

}  // namespace isowave::detail
