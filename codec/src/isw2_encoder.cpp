// The .isw 2.0 encoder (docs/FORMAT.md, version 2): base control points at
// a frame precision, local frames from them, every coefficient in its frame
// and class weight as three step-unit magnitudes, and the embedded bit planes.
#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <optional>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/error.h"
#include "isw_sections.h"
#include "bitplane_coder.h"
#include "coefficient_tree.h"
#include "isw2_layout.h"
#include "isw_headers.h"
#include "isw_models.h"
#include "local_frames.h"
#include "plane_groups.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {

using namespace detail;

namespace {

void check_v2_options(const IswEncodeOptions& options) {
  if (!(options.tangential_factor >= 1) || !std::isfinite(options.tangential_factor))
    throw Error(ErrorKind::InvalidArgument, "the tangential factor must be at least 1");
  if (options.frame_step < 0 || !std::isfinite(options.frame_step))
    throw Error(ErrorKind::InvalidArgument, "the frame step must be positive (or 0: automatic)");
  if (options.minor_version < 0 || options.minor_version > kIswMinorVersion)
    throw Error(ErrorKind::InvalidArgument, "the minor version must be 0 to " + std::to_string(kIswMinorVersion));
}

// One component in step units: magnitude and sign; false when it is not
// finite or beyond the largest magnitude.
bool split(double value, std::uint32_t& magnitude, int& negative) {
  const double m = std::floor(std::abs(value));
  if (!(m <= double(kMaxMagnitude))) return false;
  magnitude = static_cast<std::uint32_t>(m);
  negative = value < 0 && magnitude > 0 ? 1 : 0;
  return true;
}

// Every entry's magnitudes and signs: base control points as their
// residual from the frame-precision base, wavelet coefficients in their
// local frames (docs/FORMAT.md, PLNS).
PlaneSymbols symbols_of(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                        const std::vector<Vec3>& coarse_base, const std::vector<Vec3>& normals, const V2Scales& scales) {
  const CoefficientClasses classes(hierarchy);
  PlaneSymbols s;
  const std::size_t n = hierarchy.fine_vertex_count();
  s.classes = classes.count();
  s.magnitude.resize(3 * n);
  s.negative.resize(n);
  s.node_class = node_classes(classes);
  std::atomic<bool> invalid{false};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const Vec3 u = scales.to_steps(i, s.node_class[i], coefficients[i], coarse_base, normals);
      std::uint8_t negative = 0;
      for (int k = 0; k < 3; ++k) {
        int sign = 0;
        if (!split(u[k], s.magnitude[3 * i + static_cast<std::size_t>(k)], sign)) invalid = true;
        negative = static_cast<std::uint8_t>(negative | (sign << k));
      }
      s.negative[i] = negative;
    }
  });
  if (invalid)
    throw Error(ErrorKind::InvalidArgument, "a coefficient is not finite or too large for the quantization step");
  return s;
}

void put_quantization_v2(std::string& out, const V2Scales& scales, int levels, std::uint64_t nonzero) {
  std::string payload;
  put_f64(payload, scales.step);
  put_f64(payload, scales.frame_step);
  put_f64(payload, scales.tangential_factor);
  put_u32(payload, static_cast<std::uint32_t>(levels));
  put_u32(payload, static_cast<std::uint32_t>(scales.weights.size()));
  for (double w : scales.weights) put_f64(payload, w);
  put_u64(payload, nonzero);
  put_section(out, "QUAN", payload);
}

// The base control points rounded to the frame step: as integers (BPTS) and as points.
void frame_base(const std::vector<Vec3>& points, std::size_t count, double frame_step,
                std::vector<QuantizedVector>& quantized, std::vector<Vec3>& rounded) {
  quantized.assign(count, QuantizedVector{});
  rounded.assign(count, Vec3{});
  for (std::size_t v = 0; v < count; ++v)
    for (int axis = 0; axis < 3; ++axis) {
      const double scaled = points[v][axis] / frame_step;
      if (!(std::abs(scaled) <= 1e12)) throw Error(ErrorKind::InvalidArgument, "a base control point is not finite or too large");
      quantized[v][axis] = std::llround(scaled);
      rounded[v][axis] = double(quantized[v][axis]) * frame_step;
    }
}

std::uint64_t nonzero_wavelets(const SubdivisionHierarchy& hierarchy, const PlaneSymbols& s) {
  std::uint64_t count = 0;
  for (std::size_t i = hierarchy.vertex_count(0); i < hierarchy.fine_vertex_count(); ++i)
    count += (s.magnitude[3 * i] | s.magnitude[3 * i + 1] | s.magnitude[3 * i + 2]) != 0;
  return count;
}

// PCNT: per plane from `top_plane` down to 0, the wavelet coefficients with
// a component of at least 2^plane steps (those a decode through that plane
// has non-zero).
std::vector<std::uint64_t> plane_counts(const SubdivisionHierarchy& hierarchy, const PlaneSymbols& s, int top_plane) {
  std::array<std::uint64_t, 33> by_length{};  // coefficients by their largest magnitude's bit length
  for (std::size_t i = hierarchy.vertex_count(0); i < hierarchy.fine_vertex_count(); ++i) {
    std::uint32_t m = s.magnitude[3 * i] | s.magnitude[3 * i + 1] | s.magnitude[3 * i + 2];
    int length = 0;
    for (; m != 0; m >>= 1) ++length;
    ++by_length[static_cast<std::size_t>(length)];
  }
  std::vector<std::uint64_t> nonzero;
  std::uint64_t count = 0;
  for (int plane = top_plane; plane >= 0; --plane) {
    count += by_length[static_cast<std::size_t>(plane + 1)];
    nonzero.push_back(count);
  }
  return nonzero;
}

// What the planes from the top down to plane `low` decode to, in world units
// (base control points first): every component known to that plane.
void values_at_plane(const PlaneSymbols& s, int low, const V2Scales& scales, const std::vector<Vec3>& frame_base,
                     const std::vector<Vec3>& normals, std::vector<Vec3>& out) {
  out.resize(s.negative.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i)
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t known = s.magnitude[3 * i + static_cast<std::size_t>(c)] >> low << low;
        const double v = known_value(known, low);
        out[i][c] = v != 0 && ((s.negative[i] >> c) & 1) ? -v : v;
      }
  });
  steps_to_world(s.node_class, scales, frame_base, normals, out);
}

// Version 2.2's groups by space (plane_groups.h): the runs into `index`, and
// the tree's split.
TreeGroups spatial_groups(const SubdivisionHierarchy& hierarchy, const CoefficientTree& tree,
                          const std::vector<QuantizedVector>& base_q, std::size_t group_nodes, GroupIndex& index,
                          std::vector<std::uint32_t>& face_group) {
  if (hierarchy.base().face_count() == 0) throw Error(ErrorKind::InvalidArgument, "a base mesh without faces");
  const FaceOrder order = morton_face_order(hierarchy.base(), base_q);
  const std::vector<std::uint32_t> owners = root_faces(hierarchy, tree);
  index.runs = cut_face_runs(tree, owners, order, group_nodes > 0 ? group_nodes : kSpatialGroupNodes);
  face_group = face_groups(order.faces, index.runs);
  return split_tree(tree, root_groups(owners, face_group), index.count());
}

// GIDX of a complete stream: the groups' reaches on the complete decode, and the CRCs.
void index_stream(const SubdivisionHierarchy& hierarchy, const PlaneSymbols& symbols, const V2Scales& scales,
                  const std::vector<Vec3>& frame_base, const std::vector<Vec3>& normals,
                  const std::vector<std::uint32_t>& face_group, const PlaneLayout& layout,
                  const std::vector<std::string>& packets, GroupIndex& index) {
  std::vector<Vec3> fine;
  values_at_plane(symbols, 0, scales, frame_base, normals, fine);
  synthesize(hierarchy, fine);
  set_group_reach(hierarchy, frame_base, fine, face_group, index);
  const std::vector<std::string_view> views(packets.begin(), packets.end());
  index.table_crc = bytes_crc(plane_table(layout, views, PlaneEnding::Complete));
  index.group_crc = group_crcs(views, index.count());
}

}  // namespace

namespace detail {

std::string encode_isw_v2(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                          const IswMetadata& metadata, const IswEncodeOptions& options, std::vector<double> weights,
                          PlaneValuesState* values) {
  check_v2_options(options);
  const std::size_t base_count = hierarchy.vertex_count(0);
  V2Scales scales{options.step, options.frame_step > 0 ? options.frame_step : 16 * options.step / weights[0],
                  options.tangential_factor, std::move(weights)};
  // The frame-precision base, which the decoder has before any plane.
  std::vector<QuantizedVector> base_q;
  std::vector<Vec3> coarse_base;
  if (options.frame_base && options.frame_base->size() != base_count)
    throw Error(ErrorKind::InvalidArgument, "the frame base must have one point per base vertex");
  frame_base(options.frame_base ? *options.frame_base : coefficients, base_count, scales.frame_step, base_q,
             coarse_base);
  std::vector<Vec3> normals = frame_normals(hierarchy, coarse_base);
  PlaneSymbols symbols = symbols_of(hierarchy, coefficients, coarse_base, normals, scales);
  const CoefficientTree tree = build_coefficient_tree(hierarchy);
  const bool by_space = options.minor_version >= 2;
  GroupIndex index;
  std::vector<std::uint32_t> face_group;
  const TreeGroups split = by_space ? spatial_groups(hierarchy, tree, base_q, options.group_nodes, index, face_group)
                                    : split_tree(tree, plane_groups(hierarchy.fine_vertex_count()));
  IswPlaneBits bits;
  const PlanePackets planes = encode_planes(tree, symbols, split, options.minor_version, 0, values ? &bits : nullptr);
  const PlaneLayout layout{planes.top_plane, split.count(), planes.segments, options.minor_version >= 1};
  if (by_space) index_stream(hierarchy, symbols, scales, coarse_base, normals, face_group, layout, planes.packets, index);

  std::string out;
  put_file_header(out, 2, options.minor_version);
  put_meta(out, metadata, 2);
  put_base(out, hierarchy.base(), 2);
  put_quantization_v2(out, scales, hierarchy.levels(), nonzero_wavelets(hierarchy, symbols));
  put_base_points(out, hierarchy.base(), base_q);
  if (by_space) {
    put_group_index(out, index);
    put_plane_counts(out, plane_counts(hierarchy, symbols, planes.top_plane));
  }
  put_planes(out, layout, planes.packets, PlaneEnding::Complete);
  put_section(out, "END ", std::string_view());
  std::uint64_t kept = UINT64_MAX;  // plane stream bytes
  if (values) values->plane_ends = stream_plane_ends(out);
  if (options.max_bytes > 0 && out.size() > options.max_bytes) {
    kept = stream_bytes_within(out, options.max_bytes);
    out = rewrite_isw(out, IswRewrite{kept, {}, nullptr});
  }
  if (values) {
    // The planes the cut keeps whole.
    std::vector<std::uint64_t>& ends = values->plane_ends;
    ends.erase(std::upper_bound(ends.begin(), ends.end(), kept), ends.end());
    values->top_plane = planes.top_plane;
    values->symbols = std::move(symbols);
    values->scales = std::move(scales);
    values->frame_base = std::move(coarse_base);
    values->normals = std::move(normals);
    values->bits = bits;
  }
  return out;
}

}  // namespace detail

namespace {

// The sections of a complete version 2 file, in order, and its minor
// version; Error(InvalidArgument) otherwise.
std::vector<Section> sections_of_v2(const std::string& file, int* minor_version = nullptr) {
  IswDecoded header;
  read_file_header(file, "rewrite_isw", header);
  if (minor_version) *minor_version = header.minor_version;
  if (header.major_version != 2) throw Error(ErrorKind::InvalidArgument, "rewrite_isw: not a version 2 .isw file");
  SectionWalker walker(file, "rewrite_isw", 2);
  std::vector<Section> sections;
  while (std::optional<Section> section = walker.next()) sections.push_back(std::move(*section));
  if (walker.truncated() || sections.empty() || sections.back().tag != "END ")
    throw Error(ErrorKind::InvalidArgument, "rewrite_isw: the file is truncated");
  return sections;
}

}  // namespace

std::vector<Vec3> isw_frame_normals(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base,
                                    double frame_step) {
  if (!(frame_step > 0) || !std::isfinite(frame_step))
    throw Error(ErrorKind::InvalidArgument, "the frame step must be positive");
  if (base.size() < hierarchy.vertex_count(0))
    throw Error(ErrorKind::InvalidArgument, "isw_frame_normals needs one point per base vertex");
  std::vector<QuantizedVector> quantized;
  std::vector<Vec3> rounded;
  frame_base(base, hierarchy.vertex_count(0), frame_step, quantized, rounded);
  return frame_normals(hierarchy, rounded);
}

IswPlaneValues::IswPlaneValues() = default;
IswPlaneValues::~IswPlaneValues() = default;
IswPlaneValues::IswPlaneValues(IswPlaneValues&&) noexcept = default;
IswPlaneValues& IswPlaneValues::operator=(IswPlaneValues&&) noexcept = default;

const std::vector<std::uint64_t>& IswPlaneValues::plane_ends() const {
  static const std::vector<std::uint64_t> none;
  return state_ ? state_->plane_ends : none;
}

const std::vector<Vec3>& IswPlaneValues::frame_normals() const {
  static const std::vector<Vec3> none;
  return state_ ? state_->normals : none;
}

const IswPlaneBits& IswPlaneValues::plane_bits() const {
  static const IswPlaneBits none;
  return state_ ? state_->bits : none;
}

void IswPlaneValues::coefficients_at(std::size_t k, std::vector<Vec3>& out) const {
  assert(state_ && k < state_->plane_ends.size());
  values_at_plane(state_->symbols, state_->top_plane - static_cast<int>(k), state_->scales, state_->frame_base,
                  state_->normals, out);
}

std::string rewrite_isw(const std::string& file, const IswRewrite& rewrite) {
  const std::uint64_t stream_bytes = rewrite.stream_bytes;
  int minor = 0;
  const std::vector<Section> sections = sections_of_v2(file, &minor);
  std::string out;
  put_file_header(out, 2, minor);  // the planes' coding
  std::string_view index;   // GIDX's payload, rewritten with PLNS (its CRCs)
  std::string_view counts;  // PCNT's, which comes after GIDX
  for (const Section& section : sections) {
    if (section.tag == "RDTB") continue;  // replaced
    if (section.tag == "META" && rewrite.metadata) {
      put_meta(out, *rewrite.metadata, 2);
      continue;
    }
    if (section.tag == "GIDX" || section.tag == "PCNT") {
      (section.tag == "GIDX" ? index : counts) = section.payload;
      continue;
    }
    if (section.tag != "PLNS") {
      out.append(file, static_cast<std::size_t>(section.info.offset), static_cast<std::size_t>(section.info.bytes));
      continue;
    }
    PayloadReader reader = section.reader();
    const PlaneStream planes = read_planes(reader, section.payload, false, stream_bytes, kMaxStreamGroups);
    std::vector<IswRatePoint> rows;
    for (const IswRatePoint& row : rewrite.rate_table)
      if (row.stream_bytes <= stream_bytes) rows.push_back(row);
    if (!rows.empty()) put_rate_table(out, rows);
    const PlaneEnding ending = planes.last_cut ? PlaneEnding::Cut : PlaneEnding::Complete;
    if (!index.empty())
      put_section(out, "GIDX",
                  with_crcs(index, bytes_crc(plane_table(planes.layout, planes.packets, ending)),
                            group_crcs(planes.packets, planes.layout.groups)));
    if (!counts.empty()) put_section(out, "PCNT", counts);
    put_planes(out, planes.layout, planes.packets, ending);
  }
  return out;
}

std::uint64_t stream_bytes_within(const std::string& file, std::uint64_t max_bytes, std::size_t table_rows) {
  // Every section but the packet table's count and sizes and the packets.
  std::uint64_t fixed = kFileHeaderBytes + (table_rows > 0 ? kSectionOverhead + 4 + 16 * table_rows : 0);
  std::vector<std::uint64_t> sizes;
  for (const Section& section : sections_of_v2(file)) {
    if (section.tag == "RDTB") continue;
    if (section.tag != "PLNS") {
      fixed += section.info.bytes;
      continue;
    }
    PayloadReader reader = section.reader();
    const PlaneStream planes = read_planes(reader, section.payload, false, UINT64_MAX, kMaxStreamGroups);
    for (std::string_view packet : planes.packets) sizes.push_back(packet.size());
    fixed += section.info.bytes - (section.payload.size() - planes.data_offset) - varint_size(sizes.size());
    for (const std::uint64_t size : sizes) fixed -= varint_size(size);
  }
  // The table of a stream cut to s bytes: the count and the sizes it keeps.
  const auto table = [&](std::uint64_t s) {
    std::uint64_t bytes = 0, offset = 0, kept = 0;
    for (std::size_t p = 0; p < sizes.size() && offset < s; offset += sizes[p++], ++kept)
      bytes += varint_size(std::min(sizes[p], s - offset));
    return bytes + varint_size(kept);
  };
  if (fixed + table(0) >= max_bytes)
    throw Error(ErrorKind::InvalidArgument, "a file of at most " + std::to_string(max_bytes) +
                                                " bytes cannot hold even the base mesh (" +
                                                std::to_string(fixed + table(0)) + " bytes)");
  // The largest s with fixed + table(s) + s <= max_bytes (the left side grows with s).
  std::uint64_t low = 0, high = max_bytes - fixed;
  while (low < high) {
    const std::uint64_t middle = low + (high - low + 1) / 2;
    if (fixed + table(middle) + middle <= max_bytes) low = middle;
    else high = middle - 1;
  }
  return low;
}

std::vector<std::uint64_t> stream_plane_ends(const std::string& file) {
  for (const Section& section : sections_of_v2(file)) {
    if (section.tag != "PLNS") continue;
    PayloadReader reader = section.reader();
    return read_planes(reader, section.payload, false, UINT64_MAX, kMaxStreamGroups).plane_ends;
  }
  return {};
}

}  // namespace isowave
