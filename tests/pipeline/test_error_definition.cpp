// One definition of the error that convert and stats report (docs/FORMAT.md,
// "Errors"): every row against the full-resolution decode of the file, and the
// quantization error (that decode against the fitted surface) on its own line.
// Both are recomputed here from the decoded file by direct synthesis and RMS.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "isowave/pipeline/convert.h"
#include "isowave/codec/statistics.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {
namespace {

// The fine control points a reader gets from the `keep` most important
// coefficients: the decoded array with the later-ranked ones zeroed, synthesized.
std::vector<Vec3> synthesis_keeping(const IswDecoded& decoded, std::size_t keep) {
  std::vector<Vec3> data = decoded.coefficients;
  for (std::size_t r = keep; r < decoded.ranked.size(); ++r) data[decoded.ranked[r]] = Vec3{};
  synthesize(*decoded.hierarchy, data);
  return data;
}

struct DirectErrors {
  double rms = 0, max = 0;
};
DirectErrors direct_errors(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  EXPECT_EQ(a.size(), b.size());
  double sum = 0, max = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = norm(a[i] - b[i]);
    sum += d * d;
    max = std::max(max, d);
  }
  return {std::sqrt(sum / static_cast<double>(a.size())), max};
}

ConvertResult convert_mixing(double step_cells) {
  ConvertOptions options;
  options.step_cells = step_cells;
  options.summary_percents = {100, 20, 10, 5};
  return convert_volume(make_builtin_field("mixing", 40), "mixing", options);
}

// What `isowave stats` reports for the bytes convert wrote.
ErrorTable stats_of(const ConvertResult& result) {
  return error_table(decode_isw(result.bytes, "test"), {100, 20, 10, 5}, nullptr, nullptr, decode_prefixes(result.bytes));
}

// What `decode --coefficients keep` gives (from a file with plane counts,
// the prefix they name), synthesized, and the file bytes it read.
std::vector<Vec3> decode_keeping(const std::string& file, std::size_t keep, std::uint64_t& bytes) {
  IswDecodeOptions options;
  options.max_coefficients = keep;
  const IswDecoded decoded = decode_isw(file, "test", options);
  bytes = decoded.stream.offset + decoded.stream.decoded;
  return synthesis_keeping(decoded, keep);
}

// Convert's summary and stats' table of the same file are the same numbers,
// and each row is the direct distance of what `decode --coefficients` gives
// from the full decode (so the 100% row is zero), with the bytes it read.
TEST(ErrorDefinition, ConvertAndStatsReportTheSameRows) {
  const ConvertResult result = convert_mixing(0.01);
  const IswDecoded decoded = decode_isw(result.bytes, "test");
  const ErrorTable stats = stats_of(result);
  const std::vector<Vec3> full = synthesis_keeping(decoded, decoded.ranked.size());
  ASSERT_EQ(result.summary.size(), stats.rows.size());
  const double tolerance = 1e-9 * result.cell_size;
  for (std::size_t k = 0; k < stats.rows.size(); ++k) {
    const RateDistortionRow& from_convert = result.summary[k];
    const RateDistortionRow& from_stats = stats.rows[k];
    EXPECT_EQ(from_convert.kept, from_stats.kept);
    EXPECT_EQ(from_convert.bytes, from_stats.bytes);
    EXPECT_NEAR(from_convert.rms, from_stats.rms, tolerance) << "row " << k;
    EXPECT_NEAR(from_convert.max, from_stats.max, tolerance) << "row " << k;
    std::uint64_t bytes = 0;
    const DirectErrors direct = direct_errors(decode_keeping(result.bytes, from_stats.wavelet_coefficients, bytes), full);
    EXPECT_NEAR(from_stats.rms, direct.rms, tolerance) << "row " << k;
    EXPECT_NEAR(from_stats.max, direct.max, tolerance) << "row " << k;
    if (k > 0) {
      EXPECT_EQ(from_stats.bytes, bytes) << "row " << k;  // the prefix it read
    }
  }
  EXPECT_EQ(stats.rows.front().rms, 0.0);  // 100%: the full decode itself
  EXPECT_GT(stats.rows.back().rms, 0.0);   // the base mesh alone
}

// A coarse step (5 cells) leaves every row near zero, as the rows compare
// with the full decode; the quantization error both report shows it, and is
// the direct distance of the full decode from the fitted control points.
TEST(ErrorDefinition, ACoarseStepShowsAsQuantizationError) {
  const ConvertResult result = convert_mixing(5);
  const IswDecoded decoded = decode_isw(result.bytes, "test");
  const DirectErrors direct = direct_errors(synthesis_keeping(decoded, decoded.ranked.size()), result.fit.positions);
  EXPECT_GT(direct.rms, 0.2 * result.cell_size);  // about step / 2 would be expected of a fine step

  const ErrorTable stats = stats_of(result);
  ASSERT_TRUE(stats.quantization.recorded);
  const double tolerance = 1e-8 * direct.max;  // the metadata holds ten significant digits
  EXPECT_NEAR(stats.quantization.rms, direct.rms, tolerance);
  EXPECT_NEAR(stats.quantization.max, direct.max, tolerance);
  ASSERT_TRUE(result.quantization.recorded);
  EXPECT_NEAR(result.quantization.rms, stats.quantization.rms, tolerance);
  EXPECT_NEAR(result.quantization.max, stats.quantization.max, tolerance);
}

}  // namespace
}  // namespace isowave
