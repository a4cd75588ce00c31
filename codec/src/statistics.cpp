#include "isowave/codec/statistics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/codec/importance.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {

namespace {

constexpr std::size_t kGrain = 1 << 15;

// Zeroes the coefficients ranked at `keep` and after in `data` (the decoded
// array), then synthesizes level `level` and trims `data` to it.
void keep_and_synthesize(const IswDecoded& decoded, std::size_t keep, int level, std::vector<Vec3>& data) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(std::min(keep, decoded.ranked.size()), decoded.ranked.size(), kGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k < r.end(); ++k) data[decoded.ranked[k]] = Vec3{};
                    });
  synthesize(*decoded.hierarchy, data, level);
  data.resize(decoded.hierarchy->vertex_count(level < 0 ? decoded.levels : level));
}

// reconstruct() into a caller's buffer: repeated calls reuse its pages
// instead of faulting in a fresh fine-mesh-sized array each time.
void reconstruct_into(const IswDecoded& decoded, std::size_t keep, int level, std::vector<Vec3>& data) {
  if (!decoded.hierarchy) throw Error(ErrorKind::InvalidArgument, "reconstruct needs a decoded file");
  const std::size_t count = decoded.coefficients.size();
  if (data.capacity() < count) reserve_fresh_on_huge_pages(data, count);
  data.resize(count);
  // Copying and zeroing touch disjoint entries per thread: the same result
  // on any number of threads.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    std::copy(decoded.coefficients.begin() + static_cast<std::ptrdiff_t>(r.begin()),
              decoded.coefficients.begin() + static_cast<std::ptrdiff_t>(r.end()), data.begin() + static_cast<std::ptrdiff_t>(r.begin()));
  });
  keep_and_synthesize(decoded, keep, level, data);
}

}  // namespace

std::vector<Vec3> reconstruct(const IswDecoded& decoded, std::size_t keep, int level) {
  std::vector<Vec3> data;
  reconstruct_into(decoded, keep, level, data);
  return data;
}

std::vector<Vec3> take_reconstruction(IswDecoded& decoded, std::size_t keep, int level) {
  if (!decoded.hierarchy) throw Error(ErrorKind::InvalidArgument, "reconstruct needs a decoded file");
  std::vector<Vec3> data = std::move(decoded.coefficients);
  decoded.coefficients.clear();
  keep_and_synthesize(decoded, keep, level, data);
  return data;
}

std::vector<RateDistortionRow> rate_distortion(const IswDecoded& decoded, const std::vector<double>& percents,
                                               const std::vector<Vec3>* reference, const PointErrors* all_decoded_errors,
                                               const RowSurfaceVisitor& visit, const PrefixValues& prefix_values) {
  // Version 2: a stream its encoder cut (convert --size) ends inside a plane; complete is every byte read.
  const bool partial = decoded.major_version >= 2 ? decoded.stream.decoded < decoded.stream.bytes
                                                  : decoded.chunks_decoded != decoded.chunks_total;
  if (!decoded.hierarchy || decoded.truncated || partial)
    throw Error(ErrorKind::InvalidArgument, "statistics need a complete decode of the file");
  const SubdivisionHierarchy& h = *decoded.hierarchy;
  const std::size_t fine = h.fine_vertex_count();
  if (reference && reference->size() < fine)
    throw Error(ErrorKind::InvalidArgument, "the reference has fewer points than the fine level");
  const std::vector<Vec3> full = reference ? std::vector<Vec3>{} : reconstruct(decoded, decoded.ranked.size());
  const std::vector<Vec3>& compare_to = reference ? *reference : full;

  // Bytes before the first chunk, and after each chunk.
  std::uint64_t header_bytes = 16;
  std::vector<std::uint64_t> chunk_end_rank, chunk_end_bytes;
  std::uint64_t rank = 0;
  for (const IswSectionInfo& s : decoded.sections) {
    if (s.tag == "PLNS") {  // version 2: a percentage ranks the whole decode
      chunk_end_rank.push_back(decoded.ranked.size());
      chunk_end_bytes.push_back(s.offset + s.bytes);
    } else if (s.tag == "CHNK") {
      rank += s.coefficients;
      chunk_end_rank.push_back(rank);
      chunk_end_bytes.push_back(s.offset + s.bytes);
    } else if (s.tag != "END ") {
      header_bytes = s.offset + s.bytes;
    }
  }
  const auto bytes_for = [&](std::size_t kept_wavelets) -> std::uint64_t {
    if (kept_wavelets == 0) return header_bytes;
    for (std::size_t c = 0; c < chunk_end_rank.size(); ++c)
      if (chunk_end_rank[c] >= kept_wavelets) return chunk_end_bytes[c];
    return chunk_end_bytes.empty() ? header_bytes : chunk_end_bytes.back();
  };

  std::vector<RateDistortionRow> rows;
  std::vector<Vec3> reconstruction, prefix_coefficients;
  std::uint64_t prefix_read = UINT64_MAX;  // the prefix in prefix_coefficients
  const auto add_row = [&](std::size_t wavelets, bool is_base) {
    RateDistortionRow row;
    row.wavelet_coefficients = std::min(wavelets, decoded.ranked.size());
    row.kept = h.vertex_count(0) + wavelets;
    row.percent = 100.0 * static_cast<double>(row.kept) / static_cast<double>(fine);
    row.bytes = bytes_for(row.wavelet_coefficients);
    PointErrors e;
    if (wavelets >= decoded.ranked.size() && (!reference || all_decoded_errors)) {
      if (reference) e = *all_decoded_errors;  // else: the full decode itself, zero
    } else {
      const std::uint64_t prefix = stream_bytes_for_keep(decoded, wavelets);
      if (prefix_values && prefix < decoded.stream.bytes) {
        // What decode --percent keeps: the most important of the prefix's values.
        if (prefix != prefix_read) prefix_values(prefix, prefix_coefficients);
        prefix_read = prefix;
        reconstruction = prefix_coefficients;
        keep_most_important(h, reconstruction, decoded.class_weights, wavelets);
        synthesize(h, reconstruction);
        reconstruction.resize(fine);
        row.bytes = decoded.stream.offset + prefix;
      } else {
        reconstruct_into(decoded, wavelets, -1, reconstruction);
      }
      e = point_errors(reconstruction, compare_to, fine);
      if (visit) visit(rows.size(), row.wavelet_coefficients, reconstruction);
    }
    row.rms = e.rms;
    row.max = e.max;
    row.is_base = is_base;
    rows.push_back(row);
  };
  for (double percent : percents) add_row(coefficients_for_percent(h, percent), false);
  add_row(0, true);
  return rows;
}

PrefixValues decode_prefixes(const std::string& file) {
  return [&file](std::uint64_t stream_bytes, std::vector<Vec3>& coefficients) {
    IswDecodeOptions options;
    options.max_stream_bytes = stream_bytes;
    options.order = IswOrder::Index;
    coefficients = decode_isw(file, "statistics", options).coefficients;
  };
}

ErrorTable error_table(const IswDecoded& decoded, const std::vector<double>& percents, const std::vector<Vec3>* full_decode,
                       const RowSurfaceVisitor& visit, const PrefixValues& prefix_values) {
  // Rows keeping every decoded coefficient are the full decode itself.
  const PointErrors none;
  ErrorTable table;
  table.rows = rate_distortion(decoded, percents, full_decode, full_decode ? &none : nullptr, visit, prefix_values);
  table.quantization = recorded_quantization_error(decoded.metadata);
  return table;
}

namespace {
constexpr const char* kQuantizationRmseKey = "quantization_rmse";
constexpr const char* kQuantizationMaxKey = "quantization_max";

std::string ten_digits(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", value);
  return text;
}
}  // namespace

void record_quantization_error(const PointErrors& errors, IswMetadata& metadata) {
  metadata.values[kQuantizationRmseKey] = ten_digits(errors.rms);
  metadata.values[kQuantizationMaxKey] = ten_digits(errors.max);
}

QuantizationError recorded_quantization_error(const IswMetadata& metadata) {
  QuantizationError error;
  error.rms = metadata.number(kQuantizationRmseKey, NAN);
  error.max = metadata.number(kQuantizationMaxKey, NAN);
  error.recorded = std::isfinite(error.rms) && error.rms >= 0;
  if (!error.recorded) error = QuantizationError{};
  return error;
}

std::string describe_quantization_error(const QuantizationError& error, double cell_size) {
  if (!error.recorded) return "quantization error: not recorded in the file";
  char max[48] = "not recorded";
  if (std::isfinite(error.max)) std::snprintf(max, sizeof max, "%.3g%%", 100 * error.max / cell_size);
  char text[160];
  std::snprintf(text, sizeof text,
                "quantization error (full decode against the fitted surface): RMSE %.3g%% of a cell, max %s",
                100 * error.rms / cell_size, max);
  return text;
}

}  // namespace isowave
