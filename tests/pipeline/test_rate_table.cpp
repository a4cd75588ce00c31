// The file's rate table (RDTB, issue #47 item 3): a row at 0 stream bytes
// (the base mesh alone) and at every plane end of the stream the file holds,
// up to a cut, each D checked against D of that prefix decoded by
// decode_isw and measured against the extracted isosurface.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/pipeline/convert.h"

namespace isowave {
namespace {

// Rows other than the last are estimates (docs/MEASUREMENTS.md, "The rate
// table's whole curve"); this is the bound on their error the table promises.
constexpr double kEstimateTolerance = 0.06;

ConvertResult convert_mixing(const RateTarget& rate = {}) {
  ConvertOptions options;
  options.keep_extracted_mesh = true;
  options.rate = rate;
  return convert_volume(make_builtin_field("mixing", 32), "mixing", options);
}

// D (world units) of the file's first `stream_bytes` plane stream bytes,
// decoded, against the extracted isosurface.
double decoded_d(const ConvertResult& result, std::uint64_t stream_bytes) {
  IswDecodeOptions prefix;
  prefix.max_stream_bytes = stream_bytes;
  const IswDecoded decoded = decode_isw(result.bytes, "mixing", prefix);
  const PolygonMesh mesh = decoded.hierarchy->control_mesh(decoded.levels, reconstruct(decoded, SIZE_MAX));
  return surface_error(mesh, result.extracted_mesh, kErrorSamples).d();
}

// 0, then each distinct plane end of `file` below `cut` (its packet table).
std::vector<std::uint64_t> prefixes_below(const std::string& file, std::uint64_t cut) {
  std::vector<std::uint64_t> prefixes{0};
  for (const std::uint64_t end : stream_plane_ends(file))
    if (end < cut && end != prefixes.back()) prefixes.push_back(end);
  return prefixes;
}

std::vector<std::uint64_t> bytes_of(const std::vector<IswRatePoint>& table) {
  std::vector<std::uint64_t> bytes;
  for (const IswRatePoint& row : table) bytes.push_back(row.stream_bytes);
  return bytes;
}

// The last row is the exact D of the whole stream (what convert reports);
// every other row lies within the estimate's tolerance of its decode's D.
void expect_rows_measure_their_prefixes(const ConvertResult& result) {
  const std::vector<IswRatePoint>& table = result.rate_table;
  ASSERT_FALSE(table.empty());
  const double last = decoded_d(result, table.back().stream_bytes);
  EXPECT_NEAR(table.back().error, last, 1e-9 * last);
  EXPECT_EQ(table.back().error, result.file_error);
  for (std::size_t r = 0; r + 1 < table.size(); ++r) {
    const double d = decoded_d(result, table[r].stream_bytes);
    EXPECT_NEAR(table[r].error, d, kEstimateTolerance * d) << "row " << r << " at " << table[r].stream_bytes << " bytes";
  }
  // The file's RDTB is the table.
  const IswDecoded file = decode_isw(result.bytes, "mixing");
  ASSERT_EQ(file.stream.rate_table.size(), table.size());
  for (std::size_t r = 0; r < table.size(); ++r) {
    EXPECT_EQ(file.stream.rate_table[r].stream_bytes, table[r].stream_bytes);
    EXPECT_EQ(file.stream.rate_table[r].error, table[r].error);
  }
}

TEST(RateTable, CoversTheBaseMeshAndEveryPlaneEnd) {
  const ConvertResult result = convert_mixing();
  const std::vector<std::uint64_t> ends = stream_plane_ends(result.bytes);
  ASSERT_GE(ends.size(), 8u);
  std::vector<std::uint64_t> expected = prefixes_below(result.bytes, ends.back());
  expected.push_back(ends.back());
  EXPECT_EQ(bytes_of(result.rate_table), expected);
  EXPECT_TRUE(std::is_sorted(expected.begin(), expected.end()));
  expect_rows_measure_their_prefixes(result);
  // The base mesh alone lies farther than the whole stream.
  EXPECT_GT(result.rate_table.front().error, 2 * result.rate_table.back().error);
}

// A --max-error file holds the rows below its cut and the cut, whose D is
// within the bound; rows ascend in bytes.
TEST(RateTable, EndsAtAMaximumErrorsCut) {
  const ConvertResult whole = convert_mixing();
  // Between two plane ends well inside the stream.
  const std::size_t middle = whole.rate_table.size() / 2;
  const double bound = 0.5 * (whole.rate_table[middle].error + whole.rate_table[middle + 1].error);
  RateTarget target;
  target.max_error_cells = bound / whole.cell_size;
  const ConvertResult cut = convert_mixing(target);

  const IswDecoded file = decode_isw(cut.bytes, "mixing");
  const std::uint64_t cut_bytes = file.stream.bytes;
  ASSERT_LT(cut_bytes, whole.rate_table.back().stream_bytes);
  std::vector<std::uint64_t> expected = prefixes_below(whole.bytes, cut_bytes);
  expected.push_back(cut_bytes);
  EXPECT_EQ(bytes_of(cut.rate_table), expected);
  EXPECT_LE(cut.rate_table.back().error, bound);
  EXPECT_EQ(cut.rate_table.back().error, cut.file_error);
  expect_rows_measure_their_prefixes(cut);
}

}  // namespace
}  // namespace isowave
