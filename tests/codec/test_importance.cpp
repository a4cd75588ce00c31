// Coefficient importance: class weights follow the wavelets' support, and
// importance-weighted truncation beats selection by raw magnitude.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "codec_test_data.h"
#include "isowave/codec/importance.h"
#include "isowave/core/error.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {
namespace {

TEST(Importance, ClassesPartitionTheCoefficientArray) {
  const SubdivisionHierarchy h(test::genus_slab(2), 3);
  std::size_t next = 0;
  for (int c = 0; c < coefficient_class_count(h); ++c) {
    const auto [first, last] = coefficient_class_range(h, c);
    EXPECT_EQ(first, next);
    EXPECT_LT(first, last);
    for (std::size_t i = first; i < last; ++i) ASSERT_EQ(coefficient_class(h, i), c);
    next = last;
  }
  EXPECT_EQ(next, h.fine_vertex_count());
}

TEST(Importance, WaveletNormsHalveWithEachFinerLevel) {
  // Away from the finest level a wavelet is a smooth bump: a level-l one
  // covers about four times the fine points of a level-(l+1) one with
  // comparable amplitude, so its L2 norm is about twice as large.
  const SubdivisionHierarchy h(test::quad_grid(24, 24, true, true), 4);
  const std::vector<double> norms = wavelet_norms(h);
  ASSERT_EQ(norms.size(), 9u);
  for (int level = 1; level + 1 < 4; ++level)
    for (int type = 0; type < 2; ++type) {
      const double coarse = norms[1 + 2 * (level - 1) + type], finer = norms[1 + 2 * level + type];
      EXPECT_GT(coarse / finer, 1.7) << "level " << level << " type " << type;
      EXPECT_LT(coarse / finer, 2.3) << "level " << level << " type " << type;
    }
  // The scaling functions of the base mesh are the largest; finest-level
  // wavelets are their own lifting stencils, of order one.
  for (std::size_t c = 1; c < norms.size(); ++c) EXPECT_GT(norms[0], norms[c]);
  for (std::size_t c : {7u, 8u}) {
    EXPECT_GT(norms[c], 0.25);
    EXPECT_LT(norms[c], 4.0);
  }
}

TEST(Importance, WaveletNormsEqualOneSynthesisPerClass) {
  // The definition: one synthesis of random signs per class, the signs drawn
  // class after class from the fixed seed. Sharing syntheses must not change
  // a bit of the weights, which every .isw file stores.
  for (int levels : {1, 2, 3}) {
    const SubdivisionHierarchy h(test::genus_slab(2), levels);
    std::vector<double> expected(static_cast<std::size_t>(coefficient_class_count(h)), 1.0);
    std::mt19937 rng(12345);
    for (int c = 0; c < coefficient_class_count(h); ++c) {
      std::vector<Vec3> data(h.fine_vertex_count());
      const auto [first, last] = coefficient_class_range(h, c);
      for (std::size_t i = first; i < last; ++i) data[i].x = (rng() & 1) ? 1.0 : -1.0;
      synthesize(h, data);
      double sum = 0;
      for (const Vec3& p : data) sum += p.x * p.x;
      expected[static_cast<std::size_t>(c)] = std::sqrt(sum / static_cast<double>(last - first));
    }
    const std::vector<double> norms = wavelet_norms(h);
    ASSERT_EQ(norms.size(), expected.size());
    for (std::size_t c = 0; c < norms.size(); ++c) EXPECT_EQ(norms[c], expected[c]) << "levels " << levels << " class " << c;
  }
}

TEST(Importance, WeightedTruncationBeatsRawMagnitude) {
  const test::CodedSurface s = test::make_coded_surface(test::genus_slab(3), 4, 0.05, 3);
  const SubdivisionHierarchy& h = *s.hierarchy;
  const std::vector<double> weights = wavelet_norms(h);
  const std::vector<double> unit(weights.size(), 1.0);
  for (double percent : {5.0, 10.0}) {
    const std::size_t keep = coefficients_for_percent(h, percent);
    std::vector<Vec3> weighted = s.coefficients, raw = s.coefficients;
    keep_most_important(h, weighted, weights, keep);
    keep_most_important(h, raw, unit, keep);
    synthesize(h, weighted);
    synthesize(h, raw);
    const double weighted_rms = point_errors(weighted, s.fine, s.fine.size()).rms;
    const double raw_rms = point_errors(raw, s.fine, s.fine.size()).rms;
    std::printf("[ report ] %.0f%%: RMSE weighted %.5f, raw magnitude %.5f\n", percent, weighted_rms, raw_rms);
    EXPECT_LT(weighted_rms, raw_rms) << percent << "%";
  }
}

// Analytic surfaces for the oracles: the subdivided base mesh on a sphere
// around its centroid, rippled by sin(k x) sin(k y) sin(k z), analysed into
// coefficients: details of every size at every level.
struct AnalyticSurface {
  std::unique_ptr<SubdivisionHierarchy> hierarchy;
  std::vector<Vec3> fine, coefficients;
};

AnalyticSurface analytic_surface(const PolygonMesh& base, int levels, double ripple) {
  AnalyticSurface s;
  s.hierarchy = std::make_unique<SubdivisionHierarchy>(base, levels);
  s.fine = subdivide(*s.hierarchy, base.positions);
  Vec3 center{};
  for (const Vec3& p : s.fine) center = center + p;
  center = center * (1.0 / static_cast<double>(s.fine.size()));
  for (Vec3& p : s.fine) {
    const Vec3 u = (p - center) * (1.0 / norm(p - center));
    p = center + u * (1.0 + ripple * std::sin(7 * u.x) * std::sin(7 * u.y) * std::sin(7 * u.z));
  }
  s.coefficients = s.fine;
  analyze(*s.hierarchy, s.coefficients);
  return s;
}

double rms_after(const SubdivisionHierarchy& h, std::vector<Vec3> kept, const std::vector<Vec3>& fine) {
  synthesize(h, kept);
  return point_errors(kept, fine, fine.size()).rms;
}

std::size_t nonzero_wavelets(const SubdivisionHierarchy& h, const std::vector<Vec3>& c) {
  std::size_t n = 0;
  for (std::size_t i = h.vertex_count(0); i < h.fine_vertex_count(); ++i) n += c[i] == Vec3{} ? 0 : 1;
  return n;
}

TEST(Importance, GreedyOracleNeverWorseThanMagnitudeOnAnalyticSurfaces) {
  const std::vector<std::pair<const char*, PolygonMesh>> bases{
      {"cube", test::cube()}, {"octahedron", test::octahedron()}, {"torus", test::quad_grid(8, 6, true, true)},
      {"genus-2 slab", test::genus_slab(2)}, {"prism", test::pentagonal_prism()}};
  for (const auto& [name, base] : bases) {
    const AnalyticSurface s = analytic_surface(base, 4, 0.15);
    const SubdivisionHierarchy& h = *s.hierarchy;
    const std::vector<double> weights = wavelet_norms(h);
    const std::vector<double> unit(weights.size(), 1.0);
    for (double percent : {2.0, 5.0, 10.0, 20.0}) {
      const std::size_t keep = coefficients_for_percent(h, percent);
      std::vector<Vec3> greedy = s.coefficients, magnitude = s.coefficients, weighted = s.coefficients;
      const std::vector<std::uint32_t> kept = keep_greedy(h, greedy, keep);
      keep_most_important(h, magnitude, unit, keep);
      keep_most_important(h, weighted, weights, keep);
      // Exactly `keep` coefficients stay, each with its own value.
      ASSERT_EQ(kept.size(), keep);
      EXPECT_EQ(nonzero_wavelets(h, greedy), keep);
      for (std::uint32_t i : kept) ASSERT_EQ(greedy[i], s.coefficients[i]);
      const double g = rms_after(h, greedy, s.fine), m = rms_after(h, magnitude, s.fine), w = rms_after(h, weighted, s.fine);
      std::printf("[ report ] %s %.0f%%: RMSE greedy %.5f, weighted %.5f, magnitude %.5f\n", name, percent, g, w, m);
      EXPECT_LE(g, m) << name << " " << percent << "%";
    }
  }
}

TEST(Importance, GreedyOracleInOneRoundKeepsTheLargestExactWaveletEnergies) {
  // Before any rejection the conditional error is |c|^2 ||psi||^2: one round
  // keeps the coefficients with the largest (the norms themselves are
  // checked against dense syntheses in tests/transform/test_wavelet_transform.cpp).
  const test::CodedSurface s = test::make_coded_surface(test::genus_slab(2), 2, 0.05, 7);
  const SubdivisionHierarchy& h = *s.hierarchy;
  const std::size_t keep = coefficients_for_percent(h, 10);
  const std::vector<double> psi = wavelet_squared_norms(h);
  std::vector<std::pair<double, std::size_t>> energy;
  for (std::size_t i = h.vertex_count(0); i < h.fine_vertex_count(); ++i)
    energy.push_back({-squared_norm(s.coefficients[i]) * psi[i], i});
  std::sort(energy.begin(), energy.end());
  std::vector<Vec3> greedy = s.coefficients;
  keep_greedy(h, greedy, keep, 1e9);
  for (std::size_t k = 0; k < energy.size(); ++k)
    ASSERT_EQ(greedy[energy[k].second] == Vec3{}, k >= keep) << "rank " << k;
}

TEST(Importance, GreedyOracleKeepsEverythingWhenAskedForMore) {
  const test::CodedSurface s = test::make_coded_surface(test::cube(), 2, 0.05, 3);
  const SubdivisionHierarchy& h = *s.hierarchy;
  std::vector<Vec3> greedy = s.coefficients;
  const std::vector<std::uint32_t> kept = keep_greedy(h, greedy, h.fine_vertex_count());
  EXPECT_EQ(greedy, s.coefficients);
  EXPECT_EQ(kept.size(), nonzero_wavelets(h, s.coefficients));
}

TEST(Importance, PercentCountsAsThePaper) {
  const SubdivisionHierarchy h(test::cube(), 3);
  EXPECT_EQ(coefficients_for_percent(h, 0), 0u);
  EXPECT_EQ(coefficients_for_percent(h, 100), h.fine_vertex_count() - 8);
  EXPECT_EQ(coefficients_for_percent(h, 50), static_cast<std::size_t>(std::round(h.fine_vertex_count() * 0.5)) - 8);
  EXPECT_THROW(coefficients_for_percent(h, 101), Error);
}

}  // namespace
}  // namespace isowave
