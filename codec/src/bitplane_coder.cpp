#include "bitplane_coder.h"

#include <algorithm>
#include <cassert>

#include "range_coder.h"

namespace isowave::detail {

namespace {

constexpr std::uint32_t kNoParent = UINT32_MAX;
constexpr std::uint8_t kSignificant = 7;      // flag bits 0-2: component k significant
constexpr std::uint8_t kDescendants = 1 << 3;  // flag bit 3: some descendant significant
constexpr int kSignShift = 4;                  // flag bits 4-6: component k negative

// The adaptive contexts, one flat array (docs/FORMAT.md, PLNS).
struct Contexts {
  explicit Contexts(int classes)
      : node_end(static_cast<std::size_t>(classes) * 6), component_end(node_end + 18), sign_end(component_end + 9),
        descendant_end(sign_end + static_cast<std::size_t>(classes) * 2), size(descendant_end + 6) {}
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
  std::size_t node_end, component_end, sign_end, descendant_end, size;
};

struct PassState {
  std::vector<std::uint8_t>& flags;
  std::vector<std::uint32_t>& active;
  std::vector<std::uint32_t>& next;
  std::vector<std::uint32_t>& lsp;
  std::vector<Probability>& models;
};

// One plane, shared by encoder and decoder: `Io` supplies every decision
// (the encoder from the magnitudes, the decoder from the stream) and learns
// the decoded bits. Returns false when the decoder stopped; `refined`
// receives the refinement entries done.
template <class Io>
bool code_plane(Io& io, const CoefficientTree& tree, const std::vector<std::uint8_t>& node_class, const Contexts& c,
                PassState s, int b, std::size_t& refined) {
  const std::size_t lsp_before = s.lsp.size();
  s.next.clear();
  for (std::size_t idx = 0; idx < s.active.size(); ++idx) {
    const std::uint32_t i = s.active[idx];
    const std::uint32_t parent = tree.parent[i];
    const std::uint8_t pf = parent == kNoParent ? 0 : s.flags[parent];
    const int pstate = parent == kNoParent ? 0 : ((pf & kSignificant) ? 2 : 1);
    const int cls = node_class[i];
    std::uint8_t f = s.flags[i];
    const int own = (f & kSignificant) ? 1 : 0;
    if ((f & kSignificant) != kSignificant) {
      const int z = io.bit(s.models[c.node(cls, pstate, own)], [&] { return io.any_reaches(i, f, b); });
      if (z) {
        std::uint8_t nf = f;
        int insignificant = 0;
        for (int k = 0; k < 3; ++k) insignificant += (f >> k) & 1 ? 0 : 1;
        int seen_one = 0;
        for (int k = 0; k < 3; ++k) {
          if ((f >> k) & 1) continue;
          --insignificant;
          const int pk = parent == kNoParent ? 0 : (((pf >> k) & 1) ? 2 : 1);
          const int bit = insignificant == 0 && !seen_one
                              ? 1
                              : io.bit(s.models[c.component(k, pk, own)], [&] { return io.reaches(i, k, b); });
          if (!bit) continue;
          seen_one = 1;
          const int ps = pk == 2 ? 1 + ((pf >> (kSignShift + k)) & 1) : 0;
          const int negative = io.bit(s.models[c.sign(k, ps)], [&] { return io.negative(i, k); });
          nf = static_cast<std::uint8_t>(nf | (1 << k) | (negative << (kSignShift + k)));
        }
        if (io.stopped()) return false;
        for (int k = 0; k < 3; ++k)
          if (((nf & ~f) >> k) & 1) {
            io.set_significant(i, k, b);
            s.lsp.push_back(i * 4 + static_cast<std::uint32_t>(k));
          }
        s.flags[i] = f = nf;
      } else if (io.stopped()) {
        return false;
      }
    }
    const std::uint32_t first = tree.child_begin(i), last = tree.child_end(i);
    if (first != last && !(f & kDescendants)) {
      const int own_now = (f & kSignificant) ? 1 : 0;
      const int d = io.bit(s.models[c.descendants(cls, own_now)], [&] { return io.descendants_reach(i, b); });
      if (io.stopped()) return false;
      if (d) {
        s.flags[i] = f = static_cast<std::uint8_t>(f | kDescendants);
        s.active.insert(s.active.end(), tree.children.begin() + first, tree.children.begin() + last);
      }
    }
    if ((f & kSignificant) != kSignificant || (first != last && !(f & kDescendants))) s.next.push_back(i);
  }
  std::swap(s.active, s.next);
  for (refined = 0; refined < lsp_before; ++refined) {
    const std::uint32_t e = s.lsp[refined];
    const std::uint32_t i = e >> 2;
    const int k = static_cast<int>(e & 3);
    const int bit = io.bit(s.models[c.refinement(k, tree.parent[i] == kNoParent && node_class[i] == 0)],
                           [&] { return io.reaches(i, k, b); });
    if (io.stopped()) return false;
    io.refine(i, k, b, bit);
  }
  return true;
}

// The encoder's side: decisions from the magnitudes.
struct EncoderIo {
  RangeEncoder& rc;
  const PlaneSymbols& symbols;
  const std::vector<std::uint32_t>& descendant_max;  // per node with children
  template <class Value>
  int bit(Probability& p, Value value) {
    const int v = value();
    rc.encode_bit(p, v);
    return v;
  }
  std::uint32_t m(std::uint32_t i, int k) const { return symbols.magnitude[3 * std::size_t{i} + static_cast<std::size_t>(k)]; }
  int reaches(std::uint32_t i, int k, int b) const { return static_cast<int>((m(i, k) >> b) & 1u); }
  int any_reaches(std::uint32_t i, std::uint8_t f, int b) const {
    for (int k = 0; k < 3; ++k)
      if (!((f >> k) & 1) && reaches(i, k, b)) return 1;
    return 0;
  }
  int negative(std::uint32_t i, int k) const { return (symbols.negative[i] >> k) & 1; }
  int descendants_reach(std::uint32_t i, int b) const { return (descendant_max[i] >> b) != 0 ? 1 : 0; }
  bool stopped() const { return false; }
  void set_significant(std::uint32_t, int, int) {}
  void refine(std::uint32_t, int, int, int) {}
};

// The decoder's side: decisions from the stream, magnitudes built from them.
struct DecoderIo {
  PrefixRangeDecoder& rc;
  std::vector<std::uint32_t>& magnitude;
  template <class Value>
  int bit(Probability& p, Value) {
    return rc.decode_bit(p);
  }
  int reaches(std::uint32_t, int, int) const { return 0; }
  int any_reaches(std::uint32_t, std::uint8_t, int) const { return 0; }
  int negative(std::uint32_t, int) const { return 0; }
  int descendants_reach(std::uint32_t, int) const { return 0; }
  bool stopped() const { return rc.stopped(); }
  void set_significant(std::uint32_t i, int k, int b) { magnitude[3 * std::size_t{i} + static_cast<std::size_t>(k)] = 1u << b; }
  void refine(std::uint32_t i, int k, int b, int bit) {
    magnitude[3 * std::size_t{i} + static_cast<std::size_t>(k)] |= static_cast<std::uint32_t>(bit) << b;
  }
};

// Per node with children: the largest magnitude among its descendants.
std::vector<std::uint32_t> descendant_maxima(const CoefficientTree& tree, const PlaneSymbols& symbols) {
  const std::size_t parents = tree.child_offsets.empty() ? 0 : tree.child_offsets.size() - 1;
  std::vector<std::uint32_t> below(parents, 0);
  for (std::size_t i = tree.nodes; i-- > tree.roots_end;) {
    std::uint32_t m = std::max({symbols.magnitude[3 * i], symbols.magnitude[3 * i + 1], symbols.magnitude[3 * i + 2]});
    if (i < parents) m = std::max(m, below[i]);
    std::uint32_t& p = below[tree.parent[i]];
    p = std::max(p, m);
  }
  return below;
}

std::vector<std::uint32_t> roots(const CoefficientTree& tree) {
  std::vector<std::uint32_t> list(tree.roots_end);
  for (std::size_t i = 0; i < list.size(); ++i) list[i] = static_cast<std::uint32_t>(i);
  return list;
}

}  // namespace

PlanePackets encode_planes(const CoefficientTree& tree, const PlaneSymbols& symbols, int lowest_plane) {
  assert(symbols.magnitude.size() == 3 * tree.nodes && symbols.negative.size() == tree.nodes);
  PlanePackets result;
  const std::uint32_t largest =
      symbols.magnitude.empty() ? 0 : *std::max_element(symbols.magnitude.begin(), symbols.magnitude.end());
  result.top_plane = bit_length(largest) - 1;
  const Contexts c(symbols.classes);
  std::vector<Probability> models(c.size, kProbabilityHalf);
  std::vector<std::uint8_t> flags(tree.nodes, 0);
  std::vector<std::uint32_t> active = roots(tree), next, lsp;
  const std::vector<std::uint32_t> descendant_max = descendant_maxima(tree, symbols);
  for (int b = result.top_plane; b >= std::max(lowest_plane, 0); --b) {
    std::string packet;
    RangeEncoder rc(packet);
    EncoderIo io{rc, symbols, descendant_max};
    std::size_t refined = 0;
    code_plane(io, tree, symbols.node_class, c, PassState{flags, active, next, lsp, models}, b, refined);
    rc.finish_trimmed(0);
    result.packets.push_back(std::move(packet));
  }
  return result;
}

PlaneDecoder::PlaneDecoder(const CoefficientTree& tree, std::vector<std::uint8_t> node_class, int classes, int top_plane)
    : tree_(tree), node_class_(std::move(node_class)), classes_(classes), top_plane_(top_plane),
      magnitude_(3 * tree.nodes, 0), flags_(tree.nodes, 0), active_(roots(tree)),
      models_(Contexts(classes).size, kProbabilityHalf) {}

bool PlaneDecoder::decode_packet(std::string_view packet, bool cut) {
  const int b = top_plane_ - planes_done_;
  if (stopped_ || b < 0) return false;
  PrefixRangeDecoder rc(reinterpret_cast<const std::uint8_t*>(packet.data()), packet.size(),
                        cut ? PrefixRangeDecoder::Ending::Cut : PrefixRangeDecoder::Ending::Complete);
  DecoderIo io{rc, magnitude_};
  lsp_before_ = lsp_.size();
  std::size_t refined = 0;
  const bool done = code_plane(io, tree_, node_class_, Contexts(classes_), PassState{flags_, active_, next_, lsp_, models_}, b, refined);
  if (!done) {
    stopped_ = true;
    cut_plane_ = b;
    refined_ = refined;
    return false;
  }
  ++planes_done_;
  return b > 0;
}

void PlaneDecoder::values(std::vector<double>& out) const {
  out.assign(3 * tree_.nodes, 0.0);
  // The lowest plane known of each significant component: the last complete
  // plane, or, after a cut, the cut plane for what it reached.
  const int complete_low = top_plane_ - planes_done_ + 1;
  const auto half = [](int low) { return low <= 0 ? 0.5 : double(1u << (low - 1)); };
  for (std::size_t j = 0; j < lsp_.size(); ++j) {
    const std::uint32_t e = lsp_[j];
    const std::size_t i = e >> 2, k = e & 3;
    int low = complete_low;
    if (stopped_ && (j < refined_ || j >= lsp_before_)) low = cut_plane_;
    const double v = magnitude_[3 * i + k] + half(low);
    out[3 * i + k] = (flags_[i] >> (kSignShift + k)) & 1 ? -v : v;
  }
}

}  // namespace isowave::detail
