#include "bitplane_coder.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <memory>

#include <tbb/parallel_for.h>

#include "range_coder.h"

namespace isowave::detail {

namespace {

constexpr std::uint32_t kNoParent = UINT32_MAX;
constexpr std::uint8_t kSignificant = 7;      // flag bits 0-2: component k significant
constexpr std::uint8_t kDescendants = 1 << 3;  // flag bit 3: some descendant significant
constexpr int kSignShift = 4;                  // flag bits 4-6: component k negative
constexpr std::uint8_t kNonNormal = 1 << 7;    // flag bit 7 (2.1): some tangential component non-zero

// The adaptive contexts, one flat array (docs/FORMAT.md, PLNS), and whether
// the stream codes the non-normal flags (minor version 1 and later).
struct Contexts {
  Contexts(int classes, int minor_version)
      : node_end(static_cast<std::size_t>(classes) * 6), component_end(node_end + 18), sign_end(component_end + 9),
        descendant_end(sign_end + static_cast<std::size_t>(classes) * 2), refinement_end(descendant_end + 6),
        size(refinement_end + (minor_version >= 1 ? static_cast<std::size_t>(classes) * 4 : 0)),
        non_normal_flags(minor_version >= 1) {}
  // A node's significance: class, parent (0 root, 1 none significant, 2 some), own (0 none, 1 some).
  std::size_t node(int cls, int parent, int own) const { return static_cast<std::size_t>((cls * 3 + parent) * 2 + own); }
  // Component k: the parent's component k (0 root, 1 not significant, 2 significant), own.
  std::size_t component(int k, int parent, int own) const {
    return node_end + static_cast<std::size_t>((k * 3 + parent) * 2 + own);
  }
  // Sign of component k: the parent's (0 unknown, 1 positive, 2 negative).
  std::size_t sign(int k, int parent) const { return component_end + static_cast<std::size_t>(k * 3 + parent); }
  std::size_t descendants(int cls, int own) const { return sign_end + static_cast<std::size_t>(cls * 2 + own); }
  // Refinement of component k, base control point or wavelet coefficient.
  std::size_t refinement(int k, int base) const { return descendant_end + static_cast<std::size_t>(k * 2 + base); }
  // 2.1: a wavelet coefficient's non-normal flag: class, the parent's flag
  // (0 root, 1 not known yet, 2 normal, 3 non-normal).
  std::size_t non_normal(int cls, int parent) const {
    return refinement_end + static_cast<std::size_t>(cls * 4 + parent);
  }
  std::size_t node_end, component_end, sign_end, descendant_end, refinement_end, size;
  bool non_normal_flags;
};

// What a decision codes (IswPlaneBits), for the encoder's account: a base
// control point's decisions, else by component k (0 normal) and kind.
using PlaneBitCounts = std::array<double, 9>;  // by Part
enum Part : std::uint8_t { kBase, kSignificance, kSign = kSignificance + 2, kRefinement = kSign + 2, kJoint = kRefinement + 2, kTree };
constexpr int part_of(int base, int kind, int k) { return base ? kBase : kind + (k > 0); }

// Where a plane stopped: the position and the mask of its components refined.
struct PlaneCut {
  std::uint32_t position = 0;
  std::uint8_t refined = 0;
};

// The tree in group order: position p is the p-th entry of the groups'
// member lists, so each group's nodes are contiguous and ascending (parents
// before children), and a plane's scan reads every array in order.
struct GroupedTree {
  std::vector<std::uint32_t> group_offsets;  // group g: positions [group_offsets[g], group_offsets[g + 1])
  std::vector<std::uint32_t> node;           // position -> node
  std::vector<std::uint32_t> parent;         // position -> the parent's position, or kNoParent
  std::vector<std::uint32_t> child_offsets;  // children of p: children[child_offsets[p] .. child_offsets[p + 1]]
  std::vector<std::uint32_t> children;       // positions, ascending per node
  std::vector<std::uint8_t> node_class;      // position -> context class
  // The levels' positions in each group: group g's level s is
  // [segments[g * (S + 1) + s], segments[g * (S + 1) + s + 1]), S = levels + 1.
  std::size_t segment_count = 1;
  std::vector<std::uint32_t> segments;
  std::uint32_t segment_begin(std::size_t g, std::size_t s) const { return segments[g * (segment_count + 1) + s]; }
};

GroupedTree group_tree(const CoefficientTree& tree, const std::vector<std::uint8_t>& node_class, TreeGroups split) {
  const std::size_t groups = split.count();
  GroupedTree t;
  t.group_offsets = std::move(split.offsets);
  t.node = std::move(split.members);
  const std::size_t n = tree.nodes;
  std::vector<std::uint32_t> position(n);
  for (std::size_t p = 0; p < n; ++p) position[t.node[p]] = static_cast<std::uint32_t>(p);
  t.parent.resize(n);
  t.node_class.resize(n);
  t.child_offsets.assign(n + 1, 0);
  for (std::size_t p = 0; p < n; ++p) {
    const std::uint32_t i = t.node[p];
    t.parent[p] = tree.parent[i] == kNoParent ? kNoParent : position[tree.parent[i]];
    t.node_class[p] = node_class[i];
    if (t.parent[p] != kNoParent) ++t.child_offsets[t.parent[p] + 1];
  }
  // Children by a counting sort over their parents' positions (ascending).
  for (std::size_t p = 0; p < n; ++p) t.child_offsets[p + 1] += t.child_offsets[p];
  t.children.resize(t.child_offsets[n]);
  std::vector<std::uint32_t> fill(t.child_offsets.begin(), t.child_offsets.end() - 1);
  for (std::size_t p = 0; p < n; ++p)
    if (t.parent[p] != kNoParent) t.children[fill[t.parent[p]]++] = static_cast<std::uint32_t>(p);
  // Within a group positions ascend with the node index, so each level is a run.
  t.segment_count = tree.level_ends.size();
  for (std::size_t g = 0; g < groups; ++g) {
    const auto first = t.node.begin() + t.group_offsets[g], last = t.node.begin() + t.group_offsets[g + 1];
    t.segments.push_back(t.group_offsets[g]);
    for (const std::uint32_t end : tree.level_ends)
      t.segments.push_back(static_cast<std::uint32_t>(std::lower_bound(first, last, end) - t.node.begin()));
  }
  return t;
}

// A group's open nodes (the roots, and the children of nodes whose
// descendants were found significant): one bit per position of the group.
std::vector<std::uint64_t> roots_open(const GroupedTree& t, std::size_t g) {
  const std::uint32_t first = t.group_offsets[g], last = t.group_offsets[g + 1];
  std::vector<std::uint64_t> open((last - first + 63) / 64, 0);
  for (std::uint32_t p = first; p < last; ++p)
    if (t.parent[p] == kNoParent) open[(p - first) / 64] |= std::uint64_t{1} << ((p - first) % 64);
  return open;
}

// One group's coding state, in positions.
struct GroupCoder {
  const GroupedTree& t;
  const Contexts& c;
  std::vector<std::uint8_t>& flags;  // all groups' (each writes its own positions)
  std::vector<std::uint64_t>& open;  // this group's
  std::vector<Probability>& models;  // this group's
  std::uint32_t first;               // the group's first position
};

// What code_node's steps share about one open node.
struct NodeView {
  std::uint32_t i, parent;
  std::uint8_t pf;  // the parent's flags (0 for a root)
  int cls, base;    // its class; 1 for a base control point
};

// Refinement: bit b of every component significant before the plane (a
// node's flags change only on its own visit, after this).
template <class Io>
bool refine_node(Io& io, GroupCoder& s, const NodeView& v, std::uint8_t f, int b, PlaneCut& cut) {
  std::uint8_t refined = 0;
  for (int k = 0; k < 3; ++k) {
    if (!((f >> k) & 1)) continue;
    const int bit = io.bit(part_of(v.base, kRefinement, k), s.models[s.c.refinement(k, v.base)],
                           [&] { return io.reaches(v.i, k, b); });
    if (io.stopped()) {
      cut = {v.i, refined};
      return false;
    }
    io.refine(v.i, k, b, bit);
    refined = static_cast<std::uint8_t>(refined | (1 << k));
  }
  return true;
}

// The components a node may still make significant: all three, but only the
// normal for a wavelet coefficient of a 2.1 stream flagged normal.
std::uint8_t candidates(const Contexts& c, const NodeView& v, std::uint8_t f) {
  return c.non_normal_flags && !v.base && (f & kSignificant) && !(f & kNonNormal) ? 1 : kSignificant;
}

// 2.1: at a wavelet coefficient's first significance, whether it is
// non-normal (some tangential component is non-zero); context: class and
// the parent's flag (0 root, 1 unknown, 2 normal, 3 non-normal).
template <class Io>
std::uint8_t code_non_normal(Io& io, GroupCoder& s, const NodeView& v) {
  const int pn = v.parent == kNoParent ? 0 : !(v.pf & kSignificant) ? 1 : (v.pf & kNonNormal) ? 3 : 2;
  const int t = io.bit(kSignificance + 1, s.models[s.c.non_normal(v.cls, pn)], [&] { return io.non_normal(v.i); });
  return t ? kNonNormal : 0;
}

// 2.1: whether plane b must make a tangential component of a node with
// flags `f` significant: a non-normal coefficient none of whose tangential
// components is significant yet, at plane 0 (one of them is then 1).
bool tangential_due(const Contexts& c, const NodeView& v, std::uint8_t f, int b) {
  return c.non_normal_flags && !v.base && b == 0 && (f & kNonNormal) && !(f & 6);
}

// Significance of the candidate components not yet significant, and their
// signs; the node's new flags in `f`.
template <class Io>
bool code_significance(Io& io, GroupCoder& s, const NodeView& v, std::uint8_t& f, int b, PlaneCut& cut) {
  const Contexts& c = s.c;
  const std::uint8_t open = static_cast<std::uint8_t>(candidates(c, v, f) & ~f);
  if (!open) return true;
  const int pstate = v.parent == kNoParent ? 0 : ((v.pf & kSignificant) ? 2 : 1);
  const int own = (f & kSignificant) ? 1 : 0;
  const int z = own && tangential_due(c, v, f, b)
                    ? 1
                    : io.bit(v.base ? kBase : (f & 1) ? kSignificance + 1 : kJoint,
                             s.models[c.node(v.cls, pstate, own)], [&] { return io.any_reaches(v.i, f, b); });
  if (io.stopped()) {
    cut = {v.i, kSignificant};
    return false;
  }
  if (!z) return true;
  std::uint8_t nf = f;
  if (c.non_normal_flags && !v.base && !own) nf = static_cast<std::uint8_t>(nf | code_non_normal(io, s, v));
  const std::uint8_t todo = static_cast<std::uint8_t>(candidates(c, v, static_cast<std::uint8_t>(nf | 1)) & ~f);
  const bool due = tangential_due(c, v, nf, b);
  int insignificant = __builtin_popcount(todo), seen_one = 0;
  for (int k = 0; k < 3; ++k) {
    if (!((todo >> k) & 1)) continue;
    --insignificant;
    const int pk = v.parent == kNoParent ? 0 : (((v.pf >> k) & 1) ? 2 : 1);
    const int bit = (insignificant == 0 && !seen_one) || (k == 2 && due && !(nf & 2))
                        ? 1
                        : io.bit(part_of(v.base, kSignificance, k), s.models[c.component(k, pk, own)],
                                 [&] { return io.reaches(v.i, k, b); });
    if (!bit) continue;
    seen_one = 1;
    const int ps = pk == 2 ? 1 + ((v.pf >> (kSignShift + k)) & 1) : 0;
    const int negative =
        io.bit(part_of(v.base, kSign, k), s.models[c.sign(k, ps)], [&] { return io.negative_bit(v.i, k); });
    nf = static_cast<std::uint8_t>(nf | (1 << k) | (negative << (kSignShift + k)));
  }
  if (io.stopped()) {
    cut = {v.i, kSignificant};
    return false;
  }
  for (int k = 0; k < 3; ++k)
    if (((nf & ~f) >> k) & 1) io.set_significant(v.i, k, b);
  s.flags[v.i] = f = nf;
  return true;
}

// Whether some descendant reaches 2^b, which opens the children.
template <class Io>
bool code_descendants(Io& io, GroupCoder& s, const NodeView& v, std::uint8_t f, int b, PlaneCut& cut) {
  const std::uint32_t first = s.t.child_offsets[v.i], last = s.t.child_offsets[v.i + 1];
  if (first == last || (f & kDescendants)) return true;
  const int own = (f & kSignificant) ? 1 : 0;
  const int d =
      io.bit(kTree, s.models[s.c.descendants(v.cls, own)], [&] { return io.descendants_reach(v.i, b); });
  if (io.stopped()) {
    cut = {v.i, kSignificant};
    return false;
  }
  if (d) {
    s.flags[v.i] = static_cast<std::uint8_t>(f | kDescendants);
    for (std::uint32_t k = first; k < last; ++k) {
      const std::uint32_t q = s.t.children[k] - s.first;
      s.open[q / 64] |= std::uint64_t{1} << (q % 64);
    }
  }
  return true;
}

// One open node of plane b: refinement, significance, descendants. Returns
// false when the decoder stopped; `cut` then says where.
template <class Io>
bool code_node(Io& io, GroupCoder& s, std::uint32_t i, int b, PlaneCut& cut) {
  const std::uint32_t parent = s.t.parent[i];
  const int cls = s.t.node_class[i];
  const NodeView v{i, parent, parent == kNoParent ? std::uint8_t{0} : s.flags[parent], cls,
                   parent == kNoParent && cls == 0};
  std::uint8_t f = s.flags[i];
  return refine_node(io, s, v, f, b, cut) && code_significance(io, s, v, f, b, cut) &&
         code_descendants(io, s, v, f, b, cut);
}

// One level of one plane of a group (positions [begin, end)), shared by
// encoder and decoder: `Io` supplies every decision (the encoder from the
// magnitudes, the decoder from the stream) and learns the decoded bits. A
// scan over the open bits in position order; children lie in later levels.
// Returns false when the decoder stopped; `cut` then says where.
template <class Io>
bool code_segment(Io& io, GroupCoder& s, int b, std::uint32_t begin, std::uint32_t end, PlaneCut& cut) {
  const std::uint32_t q0 = begin - s.first, q1 = end - s.first;
  for (std::size_t w = q0 / 64; w * 64 < q1; ++w) {
    const std::uint64_t low = w == q0 / 64 ? ~std::uint64_t{0} << (q0 % 64) : ~std::uint64_t{0};
    const std::uint64_t window = (w + 1) * 64 <= q1 ? low : low & ((std::uint64_t{1} << (q1 % 64)) - 1);
    std::uint64_t bits = s.open[w] & window;
    while (bits != 0) {
      const int bit = __builtin_ctzll(bits);
      if (!code_node(io, s, s.first + static_cast<std::uint32_t>(w * 64 + static_cast<std::size_t>(bit)), b, cut))
        return false;
      bits = bit == 63 ? 0 : s.open[w] & window & (~std::uint64_t{0} << (bit + 1));
    }
  }
  return true;
}

// -log2 of the probability a model gives bit 0 (index p) and bit 1 (index p + 2^11).
const std::array<double, 2 << kProbabilityBits>& bit_costs() {
  static const std::array<double, 2 << kProbabilityBits> costs = [] {
    std::array<double, 2 << kProbabilityBits> c{};
    constexpr double one = 1 << kProbabilityBits;
    for (std::size_t p = 1; p < (1 << kProbabilityBits); ++p) {
      c[p] = -std::log2(double(p) / one);
      c[p + (1 << kProbabilityBits)] = -std::log2(1 - double(p) / one);
    }
    return c;
  }();
  return costs;
}

// The encoder's side: decisions from the magnitudes (in positions).
struct EncoderIo {
  RangeEncoder& rc;
  const std::vector<std::uint32_t>& magnitude;       // 3 per position
  const std::vector<std::uint8_t>& negative;         // per position
  const std::vector<std::uint32_t>& descendant_max;  // per position
  PlaneBitCounts* account;                           // nullptr: none
  template <class Value>
  int bit(int part, Probability& p, Value value) {
    const int v = value();
    if (account) (*account)[static_cast<std::size_t>(part)] += bit_costs()[p + (static_cast<std::size_t>(v) << kProbabilityBits)];
    rc.encode_bit(p, v);
    return v;
  }
  std::uint32_t m(std::uint32_t i, int k) const { return magnitude[3 * std::size_t{i} + static_cast<std::size_t>(k)]; }
  int reaches(std::uint32_t i, int k, int b) const { return static_cast<int>((m(i, k) >> b) & 1u); }
  int any_reaches(std::uint32_t i, std::uint8_t f, int b) const {
    for (int k = 0; k < 3; ++k)
      if (!((f >> k) & 1) && reaches(i, k, b)) return 1;
    return 0;
  }
  int negative_bit(std::uint32_t i, int k) const { return (negative[i] >> k) & 1; }
  int non_normal(std::uint32_t i) const { return (m(i, 1) | m(i, 2)) != 0 ? 1 : 0; }
  int descendants_reach(std::uint32_t i, int b) const { return (descendant_max[i] >> b) != 0 ? 1 : 0; }
  bool stopped() const { return false; }
  void set_significant(std::uint32_t, int, int) {}
  void refine(std::uint32_t, int, int, int) {}
};

// The decoder's side: decisions from the stream, magnitudes (in positions) built from them.
template <class Decoder>
struct DecoderIo {
  Decoder& rc;
  std::vector<std::uint32_t>& magnitude;
  template <class Value>
  int bit(int, Probability& p, Value) {
    return rc.decode_bit(p);
  }
  int reaches(std::uint32_t, int, int) const { return 0; }
  int any_reaches(std::uint32_t, std::uint8_t, int) const { return 0; }
  int negative_bit(std::uint32_t, int) const { return 0; }
  int non_normal(std::uint32_t) const { return 0; }
  int descendants_reach(std::uint32_t, int) const { return 0; }
  bool stopped() const { return rc.stopped(); }
  void set_significant(std::uint32_t i, int k, int b) { magnitude[3 * std::size_t{i} + static_cast<std::size_t>(k)] = 1u << b; }
  void refine(std::uint32_t i, int k, int b, int bit) {
    magnitude[3 * std::size_t{i} + static_cast<std::size_t>(k)] |= static_cast<std::uint32_t>(bit) << b;
  }
};

// The symbols in positions, and per position the largest magnitude among its
// descendants (a reverse scan: children lie after their parents).
struct PositionSymbols {
  std::vector<std::uint32_t> magnitude;
  std::vector<std::uint8_t> negative;
  std::vector<std::uint32_t> descendant_max;
};
PositionSymbols position_symbols(const GroupedTree& t, const PlaneSymbols& symbols) {
  const std::size_t n = t.node.size();
  PositionSymbols s{std::vector<std::uint32_t>(3 * n), std::vector<std::uint8_t>(n), std::vector<std::uint32_t>(n, 0)};
  for (std::size_t p = 0; p < n; ++p) {
    const std::size_t i = t.node[p];
    for (std::size_t k = 0; k < 3; ++k) s.magnitude[3 * p + k] = symbols.magnitude[3 * i + k];
    s.negative[p] = symbols.negative[i];
  }
  for (std::size_t p = n; p-- > 0;) {
    if (t.parent[p] == kNoParent) continue;
    const std::uint32_t m = std::max({s.magnitude[3 * p], s.magnitude[3 * p + 1], s.magnitude[3 * p + 2], s.descendant_max[p]});
    std::uint32_t& above = s.descendant_max[t.parent[p]];
    above = std::max(above, m);
  }
  return s;
}

// The groups' counts summed in group order (deterministic), by part.
IswPlaneBits plane_bits_of(const std::vector<PlaneBitCounts>& counts) {
  PlaneBitCounts sum{};
  for (const PlaneBitCounts& c : counts)
    for (std::size_t k = 0; k < sum.size(); ++k) sum[k] += c[k];
  IswPlaneBits bits;
  bits.base = sum[kBase];
  bits.normal_significance = sum[kSignificance];
  bits.tangential_significance = sum[kSignificance + 1];
  bits.normal_sign = sum[kSign];
  bits.tangential_sign = sum[kSign + 1];
  bits.normal_refinement = sum[kRefinement];
  bits.tangential_refinement = sum[kRefinement + 1];
  bits.joint_significance = sum[kJoint];
  bits.descendants = sum[kTree];
  return bits;
}

}  // namespace

PlanePackets encode_planes(const CoefficientTree& tree, const PlaneSymbols& symbols, const TreeGroups& split,
                           int minor_version, int lowest_plane, IswPlaneBits* account) {
  const std::size_t groups = split.count();
  assert(symbols.magnitude.size() == 3 * tree.nodes && symbols.negative.size() == tree.nodes);
  PlanePackets result;
  const std::uint32_t largest =
      symbols.magnitude.empty() ? 0 : *std::max_element(symbols.magnitude.begin(), symbols.magnitude.end());
  result.top_plane = bit_length(largest) - 1;
  const int planes = std::max(0, result.top_plane + 1 - std::max(lowest_plane, 0));
  const Contexts c(symbols.classes, minor_version);
  const GroupedTree t = group_tree(tree, symbols.node_class, split);
  const std::size_t segments = t.segment_count;
  result.segments = segments;
  result.packets.resize(static_cast<std::size_t>(planes) * segments * groups);
  const PositionSymbols s = position_symbols(t, symbols);
  std::vector<std::uint8_t> flags(tree.nodes, 0);
  std::vector<PlaneBitCounts> counts(account ? groups : 0, PlaneBitCounts{});
  tbb::parallel_for(std::size_t{0}, groups, [&](std::size_t g) {
    std::vector<Probability> models(c.size, kProbabilityHalf);
    std::vector<std::uint64_t> open = roots_open(t, g);
    GroupCoder coder{t, c, flags, open, models, t.group_offsets[g]};
    for (std::size_t k = 0; k < static_cast<std::size_t>(planes) * segments; ++k) {
      const std::size_t level = k % segments;
      std::string& packet = result.packets[k * groups + g];
      RangeEncoder rc(packet);
      EncoderIo io{rc, s.magnitude, s.negative, s.descendant_max, account ? &counts[g] : nullptr};
      PlaneCut cut;
      code_segment(io, coder, result.top_plane - static_cast<int>(k / segments), t.segment_begin(g, level),
                   t.segment_begin(g, level + 1), cut);
      rc.finish_trimmed(0);
    }
  });
  if (account) *account = plane_bits_of(counts);
  return result;
}

struct PlaneDecoder::State {
  GroupedTree tree;
  Contexts contexts;
  std::vector<std::uint32_t> magnitude;  // 3 per position
  std::vector<std::uint8_t> flags;       // per position
};

PlaneDecoder::PlaneDecoder(const CoefficientTree& tree, const std::vector<std::uint8_t>& node_class, int classes,
                           int minor_version, int top_plane, const TreeGroups& groups)
    : top_plane_(top_plane),
      state_(std::make_unique<State>(State{group_tree(tree, node_class, groups), Contexts(classes, minor_version),
                                           std::vector<std::uint32_t>(3 * tree.nodes, 0),
                                           std::vector<std::uint8_t>(tree.nodes, 0)})),
      group_state_(groups.count()) {
  for (std::size_t g = 0; g < group_state_.size(); ++g) {
    group_state_[g].models.assign(state_->contexts.size, kProbabilityHalf);
    group_state_[g].open = roots_open(state_->tree, g);
  }
}

PlaneDecoder::~PlaneDecoder() = default;

void PlaneDecoder::decode(const std::vector<std::string_view>& packets, bool last_cut,
                          const std::vector<std::uint8_t>* selected) {
  assert(!selected || selected->size() == group_state_.size());
  tbb::parallel_for(std::size_t{0}, group_state_.size(), [&](std::size_t g) {
    if (selected && !(*selected)[g]) {
      group_state_[g].decoded = false;
      return;
    }
    decode_group(g, packets, last_cut);
  });
}

void PlaneDecoder::decode_group(std::size_t g, const std::vector<std::string_view>& packets, bool last_cut) {
  Group& group = group_state_[g];
  State& state = *state_;
  GroupCoder coder{state.tree, state.contexts, state.flags, group.open, group.models, state.tree.group_offsets[g]};
  const std::size_t groups = group_state_.size(), segments = state.tree.segment_count;
  for (std::size_t k = 0;; ++k) {
    const int b = top_plane_ - static_cast<int>(k / segments);
    const std::size_t level = k % segments, j = k * groups + g;
    if (b < 0) return;
    if (j >= packets.size()) {
      // The stream ends before this level's packet: the plane stops at its start.
      if (level > 0) {
        group.cut_plane = b;
        group.cut_position = state.tree.segment_begin(g, level);
      }
      return;
    }
    const auto* data = reinterpret_cast<const std::uint8_t*>(packets[j].data());
    const std::uint32_t begin = state.tree.segment_begin(g, level), end = state.tree.segment_begin(g, level + 1);
    PlaneCut where;
    bool done;
    if (last_cut && j + 1 == packets.size()) {
      PrefixRangeDecoder<PacketEnding::Cut> rc(data, packets[j].size());
      DecoderIo<decltype(rc)> io{rc, state.magnitude};
      done = code_segment(io, coder, b, begin, end, where);
    } else {
      PrefixRangeDecoder<PacketEnding::Complete> rc(data, packets[j].size());
      DecoderIo<decltype(rc)> io{rc, state.magnitude};
      done = code_segment(io, coder, b, begin, end, where);
    }
    if (!done) {
      group.cut_plane = b;
      group.cut_position = where.position;
      group.cut_refined = where.refined;
      return;
    }
    if (level + 1 == segments) ++group.planes_done;
  }
}

int PlaneDecoder::planes_done() const {
  int done = top_plane_ + 1;
  for (const Group& g : group_state_)
    if (g.decoded) done = std::min(done, g.planes_done);
  return done;
}

void PlaneDecoder::values(std::vector<Vec3>& out) const {
  assert(out.size() == state_->tree.node.size());
  tbb::parallel_for(std::size_t{0}, group_state_.size(), [&](std::size_t g) { group_values(g, out); });
}

void PlaneDecoder::group_values(std::size_t g, std::vector<Vec3>& out) const {
  // The lowest plane known of each significant component: the group's last
  // complete plane, or, after a cut, the cut plane for the components it
  // reached (those it made significant, and those it refined: at positions
  // before the cut's, and the cut node's refined ones).
  const Group& group = group_state_[g];
  const State& state = *state_;
  const int complete_low = top_plane_ - group.planes_done + 1;
  const int cut = group.cut_plane;
  for (std::uint32_t p = state.tree.group_offsets[g]; p < state.tree.group_offsets[g + 1]; ++p) {
    const std::uint8_t f = state.flags[p];
    Vec3& value = out[state.tree.node[p]];
    value = Vec3{};
    for (int k = 0; k < 3; ++k) {
      if (!((f >> k) & 1)) continue;
      const std::uint32_t m = state.magnitude[3 * std::size_t{p} + static_cast<std::size_t>(k)];
      int low = complete_low;
      if (cut >= 0 &&
          (m == 1u << cut || p < group.cut_position || (p == group.cut_position && ((group.cut_refined >> k) & 1))))
        low = cut;
      const double v = known_value(m, low);
      value[k] = (f >> (kSignShift + k)) & 1 ? -v : v;
    }
  }
}

}  // namespace isowave::detail
