// The value summary against values the test knows: range and NaN/Inf
// counts, histogram counts, no warning on a sampled smooth field, and the
// warnings a wrong byte order or sample type raises on the same field.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "isowave/extract/volume_summary.h"

namespace isowave {
namespace {

// A smooth field on n^3 samples with values in 0..4000 (as a CT scan's),
// rounded to integers for the integer types.
Volume smooth_volume(std::size_t n, ScalarType type) {
  const bool integer = type != ScalarType::Float32 && type != ScalarType::Float64;
  Volume v;
  v.dims = {n, n, n};
  v.source_type = type;
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t i = 0; i < n; ++i) {
        const float value = 2000.0f + 2000.0f * std::sin(0.2f * float(i) + 0.1f * float(j)) * std::cos(0.15f * float(k));
        v.values.push_back(integer ? std::round(value) : value);
      }
  return v;
}

// The other byte order, written out per type (independent of the code's swap).
std::uint16_t swapped16(std::uint16_t v) { return static_cast<std::uint16_t>((v >> 8) | (v << 8)); }
float swapped32(float value) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &value, 4);
  bits = (bits >> 24) | ((bits >> 8) & 0xff00u) | ((bits << 8) & 0xff0000u) | (bits << 24);
  std::memcpy(&value, &bits, 4);
  return value;
}

bool mentions_misreading(const std::vector<std::string>& warnings) {
  return std::any_of(warnings.begin(), warnings.end(),
                     [](const std::string& w) { return w.find("--endian or --type") != std::string::npos; });
}

TEST(VolumeSummary, RangeAndCountsOfKnownValues) {
  Volume v;
  v.dims = {3, 2, 1};
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  v.values = {2.5f, nan, -7.0f, inf, -inf, 4.0f};
  const ValueSummary s = summarize_values(v);
  EXPECT_EQ(s.min, -7.0);
  EXPECT_EQ(s.max, 4.0);
  EXPECT_EQ(s.finite, 3u);
  EXPECT_EQ(s.nan, 1u);
  EXPECT_EQ(s.infinite, 2u);
  EXPECT_EQ(value_range_text(s), "values -7 .. 4, 1 NaN, 2 Inf");
  EXPECT_TRUE(mentions_misreading(value_warnings(s)));
  // Bins of width 11/2 over [-7, 4]: -7 in the first, 2.5 and 4 (the closed end) in the second.
  EXPECT_EQ(value_histogram(v, s, 2), (std::vector<std::size_t>{1, 2}));
}

TEST(VolumeSummary, HistogramOfARampIsFlat) {
  Volume v;
  v.dims = {100, 1, 1};
  for (int i = 0; i < 100; ++i) v.values.push_back(static_cast<float>(i));
  const ValueSummary s = summarize_values(v);
  EXPECT_EQ(value_histogram(v, s, 4), (std::vector<std::size_t>{25, 25, 25, 25}));
  EXPECT_EQ(value_histogram(v, s, 1), (std::vector<std::size_t>{100}));
}

TEST(VolumeSummary, ASmoothFieldRaisesNoWarning) {
  for (const ScalarType type : {ScalarType::Float32, ScalarType::UInt16, ScalarType::Int16, ScalarType::Float64}) {
    const ValueSummary s = summarize_values(smooth_volume(32, type));
    EXPECT_LT(s.neighbour_step, kNoiseNeighbourStep) << to_string(type);
    EXPECT_TRUE(value_warnings(s).empty()) << to_string(type) << ": " << value_warnings(s).front();
  }
}

// The field's float32 bytes read in the other order: values near the float
// limits, NaN, and the other order much smoother.
TEST(VolumeSummary, SwappedFloatsWarn) {
  Volume v = smooth_volume(32, ScalarType::Float32);
  for (float& value : v.values) value = swapped32(value);
  EXPECT_TRUE(mentions_misreading(value_warnings(summarize_values(v))));
}

// The field's uint16 and int16 bytes read in the other order: every value
// is a valid integer, but the other order is many times smoother.
TEST(VolumeSummary, SwappedIntegersWarn) {
  Volume u = smooth_volume(32, ScalarType::UInt16);
  for (float& value : u.values) value = float(swapped16(static_cast<std::uint16_t>(value)));
  EXPECT_TRUE(mentions_misreading(value_warnings(summarize_values(u))));
  Volume i = smooth_volume(32, ScalarType::Int16);
  for (float& value : i.values) value = float(static_cast<std::int16_t>(swapped16(static_cast<std::uint16_t>(static_cast<std::int16_t>(value)))));
  EXPECT_TRUE(mentions_misreading(value_warnings(summarize_values(i))));
}

// The field's uint16 samples read as uint8 (twice as many along x): low and
// high bytes alternate, like noise.
TEST(VolumeSummary, AWrongTypeWarnsAsNoise) {
  const Volume field = smooth_volume(32, ScalarType::UInt16);
  Volume bytes;
  bytes.dims = {64, 32, 32};
  bytes.source_type = ScalarType::UInt8;
  for (const float value : field.values) {
    const auto sample = static_cast<std::uint16_t>(value);
    bytes.values.push_back(float(sample & 0xff));
    bytes.values.push_back(float(sample >> 8));
  }
  const ValueSummary s = summarize_values(bytes);
  EXPECT_GT(s.neighbour_step, kNoiseNeighbourStep);
  EXPECT_TRUE(mentions_misreading(value_warnings(s)));
}

TEST(VolumeSummary, EmptyIsosurfaceErrorSaysWhereTheIsovalueLies) {
  Volume v;
  v.dims = {2, 1, 1};
  v.values = {-1.0f, 3.0f};
  const Error above = empty_isosurface_error("f.raw", 5, v);
  EXPECT_EQ(above.kind(), ErrorKind::EmptyResult);
  EXPECT_EQ(std::string(above.what()), "f.raw: the isosurface at 5 is empty (every finite sample is below it: values "
                                       "range -1 .. 3)");
  EXPECT_NE(std::string(empty_isosurface_error("f.raw", -1, v).what()).find("every finite sample is at or above it"),
            std::string::npos);
  const Error removed = empty_isosurface_error("f.raw", 1, v, 4);
  EXPECT_EQ(removed.kind(), ErrorKind::EmptyResult);
  EXPECT_NE(std::string(removed.what()).find("the topology tolerance of 4 cells removed the whole isosurface"),
            std::string::npos);
}

}  // namespace
}  // namespace isowave
