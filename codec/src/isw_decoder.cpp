// The .isw decoder: one function per section (docs/FORMAT.md), and a driver
// that reads them in order. Every count is checked against the bytes present
// before anything is allocated, and every loop is bounded by the bytes it
// reads, so hostile files cost time linear in their size.
#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <functional>
#include <optional>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/patch_hierarchy.h"
#include "isw2_layout.h"
#include "isw_headers.h"
#include "isw_models.h"
#include "isw_sections.h"

namespace isowave {

using namespace detail;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

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
      const auto start = Clock::now();
      try {
        hierarchy_ = std::make_shared<const SubdivisionHierarchy>(topology, levels);
      } catch (const Error& error) {
        error_ = std::make_exception_ptr(Error(ErrorKind::Format, context + error.what()));
      } catch (...) {
        error_ = std::current_exception();
      }
      seconds_ = seconds_since(start);
    });
  }
  bool started() const { return started_; }
  double seconds() const { return seconds_; }  // the build's own duration, once waited for
  std::shared_ptr<const SubdivisionHierarchy> get() {
    rethrow_error();
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

// What the sections hand on to later ones.
struct DecodeState {
  DecodeState(const std::string& file_bytes, const std::string& file_name, const IswDecodeOptions& decode_options)
      : bytes(file_bytes), name(file_name), options(decode_options), limit(decode_options.max_coefficients) {}

  const std::string& bytes;
  const std::string& name;
  const IswDecodeOptions& options;
  const Clock::time_point start = Clock::now();
  IswDecoded result;
  // The hierarchy is built during the chunk decoding, which needs only its
  // counts (the layout).
  HierarchyBuild build;
  std::string build_context;  // heads the build's errors
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  // A region or view decode of a 2.2 file over a patch instead of the whole
  // hierarchy (built after all when the file ends before PLNS).
  bool patch = false;
  std::optional<BaseIncidence> incidence;  // the patch's: the base's edges, numbered
  std::optional<CoefficientClasses> layout;
  std::uint64_t limit;  // ranked coefficients wanted
  std::vector<std::uint64_t> chunk_ends;
  // Quantized base control points (the prediction reads them), then the
  // decoded wavelet coefficients' values in rank order, parallel to
  // result.ranked: at a few percent only a few of the fine entries.
  std::vector<QuantizedVector> base_q;
  std::vector<QuantizedVector> ranked_q;
  std::vector<std::uint8_t> significant;  // per fine entry: sent by an earlier chunk
  bool saw_end = false;
  int major = 1;
  V2Scales scales;  // version 2
  std::optional<GroupIndex> group_index;  // version 2.2
  bool saw_plane_counts = false;          // PCNT (result.stream.plane_counts)
  // A file read in part: its bytes past `bytes`, and its size.
  std::function<std::string(std::uint64_t, std::uint64_t)> fetch;
  std::uint64_t file_size = 0;
};

// ------------------------------------------------------------ QUAN

void decode_quantization(PayloadReader& reader, DecodeState& state) {
  IswDecoded& result = state.result;
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
  result.coefficients_total = reader.read<std::uint64_t>();
  const auto chunks = reader.read<std::uint32_t>();
  if (chunks > reader.remaining() / 8) reader.fail("has an impossible chunk count");
  std::uint64_t previous = 0;
  for (std::uint32_t c = 0; c < chunks; ++c) {
    const auto end = reader.read<std::uint64_t>();
    if (end <= previous || end > result.coefficients_total) reader.fail("has invalid chunk boundaries");
    state.chunk_ends.push_back(end);
    previous = end;
  }
  if (!state.chunk_ends.empty() && state.chunk_ends.back() != result.coefficients_total)
    reader.fail("has invalid chunk boundaries");
  result.chunks_total = chunks;
}

void decode_quantization_v2(PayloadReader& reader, DecodeState& state) {
  IswDecoded& result = state.result;
  V2Scales& scales = state.scales;
  scales.step = result.step = reader.read<double>();
  scales.frame_step = reader.read<double>();
  scales.tangential_factor = reader.read<double>();
  const auto levels = reader.read<std::uint32_t>();
  const auto classes = reader.read<std::uint32_t>();
  const auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  if (!positive(scales.step) || !positive(scales.frame_step)) reader.fail("has an invalid quantization step");
  if (!(scales.tangential_factor >= 1) || !std::isfinite(scales.tangential_factor))
    reader.fail("has an invalid tangential factor");
  if (levels > kMaxLevels || classes != 1 + 2 * levels) reader.fail("has an invalid level count");
  result.levels = static_cast<int>(levels);
  for (std::uint32_t c = 0; c < classes; ++c) {
    const double w = reader.read<double>();
    if (!positive(w)) reader.fail("has an invalid class weight");
    result.class_weights.push_back(w);
  }
  scales.weights = result.class_weights;
  result.coefficients_total = reader.read<std::uint64_t>();
  result.stream.tangential_factor = scales.tangential_factor;
  result.stream.frame_step = scales.frame_step;
}

// Runs `work` on the base mesh (a check of its topology, or its
// incidences); an Error it throws becomes Error(Format) headed by `context`,
// as the hierarchy's build reports a base it cannot take.
template <class Work>
void on_base(const std::string& context, Work&& work) {
  try {
    work();
  } catch (const Error& error) {
    throw Error(ErrorKind::Format, context + error.what());
  }
}

// After QUAN: lays out the coefficient classes, bounds the hierarchy by the
// file size and starts building it (or takes options.hierarchy when it is the
// file's), and sets the coefficient limit.
void plan_hierarchy(PayloadReader& reader, DecodeState& state) {
  IswDecoded& result = state.result;
  const auto justified = [&](const CoefficientClasses& counts) {
    const double estimate = static_cast<double>(counts.fine());
    return estimate <= static_cast<double>(kMaxFineVertices) &&
           estimate <= static_cast<double>(kFineVerticesPerFileByte * state.bytes.size() + (1u << 20));
  };
  const SubdivisionHierarchy* known = state.options.hierarchy.get();
  const bool reuse = known && known->levels() == result.levels &&
                     known->base().face_offsets == result.base.face_offsets &&
                     known->base().face_vertices == result.base.face_vertices &&
                     known->base().sharp_count() == result.base.sharp_count() &&
                     (result.base.sharp_count() == 0 || known->base().sharp == result.base.sharp);
  result.seconds.headers = seconds_since(state.start);
  // With every corner counted as an edge the estimate can only grow: if
  // even that is justified, the build starts before the exact edge count.
  const IswDecodeOptions& o = state.options;
  const bool local = o.region || (o.frustum && o.view_scope == IswDecodeOptions::ViewScope::Patch);
  state.patch = local && state.major == 2 && result.minor_version >= 2 && !reuse;
  // The headers alone need the base mesh's topology checked, not refined.
  const bool refine = !reuse && !state.patch && !o.headers_only;
  const bool early = refine &&
                     justified(classes_from_counts(result.base, result.base.face_vertices.size(), result.levels));
  state.build_context = state.name + ": section BASE holds a base mesh the subdivision hierarchy cannot take: ";
  if (early) state.build.start(result.base, result.levels, state.build_context);
  if (state.patch) on_base(state.build_context, [&] { state.incidence = base_incidence(result.base); });
  const std::size_t edges = state.patch ? state.incidence->edge_count() : summarize_topology(result.base).edges;
  state.layout.emplace(classes_from_counts(result.base, edges, result.levels));
  if (!justified(*state.layout)) reader.fail("describes a hierarchy larger than the file can justify");
  result.fine_vertices = state.layout->fine();
  result.base_vertices = state.layout->base();
  if (reuse) state.hierarchy = state.options.hierarchy;
  else if (refine && !early) state.build.start(result.base, result.levels, state.build_context);
  else if (o.headers_only) on_base(state.build_context, [&] { require_manifold(result.base, "base mesh"); });
  const std::size_t base_count = state.layout->base();
  state.limit = std::min<std::uint64_t>(
      state.limit, coefficients_for_percent(state.layout->fine(), base_count, state.options.max_percent));
  if (result.coefficients_total > state.layout->fine() - base_count)
    reader.fail("claims more coefficients than the hierarchy has");
}

// ------------------------------------------------------------ CHNK

struct ChunkCoefficients {
  std::vector<std::uint32_t> indices;   // in index order
  std::vector<QuantizedVector> values;  // parallel to indices
};

// The significance flags and components of one chunk's `count` coefficients,
// from the `coded_size` bytes left in `reader`.
ChunkCoefficients decode_chunk_coefficients(PayloadReader& reader, DecodeState& state, std::uint64_t coded_size,
                                            std::uint64_t count) {
  if (coded_size != reader.remaining()) reader.fail("has an inconsistent size");
  const std::string_view coded = reader.bytes(coded_size);
  RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(coded.data()), coded.size());
  const int classes = state.layout->count();
  ChunkModels models(classes);
  ChunkCoefficients fresh;
  std::uint64_t found = 0;
  for (int c = 1; c < classes; ++c) {
    const auto [first, last] = state.layout->range(c);
    int previous_flag = 0;
    std::array<int, 3> previous_bucket{0, 0, 0};
    // The two flag contexts as locals, so that they stay in registers
    // through the millions of flags (the same arithmetic as in memory).
    Probability flag_after_zero = models.flags[static_cast<std::size_t>(c)][0];
    Probability flag_after_one = models.flags[static_cast<std::size_t>(c)][1];
    for (std::size_t i = first; i < last; ++i) {
      if (state.significant[i]) continue;
      // A flag costs at least 0.02 bits (the models saturate), so a
      // stream that ran out is found within a bounded amount of work:
      // a hostile chunk cannot make the scan outlast its bytes.
      if ((i & 0xFFFF) == 0 && rc.overran()) reader.fail("is corrupt (coded data ends early)");
      const int flag = previous_flag ? rc.decode_bit(flag_after_one) : rc.decode_bit(flag_after_zero);
      previous_flag = flag;
      if (!flag) continue;
      if (++found > count) reader.fail("holds more coefficients than it declares");
      state.significant[i] = 1;
      QuantizedVector value;
      for (int axis = 0; axis < 3; ++axis) {
        value[axis] = decode_integer(rc, models.component(c, axis, previous_bucket[static_cast<std::size_t>(axis)]));
        previous_bucket[static_cast<std::size_t>(axis)] = magnitude_bucket(value[axis]);
      }
      if (value[0] == 0 && value[1] == 0 && value[2] == 0) reader.fail("holds a zero coefficient");
      fresh.indices.push_back(static_cast<std::uint32_t>(i));
      fresh.values.push_back(value);
    }
    models.flags[static_cast<std::size_t>(c)] = {flag_after_zero, flag_after_one};
  }
  if (found != count) reader.fail("holds fewer coefficients than it declares");
  if (rc.overran()) reader.fail("is corrupt (coded data ends early)");
  return fresh;
}

// Appends a chunk's coefficients to the ranked lists in the encoder's order.
void rank_chunk(const ChunkCoefficients& fresh, DecodeState& state) {
  IswDecoded& result = state.result;
  std::vector<RankedEntry> keyed(fresh.indices.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, keyed.size(), kParallelGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k < r.end(); ++k)
                        keyed[k] = {importance_key(state.layout->of(fresh.indices[k]), fresh.values[k], result.step,
                                                   result.class_weights),
                                    fresh.indices[k], static_cast<std::uint32_t>(k)};
                    });
  sort_by_importance(keyed);
  for (const RankedEntry& entry : keyed) {
    result.ranked.push_back(entry.index);
    state.ranked_q.push_back(fresh.values[entry.position]);
  }
}

// Returns the number of coefficients the chunk held.
std::uint64_t decode_chunk(PayloadReader& reader, DecodeState& state) {
  IswDecoded& result = state.result;
  const auto chunk_start = Clock::now();
  const auto chunk = reader.read<std::uint32_t>();
  const auto begin = reader.read<std::uint64_t>();
  const auto end = reader.read<std::uint64_t>();
  const auto coded_size = reader.read<std::uint64_t>();
  const std::vector<std::uint64_t>& ends = state.chunk_ends;
  if (chunk != result.chunks_decoded || chunk >= ends.size() || end != ends[chunk] ||
      begin != (chunk == 0 ? 0 : ends[chunk - 1]))
    reader.fail("is out of order or inconsistent with QUAN");
  const ChunkCoefficients fresh = decode_chunk_coefficients(reader, state, coded_size, end - begin);
  result.seconds.chunks += seconds_since(chunk_start);
  const auto rank_start = Clock::now();
  rank_chunk(fresh, state);
  result.seconds.rank += seconds_since(rank_start);
  ++result.chunks_decoded;
  return end - begin;
}

// ------------------------------------------------------------ driver steps

void await_hierarchy(DecodeState& state) {
  IswDecoded& result = state.result;
  if (state.patch && !state.build.started()) {
    if (result.patch) return;
    state.build.start(result.base, result.levels, state.build_context);  // no PLNS: the base alone, whole
  }
  if (state.build.started()) {
    const auto wait_start = Clock::now();
    state.hierarchy = state.build.get();
    result.seconds.hierarchy_wait = seconds_since(wait_start);
    result.seconds.hierarchy = state.build.seconds();
  }
  assert(*state.layout == CoefficientClasses(*state.hierarchy));
  result.hierarchy = state.hierarchy;
}

// Version 2: the plane stream bytes to decode (the options' limit, or the
// RDTB row that reaches max_error).
std::uint64_t stream_limit(const DecodeState& state) {
  std::uint64_t limit = state.options.max_stream_bytes;
  if (state.options.max_error_cells > 0) {
    const double cell = state.result.metadata.number("cell_size", 0);
    if (!(cell > 0) || !std::isfinite(1 / cell))
      throw Error(ErrorKind::InvalidArgument, state.name + ": a maximum error needs the cell size, which the file does not record");
    const std::vector<IswRatePoint>& table = state.result.stream.rate_table;
    for (const IswRatePoint& row : table)
      if (row.error <= state.options.max_error_cells * cell) {
        limit = std::min(limit, row.stream_bytes);
        break;
      }
  }
  return limit;
}


enum class Next { Continue, Stop, HeadersOnly };

// Decodes one known section into `state`; says whether to read on.
Next decode_section(const Section& section, DecodeState& state) {
  PayloadReader reader = section.reader();
  IswSectionInfo info = section.info;
  IswDecoded& result = state.result;
  Next next = Next::Continue;
  if (section.tag == "META") {
    decode_meta(reader, section.payload, result.metadata, state.major);
  } else if (section.tag == "BASE") {
    decode_base(reader, result.base, state.major);
  } else if (section.tag == "QUAN") {
    if (state.major == 1) decode_quantization(reader, state);
    else decode_quantization_v2(reader, state);
    plan_hierarchy(reader, state);
  } else if (section.tag == "BPTS") {
    const double step = state.major == 1 ? class_step(result.step, result.class_weights, 0) : state.scales.frame_step;
    decode_base_points(reader, result.base, step, state.base_q);
    if (state.options.headers_only) {
      next = Next::HeadersOnly;
    } else if (state.major == 1) {
      reserve_fresh_on_huge_pages(state.significant, state.layout->fine());
      state.significant.assign(state.layout->fine(), 0);
    }
  } else if (section.tag == "CHNK") {
    info.coefficients = decode_chunk(reader, state);
    // Stop at the limit, but read END after the last chunk.
    if (result.ranked.size() >= state.limit && result.chunks_decoded < result.chunks_total) next = Next::Stop;
  } else if (section.tag == "RDTB") {
    result.stream.rate_table = read_rate_table(reader);
  } else if (section.tag == "GIDX") {
    state.group_index = read_group_index(reader, result.base.face_count());
  } else if (section.tag == "PCNT") {
    result.stream.plane_counts = read_plane_counts(reader);
    state.saw_plane_counts = true;
  } else if (section.tag == "PLNS") {
    if (!state.patch) await_hierarchy(state);
    const IswDecodeOptions& o = state.options;
    const StreamAccess access{state.group_index ? &*state.group_index : nullptr, &state.base_q,
                              o.region ? &*o.region : nullptr, o.frustum && !o.region ? &*o.frustum : nullptr,
                              state.fetch, state.file_size};
    // A coefficient limit reads only the planes it needs (not with a region,
    // whose limit applies outside it); PCNT is checked against PLNS always.
    StreamPrefix prefix{stream_limit(state), UINT64_MAX, state.saw_plane_counts ? &result.stream.plane_counts : nullptr};
    if (!o.region && !o.frustum && state.limit < result.coefficients_total) prefix.keep = state.limit;
    if (state.patch)
      decode_patch_stream(section, result.levels, *state.layout, state.scales, prefix, access, *state.incidence, result);
    else decode_plane_stream(section, *state.hierarchy, *state.layout, state.scales, prefix, access, result);
    if (state.fetch && section.cut) {
      // Read in part: the file holds the rest of PLNS and an END after it
      // (whose bytes are not read), or it is truncated.
      const std::uint64_t end = section.info.offset + kSectionOverhead + section.payload_size + kSectionOverhead;
      state.saw_end = state.file_size >= end;
      next = Next::Stop;
    }
  } else {  // END
    if (state.major == 1 && result.chunks_decoded != result.chunks_total)
      throw Error(ErrorKind::Format, section.where + ": chunks are missing");
    state.saw_end = true;
    next = Next::Stop;
  }
  result.sections.push_back(info);
  return next;
}

// options.headers_only: the section table after BPTS, without decoding it.
IswDecoded finish_headers_only(DecodeState& state, SectionWalker& sections) {
  IswDecoded& result = state.result;
  if (state.build.started()) state.hierarchy = state.build.get();
  result.hierarchy = state.hierarchy;
  result.truncated = sections.list_rest(result.sections);
  if (result.truncated)
    result.truncation_note = "file is truncated after byte " + std::to_string(sections.position()) + " of " +
                             std::to_string(state.bytes.size()) + " (not checked further: headers only)";
  return std::move(result);
}

// A file is truncated when it ends before END unless the limit stopped the
// decode first; the note says what was decoded.
void note_truncation(DecodeState& state, bool cut) {
  IswDecoded& result = state.result;
  const bool stopped_early = result.ranked.size() >= state.limit && result.chunks_decoded < result.chunks_total;
  result.truncated = cut || (!state.saw_end && !stopped_early);
  if (!result.truncated) return;
  result.truncation_note = result.chunks_decoded < result.chunks_total
                               ? "file is truncated inside the coefficient stream: decoded " +
                                     std::to_string(result.chunks_decoded) + " of " +
                                     std::to_string(result.chunks_total) + " chunks (" +
                                     std::to_string(result.ranked.size()) + " of " +
                                     std::to_string(result.coefficients_total) + " coefficients)"
                               : "file ends before its END section (all coefficient chunks were decoded)";
}

// The coarse-to-fine array: zero except the base control points and the
// coefficients kept (at most `limit`).
void dequantize_kept(DecodeState& state) {
  IswDecoded& result = state.result;
  const auto dequantize_start = Clock::now();
  if (result.ranked.size() > state.limit) result.ranked.resize(static_cast<std::size_t>(state.limit));
  const std::size_t fine = state.layout->fine();
  reserve_fresh_on_huge_pages(result.coefficients, fine);
  result.coefficients.resize(fine);
  std::copy(result.base.positions.begin(), result.base.positions.end(), result.coefficients.begin());
  for (std::size_t r = 0; r < result.ranked.size(); ++r) {
    const std::uint32_t i = result.ranked[r];
    const double s = class_step(result.step, result.class_weights, state.layout->of(i));
    const QuantizedVector& q = state.ranked_q[r];
    result.coefficients[i] = {q[0] * s, q[1] * s, q[2] * s};
  }
  result.seconds.dequantize = seconds_since(dequantize_start);
}

// Version 2: what the plane stream gave (the base alone when the file ends
// before it), ranked by importance and cut to the limit.
void finish_v2(DecodeState& state, bool cut) {
  IswDecoded& result = state.result;
  if (result.coefficients.empty() && !result.patch) {
    result.coefficients.assign(state.layout->fine(), Vec3{});
    std::copy(result.base.positions.begin(), result.base.positions.end(), result.coefficients.begin());
  }
  result.truncated = cut || !state.saw_end;
  if (result.truncated) {
    const IswStreamInfo& stream = result.stream;
    result.truncation_note = "file is truncated inside the plane stream: decoded " +
                             std::to_string(stream.planes_decoded) + " of " + std::to_string(stream.planes) +
                             " planes (" + std::to_string(stream.decoded) + " stream bytes)";
  }
  if (result.patch) return;  // nothing to rank: region_mesh() keeps what the region needs
  const auto rank_start = Clock::now();
  const bool unlimited = state.limit >= state.layout->fine() - state.layout->base();
  rank_and_keep(result, *state.layout, state.limit,
                unlimited && state.options.order == IswOrder::Index ? IswOrder::Index : IswOrder::Importance,
                state.options.oracle);
  result.seconds.rank = seconds_since(rank_start);
}

}  // namespace

namespace {

// decode_isw() of `bytes`, a file's first bytes when `fetch` reads the rest
// (a file of `file_size` bytes).
IswDecoded decode_from(const std::string& bytes, const std::string& name, const IswDecodeOptions& options,
                       std::function<std::string(std::uint64_t, std::uint64_t)> fetch, std::uint64_t file_size) {
  DecodeState state(bytes, name, options);
  state.fetch = std::move(fetch);
  state.file_size = file_size;
  state.result.file_bytes_read = bytes.size();
  state.result.file_bytes = file_size;
  read_file_header(bytes, name, state.result);
  state.major = state.result.major_version;
  SectionWalker sections(bytes, name, state.major);
  try {
    while (const std::optional<Section> section = sections.next()) {
      if (!section->known) {
        state.result.sections.push_back(section->info);
        continue;
      }
      const Next next = decode_section(*section, state);
      if (next == Next::HeadersOnly) return finish_headers_only(state, sections);
      if (next == Next::Stop) break;
    }
    sections.require_headers();
  } catch (...) {
    state.build.rethrow_error();
    throw;
  }
  await_hierarchy(state);
  if (state.major == 1 && options.max_error_cells > 0)
    throw Error(ErrorKind::InvalidArgument, name + ": a maximum error needs a version 2 file, which records its errors");
  if (state.major == 1 && options.oracle != Oracle::Weighted)
    throw Error(ErrorKind::InvalidArgument, name + ": another oracle needs a version 2 file (version 1 stores its ranking)");
  if (state.major == 1) {
    note_truncation(state, sections.truncated());
    dequantize_kept(state);
  } else {
    finish_v2(state, state.fetch ? !state.saw_end : sections.truncated());
  }
  return std::move(state.result);
}

}  // namespace

IswDecoded decode_isw(const std::string& bytes, const std::string& name, const IswDecodeOptions& options) {
  if (options.max_file_bytes < bytes.size()) {
    IswDecodeOptions whole = options;
    whole.max_file_bytes = UINT64_MAX;
    IswDecoded result = decode_isw(bytes.substr(0, static_cast<std::size_t>(options.max_file_bytes)), name, whole);
    result.truncated = false;
    result.truncation_note.clear();
    return result;
  }
  return decode_from(bytes, name, options, nullptr, bytes.size());
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

namespace {

// A file read by offset (Error(Io) if it cannot be opened or read).
class FileReader {
 public:
  explicit FileReader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw Error(ErrorKind::Io, path + ": cannot open");
    in_.seekg(0, std::ios::end);
    size_ = static_cast<std::uint64_t>(in_.tellg());
  }
  std::uint64_t size() const { return size_; }
  std::uint64_t bytes_read() const { return read_; }
  // Bytes [offset, offset + n), fewer where the file ends first.
  std::string read(std::uint64_t offset, std::uint64_t n) {
    if (offset >= size_) return {};
    n = std::min(n, size_ - offset);
    std::string out(static_cast<std::size_t>(n), '\0');
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    if (!in_.read(out.data(), static_cast<std::streamsize>(n))) throw Error(ErrorKind::Io, path_ + ": cannot read");
    read_ += n;
    return out;
  }

 private:
  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0, read_ = 0;
};

// The LEB128 value at `at` in `bytes`, if complete (then `at` moves past
// it). A value of more than ten bytes is complete as far as this reader
// goes (the decoder proper rejects it): every scan reads ten bytes at most.
bool next_varint(const std::string& bytes, std::size_t& at, std::uint64_t& value) {
  value = 0;
  for (std::size_t k = at, shift = 0; k < bytes.size(); ++k, shift += 7) {
    if (shift < 64) value |= std::uint64_t{static_cast<unsigned char>(bytes[k]) & 0x7Fu} << shift;
    if (!(static_cast<unsigned char>(bytes[k]) & 0x80) || k - at == 9) {
      at = k + 1;
      return true;
    }
  }
  return false;
}

// PLNS's table from `at` (its top plane, flags and counts, then a size per
// packet), read into `prefix` as the values show it must continue: each
// step reads only bytes the table still needs (a LEB128 value takes a byte
// at least). False when the file ends first.
bool read_plane_table(FileReader& file, std::string& prefix, std::size_t at, std::uint64_t end) {
  const auto reach = [&](std::uint64_t bytes) {  // prefix through byte `bytes` (exclusive)
    if (bytes > end) return false;
    if (bytes > prefix.size()) prefix += file.read(prefix.size(), bytes - prefix.size());
    return prefix.size() >= bytes;
  };
  if (!reach(at + 5)) return false;
  at += 2;
  std::uint64_t values = 3, count = 0;  // the counts, then the sizes
  for (std::uint64_t read = 0; read < values;) {
    std::uint64_t value = 0;
    if (next_varint(prefix, at, value)) {
      if (++read == 3) values = 3 + (count = value);
      continue;
    }
    // The value at `at` continues past the prefix; the others take a byte each.
    const std::uint64_t left = values - read;
    if (left > end || !reach(std::max<std::uint64_t>(prefix.size() + 1, at + left))) return false;
  }
  return true;
}

// A file's bytes through PLNS's packet table (every section before it, and
// the table), or the whole file when it has no PLNS or its table does not
// fit (the decoder then says what is wrong).
std::string read_through_plane_table(FileReader& file) {
  std::string prefix = file.read(0, kFileHeaderBytes);
  while (prefix.size() + kSectionHeader <= file.size()) {
    const std::uint64_t position = prefix.size();
    prefix += file.read(position, kSectionHeader);
    std::uint64_t size = 0;
    std::memcpy(&size, prefix.data() + position + 4, 8);
    const std::uint64_t left = file.size() - prefix.size();
    if (prefix.compare(position, 4, "PLNS") != 0) {
      prefix += file.read(prefix.size(), size < left ? std::min(left, size + 4) : left);
      continue;
    }
    if (!read_plane_table(file, prefix, prefix.size(), prefix.size() + std::min(size, left)))
      prefix += file.read(prefix.size(), file.size() - prefix.size());
    break;
  }
  return prefix;
}

}  // namespace

IswDecoded read_isw(const std::string& path, const IswDecodeOptions& options) {
  const auto start = Clock::now();
  // Reads in part whatever may need only part of the stream: a region, a
  // view, a coefficient limit (2.2's PCNT), a stream limit.
  const bool limited = options.max_coefficients != UINT64_MAX || options.max_percent < 100 ||
                       options.max_stream_bytes != UINT64_MAX || options.max_error_cells > 0;
  if (options.max_file_bytes != UINT64_MAX) {
    // A byte past the prefix tells decode_isw the file goes on (a prefix is not truncated).
    FileReader file(path);
    const std::string bytes = file.read(0, options.max_file_bytes + 1);
    const double read_seconds = seconds_since(start);
    IswDecoded result = decode_isw(bytes, path, options);
    result.file_bytes = file.size();
    result.seconds.read = read_seconds;
    return result;
  }
  if (options.region || options.frustum || limited) {
    FileReader file(path);
    const std::string prefix = read_through_plane_table(file);
    const double read_seconds = seconds_since(start);
    IswDecoded result = prefix.size() >= file.size()
                            ? decode_isw(prefix, path, options)
                            : decode_from(prefix, path, options,
                                          [&](std::uint64_t offset, std::uint64_t n) { return file.read(offset, n); },
                                          file.size());
    result.file_bytes_read = file.bytes_read();
    result.seconds.read = read_seconds;
    return result;
  }
  const std::string bytes = read_file_bytes(path);
  const double read_seconds = seconds_since(start);
  IswDecoded result = decode_isw(bytes, path, options);
  result.seconds.read = read_seconds;
  return result;
}

}  // namespace isowave
