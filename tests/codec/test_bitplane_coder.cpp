// The embedded plane coder of .isw 2.0 and 2.1 (codec/src/bitplane_coder.h)
// with several independent groups and one packet per level: split_tree's
// partition, exact values after the last plane whatever the group count, the
// bound of the last complete plane
// at every packet boundary, cuts inside packets that decode only what they
// are sure of, and hostile packets, for both codings (2.1: non-normal flags),
// on coefficients of which some lie along their frame normals (tangential
// components zero); 2.1's estimated tangential bits on coefficients that all do.
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
// zeros, random signs, classes by level; a wavelet coefficient lies along
// its normal (components 1 and 2 zero) with probability `normal`.
Sample sample(std::uint32_t seed, double normal = 0.7) {
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
    const bool along_normal = level > 0 && std::uniform_real_distribution<double>(0, 1)(rng) < normal;
    for (std::size_t k = 0; k < 3; ++k)
      s.symbols.magnitude[3 * i + k] =
          k > 0 && along_normal ? 0 : static_cast<std::uint32_t>(std::ldexp(size(rng), 9 - 2 * level));
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

// Both codings: minor version 0 (2.0) and 1 (2.1, non-normal flags).
class PlaneCoder : public ::testing::TestWithParam<int> {
 protected:
  int minor() const { return GetParam(); }
  PlanePackets encode(const Sample& s, std::size_t groups, IswPlaneBits* bits = nullptr) const {
    return encode_planes(s.tree, s.symbols, groups, minor(), 0, bits);
  }
  std::vector<double> decode(const Sample& s, int top_plane, std::size_t groups,
                             const std::vector<std::string_view>& packets, bool last_cut,
                             int* planes_done = nullptr) const;
};
INSTANTIATE_TEST_SUITE_P(Minor, PlaneCoder, ::testing::Values(0, 1));

std::vector<double> PlaneCoder::decode(const Sample& s, int top_plane, std::size_t groups,
                                       const std::vector<std::string_view>& packets, bool last_cut,
                                       int* planes_done) const {
  PlaneDecoder decoder(s.tree, s.symbols.node_class, s.symbols.classes, minor(), top_plane, groups);
  decoder.decode(packets, last_cut);
  if (planes_done) *planes_done = decoder.planes_done();
  std::vector<Vec3> values(s.tree.nodes, Vec3{1, 1, 1});  // every entry must be written
  decoder.values(values);
  std::vector<double> flat;
  for (const Vec3& v : values) flat.insert(flat.end(), {v.x, v.y, v.z});
  return flat;
}

TEST(PlaneTree, SplitTreeKeepsSubtreesTogetherAndBalancesThem) {
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

TEST_P(PlaneCoder, EveryGroupCountDecodesTheExactValues) {
  const Sample s = sample(2);
  for (const std::size_t groups : {1, 2, 3, 7}) {
    const PlanePackets planes = encode(s, groups);
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

TEST_P(PlaneCoder, PrefixesOfPacketsAndCutsInsideThemKeepTheBound) {
  const Sample s = sample(3);
  constexpr std::size_t kGroups = 3;
  const PlanePackets planes = encode(s, kGroups);
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

TEST_P(PlaneCoder, AStreamEndingBetweenALevelsPacketsDecodesThosePacketsOnly) {
  const Sample s = sample(5);
  constexpr std::size_t kGroups = 2;
  const PlanePackets planes = encode(s, kGroups);
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

TEST_P(PlaneCoder, HostilePacketsDecodeToBoundedValues) {
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

// The two codings carry the same values: after every plane (of one group
// and of several), 2.0 and 2.1 decode alike.
TEST(PlaneCoderMinors, BothCodingsDecodeTheSameValuesAtEveryPlaneEnd) {
  const Sample s = sample(6);
  for (const std::size_t groups : {1, 3}) {
    const PlanePackets p0 = encode_planes(s.tree, s.symbols, groups, 0);
    const PlanePackets p1 = encode_planes(s.tree, s.symbols, groups, 1);
    ASSERT_EQ(p0.top_plane, p1.top_plane);
    ASSERT_EQ(p0.packets.size(), p1.packets.size());
    const std::size_t per_plane = groups * p0.segments;
    for (std::size_t end = 0; end <= p0.packets.size(); end += per_plane) {
      std::vector<std::vector<Vec3>> values;
      for (int minor : {0, 1}) {
        const PlanePackets& p = minor == 0 ? p0 : p1;
        PlaneDecoder decoder(s.tree, s.symbols.node_class, s.symbols.classes, minor, p.top_plane, groups);
        decoder.decode(views(p.packets, end), false);
        values.emplace_back(s.tree.nodes);
        decoder.values(values.back());
      }
      for (std::size_t i = 0; i < s.tree.nodes; ++i) ASSERT_EQ(values[0][i], values[1][i]) << end << " " << i;
    }
  }
}

// Coefficients that all lie along their normals: 2.1 codes one non-normal
// flag (0) per wavelet coefficient that becomes significant, and nothing else
// tangential. By the range coder's model (11-bit probabilities moved 1/32 of
// the way, docs/FORMAT.md), a run of zeros in one context drives the
// probability of a 1 down to 31/2048, where a 0 costs -log2(2017/2048) =
// 0.0221 bits, and the way there from 1/2 costs under 32 bits (a geometric
// sum: about 32 x 0.5 / ln 2 = 23). So the flags cost at most 0.0221 bits
// each plus 32 bits per context (class x parent state, per group). The
// account must also agree with the packets' real size (the coder's loss and
// flush bytes only), and the values decode exactly.
TEST(PlaneCoderMinors, CoefficientsAlongTheirNormalsSpendAlmostNoTangentialBits) {
  const Sample s = sample(7, 1.0);
  constexpr std::size_t kGroups = 2;
  std::size_t significant = 0;
  for (std::size_t i = s.tree.roots_end; i < s.tree.nodes; ++i) significant += s.symbols.magnitude[3 * i] != 0;
  for (std::size_t i = 0; i < s.tree.roots_end; ++i)
    significant += s.symbols.node_class[i] > 0 && s.symbols.magnitude[3 * i] != 0;
  IswPlaneBits bits0, bits1;
  const PlanePackets p0 = encode_planes(s.tree, s.symbols, kGroups, 0, 0, &bits0);
  const PlanePackets p1 = encode_planes(s.tree, s.symbols, kGroups, 1, 0, &bits1);
  const double bound = 0.0221 * double(significant) + 32.0 * s.symbols.classes * 4 * kGroups;
  EXPECT_LE(bits1.tangential(), bound);
  EXPECT_LT(bits1.tangential(), bits0.tangential());
  EXPECT_LT(bits1.tangential_share(), bound / bits1.total());
  EXPECT_EQ(bits1.tangential_sign + bits1.tangential_refinement, 0.0);
  for (const PlanePackets* p : {&p0, &p1}) {
    const IswPlaneBits& bits = p == &p0 ? bits0 : bits1;
    double bytes = 0;
    for (const std::string& packet : p->packets) bytes += double(packet.size());
    EXPECT_LE(bits.total() / 8, bytes * 1.001 + 1);
    EXPECT_LE(bytes, bits.total() / 8 * 1.01 + 5.0 * double(p->packets.size()));
  }
  PlaneDecoder decoder(s.tree, s.symbols.node_class, s.symbols.classes, 1, p1.top_plane, kGroups);
  decoder.decode(views(p1.packets, p1.packets.size()), false);
  std::vector<Vec3> values(s.tree.nodes);
  decoder.values(values);
  for (std::size_t i = 0; i < s.tree.nodes; ++i)
    for (std::size_t k = 0; k < 3; ++k) ASSERT_EQ(values[i][k], exact(s.symbols, i, k)) << i;
}

}  // namespace
}  // namespace isowave::detail
