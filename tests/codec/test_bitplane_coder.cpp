// The embedded plane coder of .isw 2.0 (codec/src/bitplane_coder.h) with
// several independent groups and one packet per level: split_tree's
// partition, exact values after the last plane whatever the group count, the
// bound of the last complete plane
// at every packet boundary, cuts inside packets that decode only what they
// are sure of, and hostile packets.
#include <algorithm>
#include <cmath>
#include <random>
#include <string_view>

#include <gtest/gtest.h>

#include "bitplane_coder.h"
#include "coefficient_tree.h"
#include "codec_test_data.h"

namespace isowave::detail {
namespace {

struct Sample {
  test::CodedSurface surface;
  CoefficientTree tree;
  PlaneSymbols symbols;
};

// Magnitudes of decreasing size down the tree (as wavelet details are), many
// zeros, random signs, classes by level.
Sample sample(std::uint32_t seed) {
  Sample s{test::make_coded_surface(test::genus_slab(2), 3, 0.05, seed), {}, {}};
  s.tree = build_coefficient_tree(*s.surface.hierarchy);
  const std::size_t n = s.tree.nodes;
  std::mt19937 rng(seed);
  std::exponential_distribution<double> size(1.0);
  s.symbols.magnitude.resize(3 * n);
  s.symbols.negative.resize(n);
  s.symbols.node_class.resize(n);
  s.symbols.classes = 4;
  for (std::size_t i = 0; i < n; ++i) {
    const int level = s.surface.hierarchy->level_of_index(i);
    s.symbols.node_class[i] = static_cast<std::uint8_t>(level);
    for (std::size_t k = 0; k < 3; ++k)
      s.symbols.magnitude[3 * i + k] = static_cast<std::uint32_t>(std::ldexp(size(rng), 9 - 2 * level));
    s.symbols.negative[i] = static_cast<std::uint8_t>(rng() & 7);
  }
  return s;
}

// The true value of component k of node i, as the decoder reconstructs a
// component known to plane 0 (m + 1/2 with its sign; 0 when m = 0).
double exact(const PlaneSymbols& s, std::size_t i, std::size_t k) {
  const std::uint32_t m = s.magnitude[3 * i + k];
  if (m == 0) return 0;
  return ((s.negative[i] >> k) & 1 ? -1.0 : 1.0) * (m + 0.5);
}

std::vector<std::string_view> views(const std::vector<std::string>& packets, std::size_t count) {
  return {packets.begin(), packets.begin() + static_cast<std::ptrdiff_t>(count)};
}

std::vector<double> decode(const Sample& s, int top_plane, std::size_t groups, const std::vector<std::string_view>& packets,
                           bool last_cut, int* planes_done = nullptr) {
  PlaneDecoder decoder(s.tree, s.symbols.node_class, s.symbols.classes, top_plane, groups);
  decoder.decode(packets, last_cut);
  if (planes_done) *planes_done = decoder.planes_done();
  std::vector<Vec3> values(s.tree.nodes, Vec3{1, 1, 1});  // every entry must be written
  decoder.values(values);
  std::vector<double> flat;
  for (const Vec3& v : values) flat.insert(flat.end(), {v.x, v.y, v.z});
  return flat;
}

TEST(PlaneCoder, SplitTreeKeepsSubtreesTogetherAndBalancesThem) {
  const Sample s = sample(1);
  for (const std::size_t groups : {1, 2, 5, 64}) {
    const TreeGroups split = split_tree(s.tree, groups);
    ASSERT_EQ(split.count(), groups);
    ASSERT_EQ(split.members.size(), s.tree.nodes);
    std::vector<int> group_of(s.tree.nodes, -1);
    for (std::size_t g = 0; g < groups; ++g) {
      ASSERT_TRUE(std::is_sorted(split.members.begin() + split.offsets[g], split.members.begin() + split.offsets[g + 1]));
      for (std::uint32_t k = split.offsets[g]; k < split.offsets[g + 1]; ++k) group_of[split.members[k]] = static_cast<int>(g);
    }
    for (std::size_t i = 0; i < s.tree.nodes; ++i) {
      ASSERT_GE(group_of[i], 0) << i;  // every node exactly once
      if (i >= s.tree.roots_end) {
        ASSERT_EQ(group_of[i], group_of[s.tree.parent[i]]) << i;
      }
    }
    // Runs of whole subtrees: no group larger than its share plus the largest subtree.
    std::vector<std::size_t> subtree(s.tree.nodes, 1);
    for (std::size_t i = s.tree.nodes; i-- > s.tree.roots_end;) subtree[s.tree.parent[i]] += subtree[i];
    const std::size_t largest = *std::max_element(subtree.begin(), subtree.begin() + static_cast<std::ptrdiff_t>(s.tree.roots_end));
    for (std::size_t g = 0; g < groups; ++g)
      EXPECT_LE(split.offsets[g + 1] - split.offsets[g], s.tree.nodes / groups + largest + 1) << groups << " " << g;
  }
}

TEST(PlaneCoder, EveryGroupCountDecodesTheExactValues) {
  const Sample s = sample(2);
  for (const std::size_t groups : {1, 2, 3, 7}) {
    const PlanePackets planes = encode_planes(s.tree, s.symbols, groups);
    ASSERT_EQ(planes.segments, s.tree.level_ends.size());
    ASSERT_EQ(planes.packets.size(), static_cast<std::size_t>(planes.top_plane + 1) * groups * planes.segments);
    int done = 0;
    const std::vector<double> values =
        decode(s, planes.top_plane, groups, views(planes.packets, planes.packets.size()), false, &done);
    EXPECT_EQ(done, planes.top_plane + 1);
    for (std::size_t i = 0; i < s.tree.nodes; ++i)
      for (std::size_t k = 0; k < 3; ++k) ASSERT_EQ(values[3 * i + k], exact(s.symbols, i, k)) << groups << " " << i;
  }
}

// Each component within 2^low of its value when planes down to `low` are
// known (an insignificant one decodes as 0, a significant one as the middle of
// its interval), with the right sign.
void expect_within_plane_bound(const Sample& s, const std::vector<double>& values, int low, const char* what) {
  const double bound = std::ldexp(1.0, low);
  for (std::size_t i = 0; i < s.tree.nodes; ++i)
    for (std::size_t k = 0; k < 3; ++k) {
      const double truth = exact(s.symbols, i, k);
      ASSERT_LE(std::abs(values[3 * i + k] - truth), bound) << what << " node " << i << " k " << k;
      if (values[3 * i + k] != 0) {
        ASSERT_EQ(values[3 * i + k] < 0, truth < 0) << what << " sign of node " << i;
      }
    }
}

TEST(PlaneCoder, PrefixesOfPacketsAndCutsInsideThemKeepTheBound) {
  const Sample s = sample(3);
  constexpr std::size_t kGroups = 3;
  const PlanePackets planes = encode_planes(s.tree, s.symbols, kGroups);
  const std::size_t per_plane = kGroups * planes.segments;
  std::vector<double> before;
  for (std::size_t count = 0; count <= planes.packets.size(); ++count) {
    // Complete packets: every group has its planes; the slowest sets the bound.
    int done = 0;
    const std::vector<double> after = decode(s, planes.top_plane, kGroups, views(planes.packets, count), false, &done);
    EXPECT_EQ(done, static_cast<int>(count / per_plane));
    expect_within_plane_bound(s, after, planes.top_plane + 1 - done, "complete packets");
    // The last packet cut at a few places: every component decodes as without
    // that packet or as with all of it (a cut decodes only what it is sure of).
    const std::string& last = count > 0 ? planes.packets[count - 1] : std::string();
    for (const std::size_t keep : {std::size_t{0}, last.size() / 3, last.size() / 2, last.size() - 1}) {
      if (keep >= last.size()) continue;
      std::vector<std::string_view> cut = views(planes.packets, count);
      cut.back() = std::string_view(last).substr(0, keep);
      const std::vector<double> values = decode(s, planes.top_plane, kGroups, cut, true);
      for (std::size_t j = 0; j < values.size(); ++j)
        ASSERT_TRUE(values[j] == before[j] || values[j] == after[j])
            << "packet " << count - 1 << " cut to " << keep << ": component " << j << " is " << values[j] << ", not "
            << before[j] << " or " << after[j];
    }
    before = after;
  }
}

TEST(PlaneCoder, AStreamEndingBetweenALevelsPacketsDecodesThosePacketsOnly) {
  const Sample s = sample(5);
  constexpr std::size_t kGroups = 2;
  const PlanePackets planes = encode_planes(s.tree, s.symbols, kGroups);
  const std::size_t per_plane = kGroups * planes.segments;
  ASSERT_GT(planes.segments, 2u);
  std::vector<std::vector<double>> at_plane_ends;
  for (std::size_t end = 0; end <= planes.packets.size(); end += per_plane)
    at_plane_ends.push_back(decode(s, planes.top_plane, kGroups, views(planes.packets, end), false));
  // Within a plane, a component of a node whose level's packet is present has
  // the plane's bit; the others are as before the plane.
  std::vector<std::uint8_t> level(s.tree.nodes);
  std::vector<std::size_t> group(s.tree.nodes);
  const TreeGroups split = split_tree(s.tree, kGroups);
  for (std::size_t g = 0; g < kGroups; ++g)
    for (std::uint32_t k = split.offsets[g]; k < split.offsets[g + 1]; ++k) group[split.members[k]] = g;
  for (std::size_t i = 0; i < s.tree.nodes; ++i)
    level[i] = static_cast<std::uint8_t>(s.surface.hierarchy->level_of_index(i));
  for (std::size_t count = 0; count < planes.packets.size(); ++count) {
    const std::size_t plane = count / per_plane, within = count % per_plane;
    const std::vector<double> values = decode(s, planes.top_plane, kGroups, views(planes.packets, count), false);
    for (std::size_t i = 0; i < s.tree.nodes; ++i) {
      const bool present = level[i] * kGroups + group[i] < within;
      const std::vector<double>& expected = at_plane_ends[plane + (present ? 1 : 0)];
      for (std::size_t k = 0; k < 3; ++k)
        ASSERT_EQ(values[3 * i + k], expected[3 * i + k]) << count << " packets: node " << i << " (level " << int(level[i])
                                                           << ", group " << group[i] << ")";
    }
  }
}

TEST(PlaneCoder, HostilePacketsDecodeToBoundedValues) {
  const Sample s = sample(4);
  std::mt19937 rng(4);
  for (int trial = 0; trial < 20; ++trial) {
    const std::size_t groups = 1 + rng() % 6;
    const int top = static_cast<int>(rng() % 32);
    std::vector<std::string> packets(groups * s.tree.level_ends.size() * static_cast<std::size_t>(top + 1));
    for (std::string& p : packets) {
      p.resize(rng() % 64);
      for (char& c : p) c = static_cast<char>(rng());
    }
    const std::vector<double> values = decode(s, top, groups, views(packets, packets.size()), trial % 2 == 1);
    for (const double v : values) ASSERT_LT(std::abs(v), std::ldexp(1.0, top + 1)) << trial;
  }
}

}  // namespace
}  // namespace isowave::detail
