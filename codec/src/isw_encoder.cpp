// The .isw encoder: quantization, importance ranking, and one writer per
// section (docs/FORMAT.md).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/atomic_file.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isw_models.h"
#include "isw2_layout.h"
#include "isw_headers.h"
#include "isw_sections.h"

namespace isowave {

using namespace detail;

namespace {

// ------------------------------------------------------------ quantization

bool quantizable(double scaled) { return std::isfinite(scaled) && std::abs(scaled) <= 1e9; }

// Every entry rounded, per component, to a multiple of its class's step; the
// one quantization both the encoder and quantize_coefficients() use.
std::vector<QuantizedVector> quantize(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                                      double step, const std::vector<double>& weights) {
  std::vector<QuantizedVector> q;
  reserve_fresh_on_huge_pages(q, hierarchy.fine_vertex_count());
  q.resize(hierarchy.fine_vertex_count());
  std::atomic<bool> invalid{false};
  for (int c = 0; c < coefficient_class_count(hierarchy); ++c) {
    const double s = class_step(step, weights, c);
    const auto [first, last] = coefficient_class_range(hierarchy, c);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i)
        for (int axis = 0; axis < 3; ++axis) {
          const double scaled = coefficients[i][axis] / s;
          if (quantizable(scaled)) q[i][axis] = std::llround(scaled);
          else invalid.store(true, std::memory_order_relaxed);
        }
    });
  }
  if (invalid) {
    // Serially, so that the error names the first offending coefficient.
    for (int c = 0; c < coefficient_class_count(hierarchy); ++c) {
      const double s = class_step(step, weights, c);
      const auto [first, last] = coefficient_class_range(hierarchy, c);
      for (std::size_t i = first; i < last; ++i)
        for (int axis = 0; axis < 3; ++axis)
          if (!quantizable(coefficients[i][axis] / s))
            throw Error(ErrorKind::InvalidArgument, "coefficient " + std::to_string(i) +
                                                        " is not finite or too large for the quantization step");
    }
  }
  return q;
}

std::vector<Vec3> dequantize(const SubdivisionHierarchy& hierarchy, const std::vector<QuantizedVector>& q, double step,
                             const std::vector<double>& weights) {
  std::vector<Vec3> result;
  reserve_fresh_on_huge_pages(result, hierarchy.fine_vertex_count());
  result.resize(hierarchy.fine_vertex_count());
  for (int c = 0; c < coefficient_class_count(hierarchy); ++c) {
    const double s = class_step(step, weights, c);
    const auto [first, last] = coefficient_class_range(hierarchy, c);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) result[i] = {q[i][0] * s, q[i][1] * s, q[i][2] * s};
    });
  }
  return result;
}

// The non-zero wavelet coefficients in the order the encoder sends them.
std::vector<std::uint32_t> ranked_nonzero(const SubdivisionHierarchy& hierarchy, const std::vector<QuantizedVector>& q,
                                          double step, const std::vector<double>& weights) {
  std::vector<std::uint32_t> ranked;
  for (std::size_t i = hierarchy.vertex_count(0); i < hierarchy.fine_vertex_count(); ++i)
    if (q[i][0] != 0 || q[i][1] != 0 || q[i][2] != 0) ranked.push_back(static_cast<std::uint32_t>(i));
  std::vector<RankedEntry> keyed(ranked.size());
  const CoefficientClasses classes(hierarchy);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ranked.size(), kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k)
      keyed[k] = {importance_key(classes.of(ranked[k]), q[ranked[k]], step, weights), ranked[k], 0};
  });
  sort_by_importance(keyed);
  for (std::size_t k = 0; k < ranked.size(); ++k) ranked[k] = keyed[k].index;
  return ranked;
}

// Chunk boundaries (cumulative ranks) at the requested percentages; the last
// chunk ends with the last coefficient.
std::vector<std::uint64_t> chunk_ends_for(const SubdivisionHierarchy& hierarchy, const std::vector<double>& percents,
                                          std::size_t ranked) {
  std::vector<std::uint64_t> chunk_ends;
  for (double percent : percents) {
    const std::uint64_t end = std::min<std::uint64_t>(coefficients_for_percent(hierarchy, percent), ranked);
    if (end > 0 && (chunk_ends.empty() || end > chunk_ends.back())) chunk_ends.push_back(end);
  }
  if (chunk_ends.empty() || chunk_ends.back() < ranked) chunk_ends.push_back(ranked);
  if (ranked == 0) chunk_ends.clear();
  return chunk_ends;
}

void check_encode_arguments(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients, double step,
                            const std::vector<double>& weights) {
  if (hierarchy.levels() > kMaxLevels)
    throw Error(ErrorKind::InvalidArgument, "levels must be in 0.." + std::to_string(kMaxLevels));
  if (!(step > 0) || !std::isfinite(step))
    throw Error(ErrorKind::InvalidArgument, "the quantization step must be positive");
  if (coefficients.size() != hierarchy.fine_vertex_count())
    throw Error(ErrorKind::InvalidArgument, "expected " + std::to_string(hierarchy.fine_vertex_count()) +
                                                " coefficients, got " + std::to_string(coefficients.size()));
  if (weights.size() != static_cast<std::size_t>(coefficient_class_count(hierarchy)))
    throw Error(ErrorKind::InvalidArgument, "expected one weight per coefficient class");
}

// ------------------------------------------------------------ sections

void put_quantization(std::string& out, double step, int levels, const std::vector<double>& weights,
                      std::uint64_t coefficients, const std::vector<std::uint64_t>& chunk_ends) {
  std::string payload;
  put_f64(payload, step);
  put_u32(payload, static_cast<std::uint32_t>(levels));
  put_u32(payload, static_cast<std::uint32_t>(weights.size()));
  for (double w : weights) put_f64(payload, w);
  put_u64(payload, coefficients);
  put_u32(payload, static_cast<std::uint32_t>(chunk_ends.size()));
  for (std::uint64_t end : chunk_ends) put_u64(payload, end);
  put_section(out, "QUAN", payload);
}

// One CHNK section: flags over the coefficients not yet significant, in
// index order per class, with the components of those ranked in [begin, end).
std::string chunk_section(const SubdivisionHierarchy& hierarchy, const std::vector<QuantizedVector>& q,
                          const std::vector<std::uint32_t>& rank_of, std::size_t chunk, std::uint64_t begin,
                          std::uint64_t end) {
  const int classes = coefficient_class_count(hierarchy);
  std::string coded;
  RangeEncoder rc(coded);
  ChunkModels models(classes);
  for (int c = 1; c < classes; ++c) {
    const auto [first, last] = coefficient_class_range(hierarchy, c);
    int previous_flag = 0;
    std::array<int, 3> previous_bucket{0, 0, 0};
    // The flag contexts as locals, as in the decoder (the same arithmetic).
    Probability flag_after_zero = models.flags[static_cast<std::size_t>(c)][0];
    Probability flag_after_one = models.flags[static_cast<std::size_t>(c)][1];
    for (std::size_t i = first; i < last; ++i) {
      const std::uint32_t rank = rank_of[i];
      if (rank < begin) continue;  // sent by an earlier chunk
      const int flag = rank < end ? 1 : 0;
      rc.encode_bit(previous_flag ? flag_after_one : flag_after_zero, flag);
      previous_flag = flag;
      if (!flag) continue;
      for (int axis = 0; axis < 3; ++axis) {
        encode_integer(rc, models.component(c, axis, previous_bucket[static_cast<std::size_t>(axis)]), q[i][axis]);
        previous_bucket[static_cast<std::size_t>(axis)] = magnitude_bucket(q[i][axis]);
      }
    }
  }
  rc.finish();
  std::string payload;
  put_u32(payload, static_cast<std::uint32_t>(chunk));
  put_u64(payload, begin);
  put_u64(payload, end);
  put_coded(payload, coded);
  std::string section;
  put_section(section, "CHNK", payload);
  return section;
}

// The CHNK sections. A coefficient is significant before chunk k when its
// rank precedes the chunk's first, so every chunk is coded on its own, in
// parallel.
void put_chunks(std::string& out, const SubdivisionHierarchy& hierarchy, const std::vector<QuantizedVector>& q,
                const std::vector<std::uint32_t>& ranked, const std::vector<std::uint64_t>& chunk_ends) {
  std::vector<std::uint32_t> rank_of;
  reserve_fresh_on_huge_pages(rank_of, hierarchy.fine_vertex_count());
  rank_of.assign(hierarchy.fine_vertex_count(), UINT32_MAX);
  for (std::size_t r = 0; r < ranked.size(); ++r) rank_of[ranked[r]] = static_cast<std::uint32_t>(r);
  std::vector<std::string> sections(chunk_ends.size());
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, chunk_ends.size(), 1),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t chunk = r.begin(); chunk < r.end(); ++chunk)
          sections[chunk] = chunk_section(hierarchy, q, rank_of, chunk, chunk == 0 ? 0 : chunk_ends[chunk - 1],
                                          chunk_ends[chunk]);
      },
      tbb::simple_partitioner());
  for (std::string& section : sections) {
    out += section;
    std::string().swap(section);
  }
}

}  // namespace

std::vector<Vec3> quantize_coefficients(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                                        double step, const std::vector<double>& class_weights) {
  check_encode_arguments(hierarchy, coefficients, step, class_weights);
  return dequantize(hierarchy, quantize(hierarchy, coefficients, step, class_weights), step, class_weights);
}

std::string encode_isw(const PolygonMesh& base, int levels, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options) {
  if (levels < 0 || levels > kMaxLevels)
    throw Error(ErrorKind::InvalidArgument, "levels must be in 0.." + std::to_string(kMaxLevels));
  return encode_isw(SubdivisionHierarchy(base, levels), coefficients, metadata, options);
}

std::string encode_isw(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options, IswPlaneValues& planes) {
  if (options.major_version != 2) throw Error(ErrorKind::InvalidArgument, "plane values need a version 2 file");
  std::vector<double> weights = options.class_weights.empty() ? wavelet_norms(hierarchy) : options.class_weights;
  check_encode_arguments(hierarchy, coefficients, options.step, weights);
  auto state = std::make_unique<PlaneValuesState>();
  std::string file = encode_isw_v2(hierarchy, coefficients, metadata, options, std::move(weights), state.get());
  planes.state_ = std::move(state);
  return file;
}

std::string encode_isw(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options,
                       std::vector<std::uint32_t>* ranked_out) {
  std::vector<double> weights = options.class_weights.empty() ? wavelet_norms(hierarchy) : options.class_weights;
  check_encode_arguments(hierarchy, coefficients, options.step, weights);
  if (options.major_version == 2) {
    if (ranked_out) ranked_out->clear();
    return encode_isw_v2(hierarchy, coefficients, metadata, options, std::move(weights));
  }
  if (options.major_version != 1) throw Error(ErrorKind::InvalidArgument, "the format version must be 1 or 2");
  const std::vector<QuantizedVector> q = quantize(hierarchy, coefficients, options.step, weights);
  std::vector<std::uint32_t> ranked = ranked_nonzero(hierarchy, q, options.step, weights);
  const std::vector<std::uint64_t> chunk_ends = chunk_ends_for(hierarchy, options.chunk_percents, ranked.size());

  std::string out;
  put_file_header(out, 1, 0);
  put_meta(out, metadata, 1);
  put_base(out, hierarchy.base(), 1);
  put_quantization(out, options.step, hierarchy.levels(), weights, ranked.size(), chunk_ends);
  put_base_points(out, hierarchy.base(), q);
  put_chunks(out, hierarchy, q, ranked, chunk_ends);
  put_section(out, "END ", std::string_view());
  if (ranked_out) *ranked_out = std::move(ranked);
  return out;
}

void write_isw(const std::string& path, const std::string& bytes, bool overwrite) {
  AtomicFileWriter file(path, overwrite);
  file.write(bytes);
  file.commit();
}

}  // namespace isowave
