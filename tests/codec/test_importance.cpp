// Coefficient importance: class weights follow the wavelets' support, and
// importance-weighted truncation beats selection by raw magnitude.
#include <gtest/gtest.h>

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

TEST(Importance, PercentCountsAsThePaper) {
  const SubdivisionHierarchy h(test::cube(), 3);
  EXPECT_EQ(coefficients_for_percent(h, 0), 0u);
  EXPECT_EQ(coefficients_for_percent(h, 100), h.fine_vertex_count() - 8);
  EXPECT_EQ(coefficients_for_percent(h, 50), static_cast<std::size_t>(std::round(h.fine_vertex_count() * 0.5)) - 8);
  EXPECT_THROW(coefficients_for_percent(h, 101), Error);
}

}  // namespace
}  // namespace isowave
