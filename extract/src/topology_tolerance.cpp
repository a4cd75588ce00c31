// Topology tolerance: specks and bubbles by the extent of their samples'
// components, handles and tunnels by weakest-link cuts of one-sample necks,
// both in the contour's own sample connectivity (topology_tolerance.h).
#include "isowave/extract/topology_tolerance.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

#include "isowave/core/error.h"
#include "contour_rules.h"

namespace isowave {
namespace {

constexpr double kPi = 3.14159265358979323846;

enum Side : std::uint8_t { kOutside = 0, kInside = 1 };
Side other(Side s) { return s == kInside ? kOutside : kInside; }

Side side_of(float value, double iso) { return contour_rules::is_inside(value, iso) ? kInside : kOutside; }

// On an ambiguous face (corners in cyclic order, corner 0 on side s0, values
// minus iso f0..f3), the diagonal the contour gives side s: 0 for corners
// (0, 2), 1 for (1, 3), -1 when the other side has the face.
int diagonal_of(Side s, Side s0, double f0, double f1, double f2, double f3) {
  if (contour_rules::inside_corners_joined(f0, f1, f2, f3, s0 == kInside) != (s == kInside)) return -1;
  return s0 == s ? 0 : 1;
}

// The float nearest 2 iso - v on the other side of iso (at least one float step across).
float mirrored_value(float value, double iso, Side from) {
  const double v = value;
  const double limit = std::numeric_limits<float>::max();
  float f = std::isfinite(v) ? static_cast<float>(std::clamp(2 * iso - v, -limit, limit)) : static_cast<float>(iso);
  const float infinity = std::numeric_limits<float>::infinity();
  const float toward = from == kInside ? -infinity : infinity;
  while (side_of(f, iso) == from) f = std::nextafter(f, toward);
  return f;
}

// ---------------------------------------------------------------------------
// The 3 x 3 x 3 samples around a sample: node (dx+1) + 3 (dy+1) + 9 (dz+1),
// the centre is node 13; a set of nodes is a 27-bit mask. The block's grid
// edges and its 36 unit faces hold the whole contour connectivity among them.
constexpr int kCentre = 13;
constexpr std::uint32_t kCentreBit = 1u << kCentre;
constexpr std::uint32_t kAllNodes = (1u << 27) - 1;

struct BlockTables {
  std::array<std::array<int, 4>, 36> faces{};  // corners in cyclic order
  std::array<std::uint32_t, 3> low{}, high{};  // the nodes at coordinate 0 resp. 2 along each axis
  BlockTables() {
    const int stride[3] = {1, 3, 9};
    int f = 0;
    for (int n = 0; n < 27; ++n) {
      const int c[3] = {n % 3, (n / 3) % 3, n / 9};
      for (int a = 0; a < 3; ++a) {
        if (c[a] == 0) low[a] |= 1u << n;
        if (c[a] == 2) high[a] |= 1u << n;
        if (c[a] == 2) continue;
        for (int b = a + 1; b < 3; ++b)
          if (c[b] < 2) faces[f++] = {n, n + stride[a], n + stride[a] + stride[b], n + stride[b]};
      }
    }
  }
};

const BlockTables& block_tables() {
  static const BlockTables tables;
  return tables;
}

struct Block {
  std::array<double, 27> f;  // value - iso (NaN stays NaN, as in the decider)
  std::uint32_t inside = 0;  // the inside nodes
  std::uint32_t nodes(Side s) const { return s == kInside ? inside : ~inside & kAllNodes; }
};

// The nodes joined by a grid edge to a node of r.
std::uint32_t grid_neighbours(std::uint32_t r) {
  const BlockTables& t = block_tables();
  return ((r & ~t.high[0]) << 1) | ((r & ~t.low[0]) >> 1) | ((r & ~t.high[1]) << 3) | ((r & ~t.low[1]) >> 3) |
         ((r & ~t.high[2]) << 9) | ((r & ~t.low[2]) >> 9);
}

// The face diagonals the contour gives side s: on each ambiguous face, the
// pair the asymptotic decider connects (contour.cpp's rule and products).
struct Diagonals {
  int count = 0;
  std::array<std::array<int, 2>, 36> pair;
};

Diagonals diagonals(const Block& block, Side s) {
  Diagonals d;
  for (const auto& c : block_tables().faces) {
    const std::uint32_t b0 = (block.inside >> c[0]) & 1, b1 = (block.inside >> c[1]) & 1;
    if (b0 == b1 || b0 != ((block.inside >> c[2]) & 1) || b1 != ((block.inside >> c[3]) & 1)) continue;
    const Side s0 = b0 ? kInside : kOutside;
    const int pair = diagonal_of(s, s0, block.f[c[0]], block.f[c[1]], block.f[c[2]], block.f[c[3]]);
    if (pair >= 0) d.pair[d.count++] = {c[pair], c[pair + 2]};
  }
  return d;
}

// The nodes of `allowed` reachable from `seed` through it.
std::uint32_t grow(std::uint32_t seed, std::uint32_t allowed, const Diagonals& d) {
  std::uint32_t reached = seed & allowed;
  for (;;) {
    std::uint32_t next = reached | (grid_neighbours(reached) & allowed);
    for (int k = 0; k < d.count; ++k) {
      const std::uint32_t a = 1u << d.pair[k][0], b = 1u << d.pair[k][1];
      if ((next & a) && (allowed & b)) next |= b;
      if ((next & b) && (allowed & a)) next |= a;
    }
    if (next == reached) return reached;
    reached = next;
  }
}

// The nodes the centre is linked to when it has side s.
std::uint32_t centre_links(const Block& block, Side s, const Diagonals& d) {
  std::uint32_t links = grid_neighbours(kCentreBit) & block.nodes(s);
  for (int k = 0; k < d.count; ++k) {
    if (d.pair[k][0] == kCentre) links |= 1u << d.pair[k][1];
    if (d.pair[k][1] == kCentre) links |= 1u << d.pair[k][0];
  }
  return links;
}

// The pieces of side s around the centre: the components of the block's
// s-nodes other than the centre that hold a node of `neighbours`; one node
// of each.
struct Pieces {
  int count = 0;
  std::array<int, 26> node{};
};

Pieces pieces_around_centre(const Block& block, Side s, const Diagonals& d, std::uint32_t neighbours) {
  const std::uint32_t allowed = block.nodes(s) & ~kCentreBit;
  Pieces pieces;
  for (std::uint32_t seeds = neighbours & allowed; seeds != 0;) {
    const int n = __builtin_ctz(seeds);
    seeds &= ~grow(1u << n, allowed, d);
    pieces.node[pieces.count++] = n;
  }
  return pieces;
}

// ---------------------------------------------------------------------------

struct Neck {
  std::uint32_t sample;
  float depth;     // mean distance from the sample to its crossings, cells
  float original;  // the sample's value before the cut
};

class Cleaner {
 public:
  Cleaner(Volume& field, double iso, double cells)
      : field_(field), iso_(iso), cells_(cells), nx_(field.dims[0]), ny_(field.dims[1]), nz_(field.dims[2]),
        plane_(nx_ * ny_), n_(plane_ * nz_) {}

  // Per side: thin necks cut by weakest link, then specks (bubbles) removed.
  TopologyCleanup run() {
    result_ = {};
    sides_.resize(n_);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t p = range.begin(); p != range.end(); ++p) sides_[p] = side_of(field_.values[p], iso_);
    });
    parent_.resize(n_);
    mark_.assign(n_, 0);
    // One scan finds both sides' necks; the outside's are tested again after
    // the inside's changes, with the samples those changes touched.
    std::array<std::vector<Neck>, 2> found = scan_thin_necks();
    std::vector<std::uint32_t> changed;
    for (const Side s : {kInside, kOutside}) {
      std::vector<Neck> candidates = s == kInside
                                         ? std::move(found[kInside])
                                         : find_thin_necks(s, neighbourhoods(changed, samples_of(found[kOutside])));
      const std::size_t cut = cut_weakest_links(s, spaced_apart(std::move(candidates)), changed);
      const std::size_t small = remove_small(s, changed);
      (s == kInside ? result_.handles_cut : result_.tunnels_filled) = cut;
      (s == kInside ? result_.specks_removed : result_.bubbles_filled) = small;
    }
    result_.samples_changed = original_.size();
    return result_;
  }

 private:
  // --- samples and the union-find -----------------------------------------

  // A sample changed before goes back to its value exactly.
  void flip(std::uint32_t p) {
    const auto [entry, first] = original_.try_emplace(p, field_.values[p]);
    if (first) {
      field_.values[p] = mirrored_value(field_.values[p], iso_, sides_[p]);
    } else {
      field_.values[p] = entry->second;
      original_.erase(entry);
    }
    sides_[p] = other(sides_[p]);
  }

  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  std::uint32_t root_of(std::size_t x) const {  // find() without compression, for parallel readers
    while (parent_[x] != x) x = parent_[x];
    return static_cast<std::uint32_t>(x);
  }
  void unite(std::size_t a, std::size_t b) {
    std::uint32_t ra = find(static_cast<std::uint32_t>(a)), rb = find(static_cast<std::uint32_t>(b));
    if (ra != rb) parent_[std::max(ra, rb)] = std::min(ra, rb);
  }

  // The union-find of the side-s samples in the contour's connectivity.
  // Slabs of z-layers in parallel (their links stay inside the slab), then
  // the links between slabs; within a row every sample of an x-run points
  // at the run's start, and a run is joined to the runs next to it once.
  void join_side(Side s) {
    const std::size_t slabs = std::min<std::size_t>(nz_, 64);
    const auto layer = [&](std::size_t slab) { return nz_ * slab / slabs; };
    tbb::parallel_for(std::size_t{0}, slabs, [&](std::size_t slab) {
      for (std::size_t k = layer(slab); k < layer(slab + 1); ++k)
        for (std::size_t j = 0; j < ny_; ++j) {
          const std::size_t row = nx_ * j + plane_ * k;
          for (std::size_t i = 0; i < nx_; ++i) {
            const std::size_t p = row + i;
            parent_[p] = i > 0 && sides_[p] == s && sides_[p - 1] == s ? parent_[p - 1] : static_cast<std::uint32_t>(p);
          }
          for (std::size_t i = 0; i < nx_; ++i) join_backward(s, i, j, k, k > layer(slab));
        }
    });
    for (std::size_t slab = 1; slab < slabs; ++slab) {
      const std::size_t k = layer(slab);
      if (k == layer(slab - 1)) continue;
      for (std::size_t j = 0; j < ny_; ++j)
        for (std::size_t i = 0; i < nx_; ++i) join_backward_z(s, i, j, k);
    }
  }

  // Links from sample (i, j, k) to lower y (and to lower z when `with_z`).
  void join_backward(Side s, std::size_t i, std::size_t j, std::size_t k, bool with_z) {
    const std::size_t p = i + nx_ * j + plane_ * k;
    if (j > 0) {
      const std::size_t q = p - nx_;
      if (sides_[p] == s && sides_[q] == s && !(i > 0 && sides_[p - 1] == s && sides_[q - 1] == s)) unite(p, q);
      if (i > 0) join_face_diagonal(s, q - 1, q, p, p - 1);
    }
    if (with_z) join_backward_z(s, i, j, k);
  }

  void join_backward_z(Side s, std::size_t i, std::size_t j, std::size_t k) {
    const std::size_t p = i + nx_ * j + plane_ * k, q = p - plane_;
    if (sides_[p] == s && sides_[q] == s && !(i > 0 && sides_[p - 1] == s && sides_[q - 1] == s)) unite(p, q);
    if (i > 0) join_face_diagonal(s, q - 1, q, p, p - 1);
    if (j > 0) join_face_diagonal(s, q - nx_, q, p, p - nx_);
  }

  // Corners in cyclic order; joins the diagonal pair of side s if the face is
  // ambiguous and the decider gives that pair the connection (contour.cpp).
  void join_face_diagonal(Side s, std::size_t c0, std::size_t c1, std::size_t c2, std::size_t c3) {
    const Side s0 = sides_[c0];
    if (s0 == sides_[c1] || s0 != sides_[c2] || sides_[c1] != sides_[c3]) return;
    const auto f = [&](std::size_t c) { return static_cast<double>(field_.values[c]) - iso_; };
    const int pair = diagonal_of(s, s0, f(c0), f(c1), f(c2), f(c3));
    if (pair == 0) unite(c0, c2);
    if (pair == 1) unite(c1, c3);
  }

  std::size_t node_sample(std::size_t p, int n) const {
    return p + (n % 3 - 1) + nx_ * ((n / 3) % 3 - 1) + plane_ * (n / 9 - 1);
  }
  Block block_at(std::size_t p) const {
    Block block;
    for (int n = 0; n < 27; ++n) {
      const std::size_t q = node_sample(p, n);
      block.f[n] = static_cast<double>(field_.values[q]) - iso_;
      block.inside |= static_cast<std::uint32_t>(sides_[q] == kInside) << n;
    }
    return block;
  }
  // The block with the centre given `value` (of the other side of the centre's).
  static Block with_centre(Block block, double f, Side s) {
    block.f[kCentre] = f;
    block.inside = s == kInside ? block.inside | kCentreBit : block.inside & ~kCentreBit;
    return block;
  }
  bool off_box(std::size_t p) const {
    const std::size_t i = p % nx_, j = (p / nx_) % ny_, k = p / plane_;
    return i > 0 && j > 0 && k > 0 && i + 1 < nx_ && j + 1 < ny_ && k + 1 < nz_;
  }

  // Fraction of the edge from p to q (of different sides) at which the contour puts the crossing.
  double crossing_fraction(std::size_t p, std::size_t q) const {
    return contour_rules::crossing_fraction(field_.values[p], field_.values[q], iso_);
  }

  // --- specks and bubbles -------------------------------------------------

  struct Extent {
    std::array<double, 3> low{1e300, 1e300, 1e300}, high{-1e300, -1e300, -1e300};  // crossings, index units
    std::array<std::size_t, 3> first{~std::size_t{0}, ~std::size_t{0}, ~std::size_t{0}}, last{0, 0, 0};  // samples
    bool on_box = false;
    void merge(const Extent& e) {
      for (int a = 0; a < 3; ++a) {
        low[a] = std::min(low[a], e.low[a]), high[a] = std::max(high[a], e.high[a]);
        first[a] = std::min(first[a], e.first[a]), last[a] = std::max(last[a], e.last[a]);
      }
      on_box = on_box || e.on_box;
    }
  };
  using Extents = std::unordered_map<std::uint32_t, Extent>;

  // With the union-find of side s current: changes the side of every
  // component that stays off the box and whose crossings span less than T
  // cells along each axis (its samples lie within the box of its samples
  // next to a crossing). Appends the samples changed; returns the number of
  // components.
  std::size_t remove_small(Side s, std::vector<std::uint32_t>& changed) {
    // Every sample's parent is at or below it (unions link to the smaller
    // root), so one forward pass points each at its root.
    for (std::size_t p = 0; p < n_; ++p) parent_[p] = parent_[parent_[p]];
    const Extents extents = component_extents(s);
    const double spacing[3] = {field_.spacing.x, field_.spacing.y, field_.spacing.z};
    const double cell = field_.cell_size();
    std::vector<std::pair<std::uint32_t, const Extent*>> small;
    for (const auto& [root, extent] : extents) {
      if (extent.on_box) continue;
      bool fits = true;
      for (int a = 0; a < 3; ++a) fits = fits && (extent.high[a] - extent.low[a]) * spacing[a] / cell < cells_;
      if (fits) small.emplace_back(root, &extent);
    }
    std::sort(small.begin(), small.end());
    for (const auto& [root, extent] : small)
      for (std::size_t k = extent->first[2]; k <= extent->last[2]; ++k)
        for (std::size_t j = extent->first[1]; j <= extent->last[1]; ++j)
          for (std::size_t i = extent->first[0]; i <= extent->last[0]; ++i) {
            const std::size_t p = i + nx_ * j + plane_ * k;
            if (sides_[p] != s || find(static_cast<std::uint32_t>(p)) != root) continue;
            flip(static_cast<std::uint32_t>(p));
            changed.push_back(static_cast<std::uint32_t>(p));
          }
    return small.size();
  }

  // Per component root of side s: its crossings' box and whether it touches
  // the volume box. Parallel over layers (the union-find only read).
  Extents component_extents(Side s) const {
    std::vector<Extents> per_layer(nz_);
    tbb::parallel_for(std::size_t{0}, nz_, [&](std::size_t k) { per_layer[k] = layer_extents(s, k); });
    Extents extents;
    for (const Extents& layer : per_layer)
      for (const auto& [root, extent] : layer) extents[root].merge(extent);
    return extents;
  }

  Extents layer_extents(Side s, std::size_t k) const {
    Extents extents;
    const std::size_t stride[3] = {1, nx_, plane_}, size[3] = {nx_, ny_, nz_};
    for (std::size_t j = 0; j < ny_; ++j)
      for (std::size_t i = 0; i < nx_; ++i) {
        const std::size_t p = i + nx_ * j + plane_ * k;
        if (sides_[p] != s) continue;
        const std::size_t c[3] = {i, j, k};
        Extent* extent = nullptr;
        const auto get = [&]() -> Extent& {
          if (!extent) extent = &extents[root_of(p)];
          return *extent;
        };
        if (i == 0 || j == 0 || k == 0 || i + 1 == nx_ || j + 1 == ny_ || k + 1 == nz_) get().on_box = true;
        for (int a = 0; a < 3; ++a)
          for (int dir = -1; dir <= 1; dir += 2) {
            if ((dir < 0 && c[a] == 0) || (dir > 0 && c[a] + 1 == size[a])) continue;
            const std::size_t q = dir < 0 ? p - stride[a] : p + stride[a];
            if (sides_[q] == s) continue;
            Extent& e = get();
            for (int b = 0; b < 3; ++b) {
              const double x = static_cast<double>(c[b]) + (b == a ? dir * crossing_fraction(p, q) : 0.0);
              e.low[b] = std::min(e.low[b], x), e.high[b] = std::max(e.high[b], x);
              e.first[b] = std::min(e.first[b], c[b]), e.last[b] = std::max(e.last[b], c[b]);
            }
          }
      }
    return extents;
  }

  // --- handles and tunnels ------------------------------------------------

  // A side-s sample off the box whose neck is thinner than T and whose
  // change of side splits s locally and leaves the other side one piece.
  bool is_thin_neck(std::size_t p, Side s, float& depth) const {
    const std::size_t stride[3] = {1, nx_, plane_};
    double sum = 0;
    int crossings = 0;
    for (int a = 0; a < 3; ++a)
      for (const std::size_t q : {p - stride[a], p + stride[a]})
        if (sides_[q] != s) sum += crossing_fraction(p, q), ++crossings;
    if (crossings == 0 || 2 * kPi * sum / crossings >= cells_) return false;
    depth = static_cast<float>(sum / crossings);
    const Block before = block_at(p);
    const Block after =
        with_centre(before, static_cast<double>(mirrored_value(field_.values[p], iso_, s)) - iso_, other(s));
    const std::uint32_t links = centre_links(before, s, diagonals(before, s));
    if (pieces_around_centre(after, s, diagonals(after, s), links).count < 2) return false;
    const Diagonals other_side = diagonals(after, other(s));
    return pieces_around_centre(after, other(s), other_side, centre_links(after, other(s), other_side)).count == 1;
  }

  // The thin necks of side s among `samples`.
  std::vector<Neck> find_thin_necks(Side s, const std::vector<std::uint32_t>& samples) const {
    std::vector<float> depth(samples.size(), -1.0f);
    const tbb::blocked_range<std::size_t> all(0, samples.size());
    tbb::parallel_for(all, [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t m = range.begin(); m != range.end(); ++m) {
        const std::size_t p = samples[m];
        if (sides_[p] != s || !off_box(p) || !is_thin_neck(p, s, depth[m])) depth[m] = -1.0f;
      }
    });
    std::vector<Neck> necks;
    for (std::size_t m = 0; m < samples.size(); ++m)
      if (depth[m] >= 0) necks.push_back({samples[m], depth[m], field_.values[samples[m]]});
    return necks;
  }

  // The thin necks of both sides among all samples off the box.
  std::array<std::vector<Neck>, 2> scan_thin_necks() const {
    std::vector<std::array<std::vector<Neck>, 2>> found(nz_);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(1, nz_ - 1), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t k = range.begin(); k != range.end(); ++k)
        for (std::size_t j = 1; j + 1 < ny_; ++j)
          for (std::size_t i = 1; i + 1 < nx_; ++i) {
            const std::size_t p = i + nx_ * j + plane_ * k;
            float depth = 0;
            if (is_thin_neck(p, sides_[p], depth))
              found[k][sides_[p]].push_back({static_cast<std::uint32_t>(p), depth, field_.values[p]});
          }
    });
    std::array<std::vector<Neck>, 2> necks;
    for (const auto& layer : found)
      for (int s = 0; s < 2; ++s) necks[s].insert(necks[s].end(), layer[s].begin(), layer[s].end());
    return necks;
  }

  // Thinnest first, leaves out every neck within one sample of one kept:
  // each kept neck's 27 samples then hold no other, so its local test stays
  // true whatever happens to the others.
  std::vector<Neck> spaced_apart(std::vector<Neck> necks) {
    std::sort(necks.begin(), necks.end(), [](const Neck& a, const Neck& b) {
      return a.depth != b.depth ? a.depth < b.depth : a.sample < b.sample;
    });
    std::vector<Neck> kept;
    for (const Neck& neck : necks) {
      if (original_.count(neck.sample)) continue;  // changed once already: a second change would undo the first
      bool free = true;
      for (int n = 0; n < 27 && free; ++n) free = !mark_[node_sample(neck.sample, n)];
      if (!free) continue;
      mark_[neck.sample] = 1;
      kept.push_back(neck);
    }
    for (const Neck& neck : kept) mark_[neck.sample] = 0;
    return kept;
  }

  // Kruskal's weakest link on side s: takes all necks out, joins the rest,
  // puts the necks back strongest first unless one would close a cycle.
  // Leaves the union-find of side s current. Appends the necks cut to
  // `changed`; returns their count.
  std::size_t cut_weakest_links(Side s, std::vector<Neck> necks, std::vector<std::uint32_t>& changed) {
    for (const Neck& neck : necks) flip(neck.sample);
    join_side(s);
    std::sort(necks.begin(), necks.end(), [](const Neck& a, const Neck& b) {
      return a.depth != b.depth ? a.depth > b.depth : a.sample < b.sample;
    });
    std::size_t cut = 0;
    for (const Neck& neck : necks) {
      const Block after = block_at(neck.sample);
      const Block before = with_centre(after, static_cast<double>(neck.original) - iso_, s);
      const std::uint32_t links = centre_links(before, s, diagonals(before, s));
      const Pieces pieces = pieces_around_centre(after, s, diagonals(after, s), links);
      // Cut only when every piece already reaches every other: then the
      // neck's return would only close cycles, and its absence splits nothing.
      const std::uint32_t root = find(static_cast<std::uint32_t>(node_sample(neck.sample, pieces.node[0])));
      bool one_root = true;
      for (int q = 1; q < pieces.count && one_root; ++q)
        one_root = find(static_cast<std::uint32_t>(node_sample(neck.sample, pieces.node[q]))) == root;
      if (one_root) {
        changed.push_back(neck.sample);
        ++cut;
        continue;
      }
      flip(neck.sample);
      for (int n = 0; n < 27; ++n)
        if ((links >> n) & 1) unite(neck.sample, node_sample(neck.sample, n));
    }
    return cut;
  }

  static std::vector<std::uint32_t> samples_of(const std::vector<Neck>& necks) {
    std::vector<std::uint32_t> samples;
    for (const Neck& neck : necks) samples.push_back(neck.sample);
    return samples;
  }

  // The samples within one sample of a changed one (all are off the box),
  // plus `extra`; sorted, each once.
  std::vector<std::uint32_t> neighbourhoods(const std::vector<std::uint32_t>& changed,
                                            std::vector<std::uint32_t> extra) {
    std::vector<std::uint32_t> samples;
    for (const std::uint32_t p : changed)
      for (int n = 0; n < 27; ++n) samples.push_back(static_cast<std::uint32_t>(node_sample(p, n)));
    samples.insert(samples.end(), extra.begin(), extra.end());
    std::sort(samples.begin(), samples.end());
    samples.erase(std::unique(samples.begin(), samples.end()), samples.end());
    return samples;
  }

  Volume& field_;
  const double iso_, cells_;
  const std::size_t nx_, ny_, nz_, plane_, n_;
  std::vector<Side> sides_;            // per sample, kept in step with field_
  std::vector<std::uint32_t> parent_;  // union-find over samples: flat, 4 bytes each
  std::vector<std::uint8_t> mark_;     // per-sample scratch flags, all 0 between steps
  std::unordered_map<std::uint32_t, float> original_;  // the values of the samples changed
  TopologyCleanup result_;
};

}  // namespace

TopologyCleanup clean_topology(Volume& field, double iso, double cells) {
  if (!(cells >= 0) || !std::isfinite(cells))
    throw Error(ErrorKind::InvalidArgument, "the topology tolerance must be a non-negative number of cells");
  if (!std::isfinite(iso)) throw Error(ErrorKind::InvalidArgument, "the isovalue must be finite");
  // Past float's range nothing (or everything finite) is inside: no sample can change side usefully.
  if (std::abs(iso) > std::numeric_limits<float>::max()) return {};
  if (cells == 0 || field.dims[0] < 3 || field.dims[1] < 3 || field.dims[2] < 3) return {};
  if (field.sample_count() >= (std::size_t{1} << 32))
    throw Error(ErrorKind::Unsupported, "the topology tolerance handles fewer than 2^32 samples");
  const auto start = std::chrono::steady_clock::now();
  TopologyCleanup result = Cleaner(field, iso, cells).run();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace isowave
