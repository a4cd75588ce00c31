#include "isowave/codec/isw_format.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cassert>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <string_view>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_group.h>
#include <zlib.h>

#include "isowave/codec/importance.h"
#include "isowave/core/atomic_file.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/transform/hierarchy.h"
#include "range_coder.h"

namespace isowave {

using detail::IntegerModel;
using detail::Probability;
using detail::RangeDecoder;
using detail::RangeEncoder;

namespace {

constexpr char kMagic[8] = {'\x89', 'I', 'S', 'W', '\r', '\n', '\x1a', '\n'};
constexpr std::size_t kHeaderBytes = 16;
constexpr std::size_t kSectionHeader = 4 + 8 + 4;  // tag, payload size, CRC-32 of tag and size
constexpr std::size_t kSectionOverhead = kSectionHeader + 4;
// Generous bounds that a hostile file cannot push the decoder past.
constexpr int kMaxLevels = 8;
constexpr std::uint64_t kMaxFineVertices = 1ull << 28;
constexpr std::uint64_t kFineVerticesPerFileByte = 4096;
// An adaptive binary decision costs at least ~0.02 bits and an integer at
// least six of them, so a coded byte holds at most ~64 integers.
constexpr std::uint64_t kMaxIntegersPerCodedByte = 64;

// ------------------------------------------------------------ byte helpers

void put_u16(std::string& out, std::uint16_t v) { out.append(reinterpret_cast<const char*>(&v), 2); }
void put_u32(std::string& out, std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); }
void put_u64(std::string& out, std::uint64_t v) { out.append(reinterpret_cast<const char*>(&v), 8); }
void put_f64(std::string& out, double v) { out.append(reinterpret_cast<const char*>(&v), 8); }

std::uint32_t crc_of(const char* tag, std::string_view payload) {
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(tag), 4);
  // zlib's crc32 takes a uInt length: feed large payloads in pieces.
  for (std::size_t offset = 0; offset < payload.size(); offset += 1u << 30) {
    const std::size_t n = std::min<std::size_t>(payload.size() - offset, 1u << 30);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(payload.data() + offset), static_cast<uInt>(n));
  }
  return static_cast<std::uint32_t>(crc);
}

// The header has its own CRC so that a damaged size field reads as corruption,
// while a file cut inside a payload reads as truncation.
std::uint32_t header_crc(const char* tag, std::uint64_t size) {
  std::string size_bytes;
  put_u64(size_bytes, size);
  return crc_of(tag, size_bytes);
}

void put_section(std::string& out, const char* tag, const std::string& payload) {
  out.append(tag, 4);
  put_u64(out, payload.size());
  put_u32(out, header_crc(tag, payload.size()));
  out += payload;
  put_u32(out, crc_of(tag, payload));
}

// Bounds-checked little-endian reader over one section's payload.
class PayloadReader {
 public:
  PayloadReader(std::string_view data, std::string context) : data_(data), context_(std::move(context)) {}
  template <class T>
  T read() {
    if (data_.size() - position_ < sizeof(T)) fail("is truncated");
    T v;
    std::memcpy(&v, data_.data() + position_, sizeof(T));
    position_ += sizeof(T);
    return v;
  }
  std::string_view bytes(std::uint64_t n) {
    if (data_.size() - position_ < n) fail("is truncated");
    const std::string_view s = data_.substr(position_, static_cast<std::size_t>(n));
    position_ += static_cast<std::size_t>(n);
    return s;
  }
  std::size_t remaining() const { return data_.size() - position_; }
  [[noreturn]] void fail(const std::string& what) const { throw Error(ErrorKind::Format, context_ + " " + what); }

 private:
  std::string_view data_;
  std::size_t position_ = 0;
  std::string context_;
};

// ------------------------------------------------------------ models

int magnitude_bucket(std::int64_t value) {
  const std::uint64_t m = static_cast<std::uint64_t>(value < 0 ? -value : value);
  return m == 0 ? 0 : (m < 4 ? 1 : (m < 64 ? 2 : 3));
}

// Coefficient chunk contexts: significance flags by class and previous flag;
// components by class, component and the previous coefficient's magnitude.
struct ChunkModels {
  std::vector<std::array<Probability, 2>> flags;
  std::vector<IntegerModel> components;
  explicit ChunkModels(int classes)
      : flags(static_cast<std::size_t>(classes), {detail::kProbabilityHalf, detail::kProbabilityHalf}),
        components(static_cast<std::size_t>(classes) * 3 * 4) {}
  IntegerModel& component(int cls, int axis, int bucket) {
    return components[(static_cast<std::size_t>(cls) * 3 + static_cast<std::size_t>(axis)) * 4 + static_cast<std::size_t>(bucket)];
  }
};

struct BaseModels {
  IntegerModel face_size, first_index, other_index, sharp_gap;
};

// Neighbours of each base vertex with a smaller index: the decoded ones when
// base control points are decoded in index order.
std::vector<std::vector<std::uint32_t>> earlier_neighbours(const PolygonMesh& base) {
  std::vector<std::vector<std::uint32_t>> result(base.vertex_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t n = base.face_size(f);
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t a = base.face_begin(f)[k], b = base.face_begin(f)[(k + 1) % n];
      if (a < b) result[b].push_back(a);
      else result[a].push_back(b);
    }
  }
  for (auto& list : result) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return result;
}

using QuantizedVector = std::array<std::int64_t, 3>;

QuantizedVector predict_base(const std::vector<QuantizedVector>& q, const std::vector<std::uint32_t>& neighbours,
                             std::size_t index) {
  if (neighbours.empty()) return index == 0 ? QuantizedVector{0, 0, 0} : q[index - 1];
  QuantizedVector p{};
  for (int axis = 0; axis < 3; ++axis) {
    std::int64_t sum = 0;
    for (std::uint32_t n : neighbours) sum += q[n][axis];
    const auto count = static_cast<std::int64_t>(neighbours.size());
    p[axis] = sum >= 0 ? (sum + count / 2) / count : -((-sum + count / 2) / count);
  }
  return p;
}

double class_step(double step, const std::vector<double>& weights, int cls) {
  return step / weights[static_cast<std::size_t>(cls)];
}

// Importance of a non-zero quantized coefficient: class weight times the
// dequantized magnitude. Encoder and decoder compute it from the same integers
// and weights, so they agree exactly.
double importance_key(int cls, const QuantizedVector& q, double step, const std::vector<double>& weights) {
  const auto c = static_cast<std::size_t>(cls);
  const double s = step / weights[c];
  return weights[c] * norm(Vec3{q[0] * s, q[1] * s, q[2] * s});
}

struct RankedEntry {
  double key;
  std::uint32_t index;
  std::uint32_t position;  // in the caller's list before sorting
};

// Sorts by importance, ties by index: a strict total order, so the result
// does not depend on the method.
void sort_by_importance(std::vector<RankedEntry>& entries) {
  const auto by_index = [](const RankedEntry& a, const RankedEntry& b) { return a.index < b.index; };
  const bool positive_keys = std::all_of(entries.begin(), entries.end(), [](const RankedEntry& e) {
    return e.key > 0 && e.key <= std::numeric_limits<double>::max();
  });
  if (entries.size() < (1u << 16) || !positive_keys || !std::is_sorted(entries.begin(), entries.end(), by_index)) {
    tbb::parallel_sort(entries.begin(), entries.end(), [](const RankedEntry& a, const RankedEntry& b) {
      return a.key > b.key || (a.key == b.key && a.index < b.index);
    });
    return;
  }
  // Entries in index order, keys positive and finite, whose bit patterns
  // order as their values: a stable radix sort on the complemented bits
  // (largest first) keeps ties in index order, several times faster than
  // a comparison sort of millions of entries.
  constexpr int kDigitBits = 16;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  const auto digit = [](double key, int shift) {
    std::uint64_t bits;
    std::memcpy(&bits, &key, sizeof bits);
    return static_cast<std::size_t>((~bits >> shift) & (kBuckets - 1));
  };
  std::vector<RankedEntry> buffer(entries.size());
  std::vector<std::size_t> start(kBuckets);
  for (int shift = 0; shift < 64; shift += kDigitBits) {
    std::fill(start.begin(), start.end(), 0);
    for (const RankedEntry& e : entries) ++start[digit(e.key, shift)];
    if (start[digit(entries.front().key, shift)] == entries.size()) continue;  // one digit: nothing moves
    std::size_t sum = 0;
    for (std::size_t& count : start) sum += std::exchange(count, sum);
    for (const RankedEntry& e : entries) buffer[start[digit(e.key, shift)]++] = e;
    entries.swap(buffer);
  }
}

// Importance order of non-zero quantized coefficients (q holds every entry).
void rank_by_importance(const SubdivisionHierarchy& hierarchy, const std::vector<QuantizedVector>& q, double step,
                        const std::vector<double>& weights, std::vector<std::uint32_t>& indices) {
  std::vector<RankedEntry> keyed(indices.size());
  const CoefficientClasses classes(hierarchy);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, indices.size(), 1 << 14), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k)
      keyed[k] = {importance_key(classes.of(indices[k]), q[indices[k]], step, weights), indices[k], 0};
  });
  sort_by_importance(keyed);
  for (std::size_t k = 0; k < indices.size(); ++k) indices[k] = keyed[k].index;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Metadata lines are `key=value`, split at the first '=': a key loses its
// '=', both lose line breaks (to spaces).
std::string sanitize(const std::string& text, bool key) {
  std::string s = text;
  for (char& c : s)
    if (c == '\n' || c == '\r' || (key && c == '=')) c = ' ';
  return s;
}

}  // namespace

double IswMetadata::number(const std::string& key, double fallback) const {
  const auto it = values.find(key);
  if (it == values.end()) return fallback;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  return end && *end == '\0' && std::isfinite(v) ? v : fallback;
}

std::string IswMetadata::text(const std::string& key, const std::string& fallback) const {
  const auto it = values.find(key);
  return it == values.end() ? fallback : it->second;
}

// ================================================================ encoder

namespace {

// Every entry rounded, per component, to a multiple of its class's step; the
// one quantization both the encoder and quantize_coefficients() use.
constexpr std::size_t kParallelGrain = 1 << 14;

bool quantizable(double scaled) { return std::isfinite(scaled) && std::abs(scaled) <= 1e9; }

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
  rank_by_importance(hierarchy, q, step, weights, ranked);
  return ranked;
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

}  // namespace

std::vector<Vec3> quantize_coefficients(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                                        double step, const std::vector<double>& class_weights) {
  check_encode_arguments(hierarchy, coefficients, step, class_weights);
  return dequantize(hierarchy, quantize(hierarchy, coefficients, step, class_weights), step, class_weights);
}

IswDecoded expected_decode(const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, std::vector<Vec3> stored,
                          std::vector<std::uint32_t> ranked, const std::string& bytes, const std::string& name) {
  assert(hierarchy);
  IswDecodeOptions headers;
  headers.headers_only = true;
  headers.hierarchy = hierarchy;  // reused: the header decode builds none
  IswDecoded result = decode_isw(bytes, name, headers);
  if (result.hierarchy != hierarchy || stored.size() != hierarchy->fine_vertex_count() ||
      ranked.size() != result.coefficients_total)
    throw Error(ErrorKind::InvalidArgument, name + ": the file was not written from these coefficients");
  result.coefficients = std::move(stored);
  result.ranked = std::move(ranked);
  result.chunks_decoded = result.chunks_total;
  return result;
}

std::string encode_isw(const PolygonMesh& base, int levels, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options) {
  if (levels < 0 || levels > kMaxLevels)
    throw Error(ErrorKind::InvalidArgument, "levels must be in 0.." + std::to_string(kMaxLevels));
  return encode_isw(SubdivisionHierarchy(base, levels), coefficients, metadata, options);
}

std::string encode_isw(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options,
                       std::vector<std::uint32_t>* ranked_out) {
  const PolygonMesh& base = hierarchy.base();
  const int levels = hierarchy.levels();
  const std::vector<double> weights = options.class_weights.empty() ? wavelet_norms(hierarchy) : options.class_weights;
  check_encode_arguments(hierarchy, coefficients, options.step, weights);
  const int classes = coefficient_class_count(hierarchy);
  const std::size_t fine = hierarchy.fine_vertex_count();
  const std::size_t base_count = hierarchy.vertex_count(0);

  // Quantize every entry with its class's step; rank by importance.
  const std::vector<QuantizedVector> q = quantize(hierarchy, coefficients, options.step, weights);
  std::vector<std::uint32_t> ranked = ranked_nonzero(hierarchy, q, options.step, weights);

  // Chunk boundaries (cumulative ranks).
  std::vector<std::uint64_t> chunk_ends;
  for (double percent : options.chunk_percents) {
    const std::uint64_t end = std::min<std::uint64_t>(coefficients_for_percent(hierarchy, percent), ranked.size());
    if (end > 0 && (chunk_ends.empty() || end > chunk_ends.back())) chunk_ends.push_back(end);
  }
  if (chunk_ends.empty() || chunk_ends.back() < ranked.size()) chunk_ends.push_back(ranked.size());
  if (ranked.empty()) chunk_ends.clear();

  std::string out(kMagic, kMagic + 8);
  put_u16(out, kIswMajorVersion);
  put_u16(out, kIswMinorVersion);
  put_u32(out, 0);

  {  // META
    std::string text;
    for (const auto& [key, value] : metadata.values) text += sanitize(key, true) + "=" + sanitize(value, false) + "\n";
    put_section(out, "META", text);
  }
  {  // BASE
    std::string payload;
    put_u32(payload, static_cast<std::uint32_t>(base.vertex_count()));
    put_u32(payload, static_cast<std::uint32_t>(base.face_count()));
    put_u32(payload, static_cast<std::uint32_t>(base.face_vertices.size()));
    std::vector<std::uint32_t> sharp;
    for (std::size_t v = 0; v < base.vertex_count(); ++v)
      if (base.is_sharp(v)) sharp.push_back(static_cast<std::uint32_t>(v));
    put_u32(payload, static_cast<std::uint32_t>(sharp.size()));
    std::string coded;
    RangeEncoder rc(coded);
    BaseModels m;
    std::int64_t previous_first = 0;
    for (std::size_t f = 0; f < base.face_count(); ++f) {
      const std::uint32_t* face = base.face_begin(f);
      detail::encode_integer(rc, m.face_size, static_cast<std::int64_t>(base.face_size(f)) - 3);
      detail::encode_integer(rc, m.first_index, static_cast<std::int64_t>(face[0]) - previous_first);
      for (std::uint32_t k = 1; k < base.face_size(f); ++k)
        detail::encode_integer(rc, m.other_index, static_cast<std::int64_t>(face[k]) - static_cast<std::int64_t>(face[0]));
      previous_first = face[0];
    }
    std::int64_t previous_sharp = -1;
    for (std::uint32_t v : sharp) {
      detail::encode_integer(rc, m.sharp_gap, static_cast<std::int64_t>(v) - previous_sharp);
      previous_sharp = v;
    }
    rc.finish();
    put_u64(payload, coded.size());
    payload += coded;
    put_section(out, "BASE", payload);
  }
  {  // QUAN
    std::string payload;
    put_f64(payload, options.step);
    put_u32(payload, static_cast<std::uint32_t>(levels));
    put_u32(payload, static_cast<std::uint32_t>(classes));
    for (double w : weights) put_f64(payload, w);
    put_u64(payload, ranked.size());
    put_u32(payload, static_cast<std::uint32_t>(chunk_ends.size()));
    for (std::uint64_t end : chunk_ends) put_u64(payload, end);
    put_section(out, "QUAN", payload);
  }
  {  // BPTS
    std::string coded;
    RangeEncoder rc(coded);
    std::array<IntegerModel, 3> models;
    const auto neighbours = earlier_neighbours(base);
    for (std::size_t v = 0; v < base_count; ++v) {
      const QuantizedVector prediction = predict_base(q, neighbours[v], v);
      for (int axis = 0; axis < 3; ++axis) detail::encode_integer(rc, models[static_cast<std::size_t>(axis)], q[v][axis] - prediction[axis]);
    }
    rc.finish();
    std::string payload;
    put_u64(payload, coded.size());
    payload += coded;
    put_section(out, "BPTS", payload);
  }
  // CHNK: flags over the not-yet-significant coefficients in index order.
  // A coefficient is significant before chunk k when its rank precedes the
  // chunk's first, so every chunk is coded on its own, in parallel.
  std::vector<std::uint32_t> rank_of;
  reserve_fresh_on_huge_pages(rank_of, fine);
  rank_of.assign(fine, UINT32_MAX);
  for (std::size_t r = 0; r < ranked.size(); ++r) rank_of[ranked[r]] = static_cast<std::uint32_t>(r);
  const auto encode_chunk = [&](std::size_t chunk) {
    const std::uint64_t begin = chunk == 0 ? 0 : chunk_ends[chunk - 1], end = chunk_ends[chunk];
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
          detail::encode_integer(rc, models.component(c, axis, previous_bucket[static_cast<std::size_t>(axis)]), q[i][axis]);
          previous_bucket[static_cast<std::size_t>(axis)] = magnitude_bucket(q[i][axis]);
        }
      }
    }
    rc.finish();
    std::string payload;
    put_u32(payload, static_cast<std::uint32_t>(chunk));
    put_u64(payload, begin);
    put_u64(payload, end);
    put_u64(payload, coded.size());
    payload += coded;
    std::string section;
    put_section(section, "CHNK", payload);
    return section;
  };
  std::vector<std::string> chunk_sections(chunk_ends.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunk_ends.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t chunk = r.begin(); chunk < r.end(); ++chunk) chunk_sections[chunk] = encode_chunk(chunk);
                    },
                    tbb::simple_partitioner());
  for (std::string& section : chunk_sections) {
    out += section;
    std::string().swap(section);
  }
  put_section(out, "END ", std::string());
  if (ranked_out) *ranked_out = std::move(ranked);
  return out;
}

// ================================================================ decoder

namespace {

// The coefficient classes of the hierarchy a file's base mesh and level
// count make, from the counts alone (see CoefficientClasses). Above 2^53 the
// counts are inexact (hostile files); the caller rejects such sizes.
CoefficientClasses classes_from_counts(const PolygonMesh& base, std::size_t base_edges, int levels) {
  const std::vector<LevelCounts> counts = refinement_counts(level_counts(base, base_edges), levels);
  const auto exact = [](double v) { return v < 9e15 ? static_cast<std::size_t>(v) : std::size_t{1} << 53; };
  std::array<std::size_t, SubdivisionHierarchy::kMaxLevels + 1> vertex_counts{};
  std::array<std::size_t, SubdivisionHierarchy::kMaxLevels> parent_faces{};
  for (int l = 0; l <= levels; ++l) vertex_counts[static_cast<std::size_t>(l)] = exact(counts[static_cast<std::size_t>(l)].vertices);
  for (int l = 1; l <= levels; ++l) parent_faces[static_cast<std::size_t>(l - 1)] = exact(counts[static_cast<std::size_t>(l - 1)].faces);
  return CoefficientClasses(vertex_counts.data(), parent_faces.data(), levels);
}

// Builds the subdivision hierarchy on a TBB thread while the caller decodes
// the coefficient chunks; get() waits for it and rethrows its error, as a
// format error of the file (`context` names it) when the base mesh is one the
// hierarchy cannot take.
class HierarchyBuild {
 public:
  HierarchyBuild() = default;
  HierarchyBuild(const HierarchyBuild&) = delete;
  HierarchyBuild& operator=(const HierarchyBuild&) = delete;
  ~HierarchyBuild() { wait(); }

  void start(const PolygonMesh& base, int levels, const std::string& context) {
    // Its own copy of the topology: the caller goes on writing base positions.
    PolygonMesh topology;
    topology.face_offsets = base.face_offsets;
    topology.face_vertices = base.face_vertices;
    topology.sharp = base.sharp;
    topology.positions.resize(base.vertex_count());
    started_ = true;
    group_.run([this, topology = std::move(topology), levels, context] {
      const auto start = std::chrono::steady_clock::now();
      try {
        hierarchy_ = std::make_shared<const SubdivisionHierarchy>(topology, levels);
      } catch (const Error& error) {
        error_ = std::make_exception_ptr(Error(ErrorKind::Format, context + error.what()));
      } catch (...) {
        error_ = std::current_exception();
      }
      seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    });
  }
  bool started() const { return started_; }
  double seconds() const { return seconds_; }  // the build's own duration, once waited for
  std::shared_ptr<const SubdivisionHierarchy> get() {
    wait();
    if (error_) std::rethrow_exception(error_);
    return hierarchy_;
  }
  // Rethrows the build's error, if any: it takes precedence over errors found
  // meanwhile in later sections, as when the build came first.
  void rethrow_error() {
    wait();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void wait() {
    if (!started_ || waited_) return;
    waited_ = true;
    group_.wait();  // the task catches everything, so this does not throw
  }

  tbb::task_group group_;
  bool started_ = false, waited_ = false;
  std::shared_ptr<const SubdivisionHierarchy> hierarchy_;
  std::exception_ptr error_;
  double seconds_ = 0;
};

}  // namespace

IswDecoded decode_isw(const std::string& bytes, const std::string& name, const IswDecodeOptions& options) {
  const auto decode_start = std::chrono::steady_clock::now();
  IswDecoded result;
  if (bytes.empty()) throw Error(ErrorKind::Format, name + ": empty file, not an isowave .isw file");
  if (std::memcmp(bytes.data(), kMagic, std::min<std::size_t>(8, bytes.size())) != 0)
    throw Error(ErrorKind::Format, name + ": not an isowave .isw file (bad magic)");
  if (bytes.size() < kHeaderBytes)
    throw Error(ErrorKind::Format, name + ": truncated inside the file header (" + std::to_string(bytes.size()) +
                                       " of " + std::to_string(kHeaderBytes) + " bytes)");
  std::uint16_t major = 0, minor = 0;
  std::uint32_t reserved = 0;
  std::memcpy(&major, bytes.data() + 8, 2);
  std::memcpy(&minor, bytes.data() + 10, 2);
  std::memcpy(&reserved, bytes.data() + 12, 4);
  if (major != kIswMajorVersion)
    throw Error(ErrorKind::Unsupported, name + ": .isw format version " + std::to_string(major) + "." +
                                            std::to_string(minor) + " is not supported (this build reads " +
                                            std::to_string(kIswMajorVersion) + ".x)");
  if (reserved != 0) throw Error(ErrorKind::Format, name + ": corrupt file header (reserved field is not zero)");
  result.major_version = major;
  result.minor_version = minor;

  std::size_t position = kHeaderBytes;
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  // The hierarchy is built during the chunk decoding, which needs only its
  // counts (the layout).
  HierarchyBuild build;
  std::optional<CoefficientClasses> layout;
  std::uint64_t limit = options.max_coefficients;
  // Quantized base control points (the prediction reads them), then the
  // decoded wavelet coefficients' values in rank order, parallel to
  // result.ranked: at a few percent only a few of the fine entries.
  std::vector<QuantizedVector> base_q;
  std::vector<QuantizedVector> ranked_q;
  std::vector<std::uint8_t> significant;
  std::vector<std::uint64_t> chunk_ends;
  std::uint64_t nonzero_total = 0;
  static constexpr const char* expected_order[] = {"META", "BASE", "QUAN", "BPTS"};
  static constexpr std::string_view kKnownTags[] = {"META", "BASE", "QUAN", "BPTS", "CHNK", "END "};
  std::size_t section_index = 0;
  bool saw_end = false;

  try {
    while (position < bytes.size()) {
      if (bytes.size() - position < kSectionHeader) {
        if (section_index >= 4) {
          result.truncated = true;
          break;
        }
        throw Error(ErrorKind::Format, name + ": truncated inside the header of section " +
                                           expected_order[section_index] + " (at byte " + std::to_string(position) + ")");
      }
      const std::string tag = bytes.substr(position, 4);
      std::uint64_t size = 0;
      std::uint32_t stored_header_crc = 0;
      std::memcpy(&size, bytes.data() + position + 4, 8);
      std::memcpy(&stored_header_crc, bytes.data() + position + 12, 4);
      const std::string where = name + ": section " + tag + " (at byte " + std::to_string(position) + ")";
      if (header_crc(tag.c_str(), size) != stored_header_crc)
        throw Error(ErrorKind::Format, where + ": corrupt section header (CRC mismatch)");
      // A section this reader does not know comes from a later minor version:
      // checked like the others, then skipped.
      const bool known_tag = std::find(std::begin(kKnownTags), std::end(kKnownTags), tag) != std::end(kKnownTags);
      if (known_tag && section_index < 4 && tag != expected_order[section_index])
        throw Error(ErrorKind::Format, where + ": expected section " + expected_order[section_index]);
      if (known_tag && section_index >= 4 && tag != "CHNK" && tag != "END ")
        throw Error(ErrorKind::Format, where + ": section out of order");
      if (size > bytes.size() - position - kSectionHeader || bytes.size() - position - kSectionHeader - size < 4) {
        if (tag == "CHNK" || tag == "END " || (!known_tag && section_index >= 4)) {
          result.truncated = true;
          break;
        }
        throw Error(ErrorKind::Format, where + " is truncated");
      }
      const std::string_view payload = std::string_view(bytes).substr(position + kSectionHeader, static_cast<std::size_t>(size));
      std::uint32_t stored_crc = 0;
      std::memcpy(&stored_crc, bytes.data() + position + kSectionHeader + size, 4);
      if (crc_of(tag.c_str(), payload) != stored_crc) throw Error(ErrorKind::Format, where + " is corrupt (CRC mismatch)");
      IswSectionInfo info{tag, position, size + kSectionOverhead, 0};
      position += static_cast<std::size_t>(size) + kSectionOverhead;
      if (!known_tag) {
        result.sections.push_back(info);
        continue;
      }
      PayloadReader reader(payload, where);
      ++section_index;

      if (tag == "META") {
        std::size_t start = 0;
        while (start < payload.size()) {
          std::size_t end = payload.find('\n', start);
          if (end == std::string::npos) end = payload.size();
          const std::string line(payload.substr(start, end - start));
          const std::size_t eq = line.find('=');
          if (eq != std::string::npos) result.metadata.values[line.substr(0, eq)] = line.substr(eq + 1);
          start = end + 1;
        }
      } else if (tag == "BASE") {
        const auto vertices = reader.read<std::uint32_t>();
        const auto faces = reader.read<std::uint32_t>();
        const auto corners = reader.read<std::uint32_t>();
        const auto sharp_count = reader.read<std::uint32_t>();
        const auto coded_size = reader.read<std::uint64_t>();
        if (coded_size != reader.remaining()) reader.fail("has an inconsistent size");
        const std::uint64_t integer_budget = kMaxIntegersPerCodedByte * (coded_size + 16);
        if (faces == 0 || corners < 3ull * faces || vertices > corners || sharp_count > vertices ||
            std::uint64_t{corners} + faces + sharp_count > integer_budget)
          reader.fail("has impossible counts");
        const std::string_view coded = reader.bytes(coded_size);
        RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(coded.data()), coded.size());
        BaseModels m;
        PolygonMesh& base = result.base;
        base.positions.assign(vertices, Vec3{});
        base.face_offsets.reserve(std::size_t{faces} + 1);
        base.face_vertices.reserve(corners);
        std::int64_t previous_first = 0;
        std::vector<std::uint32_t> face;
        for (std::uint32_t f = 0; f < faces; ++f) {
          const std::int64_t size_code = detail::decode_integer(rc, m.face_size);
          if (size_code < 0 || base.face_vertices.size() + 3 + static_cast<std::uint64_t>(size_code) > corners)
            reader.fail("has an invalid face size");
          face.assign(static_cast<std::size_t>(size_code + 3), 0);
          const std::int64_t first = previous_first + detail::decode_integer(rc, m.first_index);
          for (std::size_t k = 0; k < face.size(); ++k) {
            const std::int64_t index = k == 0 ? first : first + detail::decode_integer(rc, m.other_index);
            if (index < 0 || index >= vertices) reader.fail("has a vertex index out of range");
            face[k] = static_cast<std::uint32_t>(index);
          }
          previous_first = first;
          base.add_face(face.data(), face.size());
        }
        if (base.face_vertices.size() != corners) reader.fail("has an inconsistent corner count");
        if (sharp_count > 0) base.sharp.assign(vertices, 0);
        std::int64_t previous_sharp = -1;
        for (std::uint32_t s = 0; s < sharp_count; ++s) {
          const std::int64_t v = previous_sharp + detail::decode_integer(rc, m.sharp_gap);
          if (v <= previous_sharp || v >= vertices) reader.fail("has an invalid sharp vertex");
          base.sharp[static_cast<std::size_t>(v)] = 1;
          previous_sharp = v;
        }
        if (rc.overran()) reader.fail("is corrupt (coded data ends early)");
        try {
          require_manifold(base, "base mesh");
        } catch (const Error& error) {
          reader.fail(std::string("holds an invalid base mesh: ") + error.what());
        }
      } else if (tag == "QUAN") {
        result.step = reader.read<double>();
        const auto levels = reader.read<std::uint32_t>();
        const auto classes = reader.read<std::uint32_t>();
        if (!(result.step > 0) || !std::isfinite(result.step)) reader.fail("has an invalid quantization step");
        if (levels > kMaxLevels || classes != 1 + 2 * levels) reader.fail("has an invalid level count");
        result.levels = static_cast<int>(levels);
        for (std::uint32_t c = 0; c < classes; ++c) {
          const double w = reader.read<double>();
          if (!(w > 0) || !std::isfinite(w)) reader.fail("has an invalid class weight");
          result.class_weights.push_back(w);
        }
        nonzero_total = reader.read<std::uint64_t>();
        const auto chunks = reader.read<std::uint32_t>();
        if (chunks > reader.remaining() / 8) reader.fail("has an impossible chunk count");
        std::uint64_t previous = 0;
        for (std::uint32_t c = 0; c < chunks; ++c) {
          const auto end = reader.read<std::uint64_t>();
          if (end <= previous || end > nonzero_total) reader.fail("has invalid chunk boundaries");
          chunk_ends.push_back(end);
          previous = end;
        }
        if (!chunk_ends.empty() && chunk_ends.back() != nonzero_total) reader.fail("has invalid chunk boundaries");
        result.chunks_total = chunks;
        result.coefficients_total = nonzero_total;
        // The hierarchy (and so the fine vertex count) follows from the base
        // mesh and the levels; bound it by the file size before building it.
        const auto justified = [&](const CoefficientClasses& counts) {
          const double estimate = static_cast<double>(counts.fine());
          return estimate <= static_cast<double>(kMaxFineVertices) &&
                 estimate <= static_cast<double>(kFineVerticesPerFileByte * bytes.size() + (1u << 20));
        };
        const SubdivisionHierarchy* known = options.hierarchy.get();
        const bool reuse = known && known->levels() == result.levels &&
                           known->base().face_offsets == result.base.face_offsets &&
                           known->base().face_vertices == result.base.face_vertices &&
                           known->base().sharp_count() == result.base.sharp_count() &&
                           (result.base.sharp_count() == 0 || known->base().sharp == result.base.sharp);
        result.seconds.headers = seconds_since(decode_start);
        // With every corner counted as an edge the estimate can only grow: if
        // even that is justified, the build starts before the exact edge count.
        const bool early = !reuse && justified(classes_from_counts(result.base, result.base.face_vertices.size(), result.levels));
        const std::string build_context = name + ": section BASE holds a base mesh the subdivision hierarchy cannot take: ";
        if (early) build.start(result.base, result.levels, build_context);
        layout.emplace(classes_from_counts(result.base, summarize_topology(result.base).edges, result.levels));
        if (!justified(*layout)) reader.fail("describes a hierarchy larger than the file can justify");
        if (reuse) hierarchy = options.hierarchy;
        else if (!early) build.start(result.base, result.levels, build_context);
        const std::size_t base_count = layout->base();
        limit = std::min<std::uint64_t>(limit, coefficients_for_percent(layout->fine(), base_count, options.max_percent));
        if (nonzero_total > layout->fine() - base_count) reader.fail("claims more coefficients than the hierarchy has");
      } else if (tag == "BPTS") {
        const auto coded_size = reader.read<std::uint64_t>();
        if (coded_size != reader.remaining()) reader.fail("has an inconsistent size");
        if (3ull * result.base.vertex_count() > kMaxIntegersPerCodedByte * (coded_size + 16)) reader.fail("is too short");
        const std::string_view coded = reader.bytes(coded_size);
        RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(coded.data()), coded.size());
        base_q.assign(result.base.vertex_count(), QuantizedVector{0, 0, 0});
        std::array<IntegerModel, 3> models;
        const auto neighbours = earlier_neighbours(result.base);
        const double s = class_step(result.step, result.class_weights, 0);
        for (std::size_t v = 0; v < result.base.vertex_count(); ++v) {
          const QuantizedVector prediction = predict_base(base_q, neighbours[v], v);
          for (int axis = 0; axis < 3; ++axis) {
            base_q[v][axis] = prediction[axis] + detail::decode_integer(rc, models[static_cast<std::size_t>(axis)]);
            if (std::abs(base_q[v][axis]) > (1ll << 40)) reader.fail("holds an impossible value");
          }
          result.base.positions[v] = {base_q[v][0] * s, base_q[v][1] * s, base_q[v][2] * s};
        }
        if (rc.overran()) reader.fail("is corrupt (coded data ends early)");
        if (options.headers_only) {
          if (build.started()) hierarchy = build.get();
          result.hierarchy = hierarchy;
          result.sections.push_back(info);
          // List the remaining sections without decoding them.
          while (position + kSectionHeader <= bytes.size()) {
            std::uint64_t next_size = 0;
            std::memcpy(&next_size, bytes.data() + position + 4, 8);
            IswSectionInfo next{bytes.substr(position, 4), position, 0, 0};
            if (next_size > bytes.size() - position - kSectionHeader ||
                bytes.size() - position - kSectionHeader - next_size < 4) {
              result.truncated = true;
              break;
            }
            next.bytes = next_size + kSectionOverhead;
            if (next.tag == "CHNK" && next_size >= 20) {
              std::uint64_t b = 0, e = 0;
              std::memcpy(&b, bytes.data() + position + kSectionHeader + 4, 8);
              std::memcpy(&e, bytes.data() + position + kSectionHeader + 12, 8);
              next.coefficients = e >= b ? e - b : 0;
            }
            result.sections.push_back(next);
            position += static_cast<std::size_t>(next.bytes);
          }
          // As the full decode says it: a file without its END is truncated.
          if (result.sections.back().tag != "END ") result.truncated = true;
          if (result.truncated)
            result.truncation_note = "file is truncated after byte " + std::to_string(position) + " of " +
                                     std::to_string(bytes.size()) + " (not checked further: headers only)";
          return result;
        }
        reserve_fresh_on_huge_pages(significant, layout->fine());
        significant.assign(layout->fine(), 0);
      } else if (tag == "CHNK") {
        const auto chunk_start = std::chrono::steady_clock::now();
        const auto chunk = reader.read<std::uint32_t>();
        const auto begin = reader.read<std::uint64_t>();
        const auto end = reader.read<std::uint64_t>();
        const auto coded_size = reader.read<std::uint64_t>();
        if (chunk != result.chunks_decoded || chunk >= chunk_ends.size() || end != chunk_ends[chunk] ||
            begin != (chunk == 0 ? 0 : chunk_ends[chunk - 1]))
          reader.fail("is out of order or inconsistent with QUAN");
        if (coded_size != reader.remaining()) reader.fail("has an inconsistent size");
        const std::string_view coded = reader.bytes(coded_size);
        RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(coded.data()), coded.size());
        const int classes = layout->count();
        ChunkModels models(classes);
        std::uint64_t found = 0;
        std::vector<std::uint32_t> fresh;
        std::vector<QuantizedVector> fresh_q;
        for (int c = 1; c < classes; ++c) {
          const auto [first, last] = layout->range(c);
          int previous_flag = 0;
          std::array<int, 3> previous_bucket{0, 0, 0};
          // The two flag contexts as locals, so that they stay in registers
          // through the millions of flags (the same arithmetic as in memory).
          Probability flag_after_zero = models.flags[static_cast<std::size_t>(c)][0];
          Probability flag_after_one = models.flags[static_cast<std::size_t>(c)][1];
          for (std::size_t i = first; i < last; ++i) {
            if (significant[i]) continue;
            // A flag costs at least 0.02 bits (the models saturate), so a
            // stream that ran out is found within a bounded amount of work:
            // a hostile chunk cannot make the scan outlast its bytes.
            if ((i & 0xFFFF) == 0 && rc.overran()) reader.fail("is corrupt (coded data ends early)");
            const int flag = previous_flag ? rc.decode_bit(flag_after_one) : rc.decode_bit(flag_after_zero);
            previous_flag = flag;
            if (!flag) continue;
            if (++found > end - begin) reader.fail("holds more coefficients than it declares");
            significant[i] = 1;
            QuantizedVector value;
            for (int axis = 0; axis < 3; ++axis) {
              value[axis] = detail::decode_integer(rc, models.component(c, axis, previous_bucket[static_cast<std::size_t>(axis)]));
              previous_bucket[static_cast<std::size_t>(axis)] = magnitude_bucket(value[axis]);
            }
            if (value[0] == 0 && value[1] == 0 && value[2] == 0) reader.fail("holds a zero coefficient");
            fresh.push_back(static_cast<std::uint32_t>(i));
            fresh_q.push_back(value);
          }
          models.flags[static_cast<std::size_t>(c)] = {flag_after_zero, flag_after_one};
        }
        if (found != end - begin) reader.fail("holds fewer coefficients than it declares");
        if (rc.overran()) reader.fail("is corrupt (coded data ends early)");
        result.seconds.chunks += seconds_since(chunk_start);
        const auto rank_start = std::chrono::steady_clock::now();
        // Rank the new coefficients as the encoder did.
        std::vector<RankedEntry> keyed(fresh.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fresh.size(), kParallelGrain),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                            for (std::size_t k = r.begin(); k < r.end(); ++k)
                              keyed[k] = {importance_key(layout->of(fresh[k]), fresh_q[k], result.step,
                                                         result.class_weights),
                                          fresh[k], static_cast<std::uint32_t>(k)};
                          });
        sort_by_importance(keyed);
        for (const RankedEntry& entry : keyed) {
          result.ranked.push_back(entry.index);
          ranked_q.push_back(fresh_q[entry.position]);
        }
        result.seconds.rank += seconds_since(rank_start);
        info.coefficients = end - begin;
        ++result.chunks_decoded;
        result.sections.push_back(info);
        // Stop at the limit, but read END after the last chunk.
        if (result.ranked.size() >= limit && result.chunks_decoded < result.chunks_total) break;
        continue;
      } else if (tag == "END ") {
        if (result.chunks_decoded != result.chunks_total) throw Error(ErrorKind::Format, where + ": chunks are missing");
        saw_end = true;
        result.sections.push_back(info);
        break;
      }
      result.sections.push_back(info);
    }
    if (section_index < 4)
      throw Error(ErrorKind::Format, name + ": truncated before section " + expected_order[section_index] + " (at byte " +
                                         std::to_string(position) + ")");
  } catch (...) {
    build.rethrow_error();
    throw;
  }
  if (build.started()) {
    const auto wait_start = std::chrono::steady_clock::now();
    hierarchy = build.get();
    result.seconds.hierarchy_wait = seconds_since(wait_start);
    result.seconds.hierarchy = build.seconds();
  }
  assert(*layout == CoefficientClasses(*hierarchy));
  result.hierarchy = hierarchy;
  const bool stopped_early = result.ranked.size() >= limit && result.chunks_decoded < result.chunks_total;
  if (!saw_end && !stopped_early) result.truncated = true;
  if (result.truncated)
    result.truncation_note = result.chunks_decoded < result.chunks_total
                                 ? "file is truncated inside the coefficient stream: decoded " +
                                       std::to_string(result.chunks_decoded) + " of " +
                                       std::to_string(result.chunks_total) + " chunks (" +
                                       std::to_string(result.ranked.size()) + " of " +
                                       std::to_string(result.coefficients_total) + " coefficients)"
                                 : "file ends before its END section (all coefficient chunks were decoded)";

  const auto dequantize_start = std::chrono::steady_clock::now();
  // The coarse-to-fine array: zero except the base control points and the
  // coefficients kept.
  if (result.ranked.size() > limit) result.ranked.resize(static_cast<std::size_t>(limit));
  const std::size_t fine = layout->fine();
  reserve_fresh_on_huge_pages(result.coefficients, fine);
  result.coefficients.resize(fine);
  std::copy(result.base.positions.begin(), result.base.positions.end(), result.coefficients.begin());
  for (std::size_t r = 0; r < result.ranked.size(); ++r) {
    const std::uint32_t i = result.ranked[r];
    const double s = class_step(result.step, result.class_weights, layout->of(i));
    result.coefficients[i] = {ranked_q[r][0] * s, ranked_q[r][1] * s, ranked_q[r][2] * s};
  }
  result.seconds.dequantize = seconds_since(dequantize_start);
  return result;
}

IswDecoded read_isw(const std::string& path, const IswDecodeOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::string bytes = read_file_bytes(path);
  const double read_seconds = seconds_since(start);
  IswDecoded result = decode_isw(bytes, path, options);
  result.seconds.read = read_seconds;
  return result;
}

void write_isw(const std::string& path, const std::string& bytes, bool overwrite) {
  AtomicFileWriter file(path, overwrite);
  file.write(bytes);
  file.commit();
}

}  // namespace isowave
