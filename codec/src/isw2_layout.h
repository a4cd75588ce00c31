#pragma once
// Private: what the .isw 2.0 encoder and decoder share (docs/FORMAT.md,
// version 2): the scaling of every entry to step units in its local frame,
// the context class of every node, and the PLNS and RDTB payloads.
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/patch_hierarchy.h"
#include "bitplane_coder.h"
#include "isw_sections.h"
#include "local_frames.h"
#include "plane_groups.h"

namespace isowave::detail {

// QUAN of version 2. An entry of class c > 0 with world value d and frame
// (n, t, b) is, in step units, (d.n, d.t / k, d.b / k) x weight_c / step; a
// base control point is (p - p_frame) x weight_0 / step, p_frame its value
// at the frame step (BPTS).
struct V2Scales {
  double step = 0;               // world units at weight 1, > 0
  double frame_step = 0;         // BPTS step, world units, > 0
  double tangential_factor = 1;  // k >= 1
  std::vector<double> weights;   // per class, > 0

  Vec3 to_steps(std::size_t i, int cls, const Vec3& value, const std::vector<Vec3>& frame_base,
                const std::vector<Vec3>& normals) const {
    if (cls == 0) return (value - frame_base[i]) * (weights[0] / step);
    const Vec3 c = to_frame(frame_of(normals[i]), value) * (weights[static_cast<std::size_t>(cls)] / step);
    return {c[0], c[1] / tangential_factor, c[2] / tangential_factor};
  }
  Vec3 from_steps(std::size_t i, int cls, const Vec3& u, const std::vector<Vec3>& frame_base,
                  const std::vector<Vec3>& normals) const {
    if (cls == 0) return frame_base[i] + u * (step / weights[0]);
    const Vec3 c{u[0], u[1] * tangential_factor, u[2] * tangential_factor};
    return from_frame(frame_of(normals[i]), c) * (step / weights[static_cast<std::size_t>(cls)]);
  }
};

// Step-unit values (`values`, one per entry) into world coefficients in
// place, as the decoder gives them: a base control point is its frame-precision
// point plus the value, a wavelet coefficient the value in its local frame
// (zero where every component is). Parallel.
void steps_to_world(const std::vector<std::uint8_t>& classes, const V2Scales& scales, const std::vector<Vec3>& frame_base,
                    const std::vector<Vec3>& normals, std::vector<Vec3>& values);

// Per entry, its coefficient class (the plane coder's context class).
std::vector<std::uint8_t> node_classes(const CoefficientClasses& classes);

// PLNS: i8 top plane, u8 flags (bit 0: the last packet is cut; bit 1: the
// planes code non-normal flags, 2.1), LEB128 group and segment (level)
// counts, LEB128 packet count and sizes, then the packets (plane, then
// level, then group).
enum class PlaneEnding { Complete, Cut };
struct PlaneLayout {
  int top_plane = -1;
  std::size_t groups = 1;
  std::size_t segments = 1;  // levels + 1
  bool non_normal_flags = false;  // the coding of minor version 1 (encode_planes)
  int coding_minor() const { return non_normal_flags ? 1 : 0; }
  std::size_t packets_per_plane() const { return groups * segments; }
};
void put_planes(std::string& out, PlaneLayout layout, const std::vector<std::string_view>& packets, PlaneEnding last);
// PLNS's payload before its packets (GIDX holds its CRC).
std::string plane_table(PlaneLayout layout, const std::vector<std::string_view>& packets, PlaneEnding last);
inline void put_planes(std::string& out, PlaneLayout layout, const std::vector<std::string>& packets,
                       PlaneEnding last) {
  put_planes(out, layout, std::vector<std::string_view>(packets.begin(), packets.end()), last);
}

// Bytes of the LEB128 encoding of v.
inline std::uint64_t varint_size(std::uint64_t v) {
  std::uint64_t bytes = 1;
  for (; v >= 0x80; v >>= 7) ++bytes;
  return bytes;
}

struct PlaneStream {
  PlaneLayout layout;
  std::size_t packets_total = 0;          // as the table says
  std::size_t planes_total = 0;           // planes the packets begin
  std::vector<std::uint64_t> plane_ends;  // cumulative sizes at each plane's end, as the table says
  bool table = false;                     // the packet table is complete
  std::vector<std::uint64_t> sizes;       // of every packet, as the table says
  bool encoder_cut = false;               // flags bit 0: the encoder cut the last packet
  std::vector<std::string_view> packets;  // those present, the last maybe cut
  bool last_cut = false;                // the last of `packets` is cut (by the encoder or the file's end)
  std::uint64_t data_offset = 0;        // of the first packet in the payload
};
// Reads a PLNS payload that may itself be cut (`payload_cut`), keeping at
// most `max_stream_bytes` bytes of packets. Error(Format) through `reader`
// for impossible tables (more than `max_groups` groups or kMaxSegments
// segments, more packets than planes, unknown flags). A cut payload whose
// table is incomplete gives no sizes.
PlaneStream read_planes(PayloadReader& reader, std::string_view payload, bool payload_cut,
                        std::uint64_t max_stream_bytes, std::uint64_t max_groups = kMaxGroups);

// The packets a stream of `available` bytes holds: each one's offset and
// size from the table's `sizes` (the last maybe cut short: `last_cut`, also
// when the encoder cut it).
struct PacketSpan {
  std::uint64_t offset = 0, size = 0;
};
std::vector<PacketSpan> present_packets(const std::vector<std::uint64_t>& sizes, std::uint64_t available,
                                        bool encoder_cut, bool& last_cut);

// RDTB: u32 rows, each u64 stream bytes and f64 D (world units).
void put_rate_table(std::string& out, const std::vector<IswRatePoint>& rows);
std::vector<IswRatePoint> read_rate_table(PayloadReader& reader);

// PCNT (2.2): u32 rows, each u64: per plane of the complete stream, from the
// top, the wavelet coefficients non-zero once that plane is decoded
// (non-decreasing). Reading checks the rows' count and order.
void put_plane_counts(std::string& out, const std::vector<std::uint64_t>& nonzero);
std::vector<std::uint64_t> read_plane_counts(PayloadReader& reader);

// How much of the plane stream a decode reads: at most `bytes`, and with a
// coefficient limit `keep` and PCNT's counts, the planes limit_planes() gives.
struct StreamPrefix {
  std::uint64_t bytes = UINT64_MAX;
  std::uint64_t keep = UINT64_MAX;                      // UINT64_MAX: no limit
  const std::vector<std::uint64_t>* nonzero = nullptr;  // PCNT, if the file has one
};

// The planes (from the top) a decode keeping `keep` wavelet coefficients
// (and `base` control points) reads, from PCNT's counts `nonzero` (rows from
// plane top_plane down): the fewest past the plane that makes the keep-th
// coefficient significant whose quantization error, (keep + base) x 4^p
// squared steps when plane p is the last read (3 components, each known
// to an interval of 2^p), is at most a tenth of the error of what is dropped, 2.25 x 4^b
// per coefficient of plane b (its largest component in [2^b, 2^(b+1)));
// all of them when none is. docs/FORMAT.md, "Percentages".
std::size_t limit_planes(const std::vector<std::uint64_t>& nonzero, int top_plane, std::uint64_t keep,
                         std::uint64_t base);

// What IswPlaneValues keeps of an encoding: every entry's magnitudes and
// signs, and what turns them into world coefficients.
struct PlaneValuesState {
  PlaneSymbols symbols;
  V2Scales scales;
  std::vector<Vec3> frame_base, normals;
  int top_plane = -1;
  std::vector<std::uint64_t> plane_ends;  // of the file written (a cut one has fewer)
  IswPlaneBits bits;                      // of the whole stream encoded
};

// The encoder (isw2_encoder.cpp): `weights` are the class weights; `values`,
// if given, receives what the plane ends decode to.
std::string encode_isw_v2(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                          const IswMetadata& metadata, const IswEncodeOptions& options, std::vector<double> weights,
                          PlaneValuesState* values = nullptr);

// What the decoder's PLNS reads besides the section: version 2.2's index
// and frame-base integers, the region (decode_patch_stream()) or view
// frustum whose groups alone to decode, and, for a file read in part, where
// its bytes past those in memory come from.
struct StreamAccess {
  const GroupIndex* index = nullptr;                      // GIDX (required by 2.2)
  const std::vector<QuantizedVector>* base_q = nullptr;  // BPTS's integers
  const RegionOfInterest* region = nullptr;
  const Camera* frustum = nullptr;  // the faces that may lie in its view
  // File bytes [offset, offset + size) (the file's end may come first), and
  // the file's size; none when the whole file is in memory.
  std::function<std::string(std::uint64_t offset, std::uint64_t size)> fetch;
  std::uint64_t file_size = 0;
};

// The decoder's PLNS (isw2_decoder.cpp): decodes the `prefix` of the
// section's packets into result.coefficients (world units; base
// control points included, and result.base.positions) and result.stream.
// Error(Format) naming the section for a damaged complete packet, or (2.2)
// a packet table or a group's packets that disagree with GIDX's CRCs.
void decode_plane_stream(const Section& section, const SubdivisionHierarchy& hierarchy,
                         const CoefficientClasses& layout, const V2Scales& scales, const StreamPrefix& prefix,
                         const StreamAccess& access, IswDecoded& result);

// The same for a region (access.region, 2.2): only the groups the region
// needs, over a patch of the base (patch_selection.h; `incidence` the
// base's) instead of the whole hierarchy, into result.patch (region.h);
// result.coefficients stays empty. Error(Format) as above, and for a base
// the hierarchy cannot take.
void decode_patch_stream(const Section& section, int levels, const CoefficientClasses& layout, const V2Scales& scales,
                         const StreamPrefix& prefix, const StreamAccess& access, const BaseIncidence& incidence,
                         IswDecoded& result);

// result.ranked: the non-zero wavelet coefficients by importance (class
// weight times magnitude, ties by index), the first `keep` of them; the
// others are zeroed in result.coefficients. IswOrder::Index: all of them in
// index order (`keep` is then ignored). With fewer kept than decoded,
// `oracle` chooses them (Greedy synthesizes with result.hierarchy).
void rank_and_keep(IswDecoded& result, const CoefficientClasses& layout, std::uint64_t keep, IswOrder order,
                   Oracle oracle);

}  // namespace isowave::detail
