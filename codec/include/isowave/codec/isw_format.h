#pragma once
// The .isw file: a wavelet-compressed isosurface (documented in docs/FORMAT.md).
//
//   header   8-byte magic "\x89ISW\r\n\x1a\n", u16 major version, u16 minor version, u32 zero
//   sections [4-byte tag][u64 payload size][u32 CRC-32 of tag and size][payload][u32 CRC-32 of tag and payload]:
//            META  metadata as UTF-8 "key=value" lines (deflated in version 2)
//            BASE  base mesh: counts, face sizes and indices (range coded), sharp flags
//            QUAN  quantization steps and per-class wavelet weights
//            BPTS  base control points, quantized, predicted from decoded neighbours, range coded
//   version 2 (written by default; issue #34):
//            RDTB  optional: the surface error D measured at prefixes of the plane stream
//            PLNS  embedded bit planes of every coefficient in its local frame (normal,
//                  tangent, bitangent), most significant plane first, set-partitioned over
//                  the hierarchy's parent-child tree, in independent groups (decoded
//                  in parallel): any prefix decodes; 2.1 flags the coefficients with a
//                  tangential part and codes none for the others
//   version 1:
//            CHNK  (several) wavelet coefficients, most important first: chunk k holds the coefficients
//                  ranked in [start_k, end_k) by importance, coded by significance flags over the
//                  coefficients not yet sent plus quantized components
//            END   empty
//
// Progressive: a version 2 file cut at any byte of its plane stream (or
// decoded with max_stream_bytes) rebuilds the best surface that prefix
// allows; a version 1 reader may stop after any chunk. Decoding treats every byte as hostile: every count is checked
// against the bytes present before anything is allocated and the work is
// linear in the file size; a corrupt section (bad CRC, impossible values) is
// an Error(Format) naming the section; a file cut inside the coefficient
// chunks decodes the complete chunks and says so (IswDecoded::truncated).
// Sources: isw_sections (framing, CRCs), isw_encoder, isw_decoder (one
// function per section), isw_models (what both must compute alike).
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "isowave/codec/camera.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/region_of_interest.h"
#include "isowave/core/mesh.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// A reader decodes every minor version of major 1 (it skips the sections it
// does not know) and versions 2.0 to 2.kIswMinorVersion of major 2 (2.1 codes
// a non-normal flag per wavelet coefficient in the planes; 2.2 groups the
// planes' tree by space and indexes the groups, GIDX); it refuses other
// versions (Error(Unsupported)).
constexpr std::uint16_t kIswMajorVersion = 2;
constexpr std::uint16_t kIswMinorVersion = 2;

struct IswMetadata {
  // Free-form but conventional keys (docs/FORMAT.md, META): source, isovalue,
  // spacing, origin, cell_size, levels, extracted_vertices, quantization_rmse,
  // options, ... Keys lose '=' and line breaks when written, values line breaks.
  std::map<std::string, std::string> values;

  // The value of `key` as a finite number, else `fallback` (missing or not a number).
  double number(const std::string& key, double fallback) const;
  std::string text(const std::string& key, const std::string& fallback = {}) const;
};

// D of a decoded surface at a prefix of the plane stream (RDTB).
struct IswRatePoint {
  std::uint64_t stream_bytes = 0;  // bytes of the plane stream (PLNS packets) decoded
  double error = 0;                // D at that prefix, world units (the writer's measure; convert: against the isosurface)
};

struct IswEncodeOptions {
  // The major version written: 2 (embedded planes in local frames) or 1.
  int major_version = kIswMajorVersion;
  // Version 2: the minor version written, 0 to 2 (1 codes, at a wavelet
  // coefficient's first significance, whether it is non-normal, and no
  // tangential decision for the others; 2 also groups the tree by space and
  // writes the groups' index, so that a region reads only its groups;
  // docs/FORMAT.md, versions 2.1 and 2.2).
  int minor_version = kIswMinorVersion;
  // Quantization step for importance-weighted coefficients, in world units,
  // finite and > 0: a coefficient of class c is quantized with step / weight_c,
  // so every kept coefficient adds about the same error to the fine control
  // points. Version 1: the expected RMSE added over the fine points is about
  // step / 2. Version 2: the step of the last bit plane (a dead-zone
  // quantizer; any prefix stops at a coarser one).
  double step = 0.01;
  // Version 2: tangential components use a step this many times the normal
  // one (>= 1): they move the surface along itself, which costs bits and
  // changes the surface little.
  double tangential_factor = 8;
  // Version 2: BPTS sends the base control points at this step (world units;
  // 0: 16 x step / weight_0), from which the local frames are built; the
  // planes refine them to `step`.
  double frame_step = 0;
  // Version 2: the points BPTS sends (rounded to frame_step), from which the
  // local frames are built, one per base vertex in the hierarchy's order;
  // the planes then refine the base control points from them. nullptr: the
  // base control points themselves. A fit whose coefficients lie along the
  // frames of another base than its final one (fit/normal_fit.h) passes it,
  // with the frame_step (> 0) it took isw_frame_normals() at.
  const std::vector<Vec3>* frame_base = nullptr;
  // Version 2.2: tree nodes per group of the plane stream (a run of base
  // faces holds at most this many where the Morton order's cells allow; 0:
  // the default, 32,768). Smaller groups let a region read fewer bytes
  // beyond itself, at the cost per group of context learning, flushes and
  // index (docs/MEASUREMENTS.md, "Random access").
  std::size_t group_nodes = 0;
  // Version 2: cut the plane stream so that the file holds at most this many
  // bytes (0: the whole stream). Error(InvalidArgument) when the headers alone exceed it.
  std::uint64_t max_bytes = 0;
  // Chunk boundaries in percent of full resolution (fine control points),
  // ascending in (0, 100]; the remaining coefficients form the last chunk. A
  // reader stopping at p% reads the chunks up to the first boundary >= p.
  std::vector<double> chunk_percents{1, 2, 3.5, 5, 7.5, 10, 15, 20, 30, 50, 75};
  // Per-class wavelet weights (wavelet_norms of the hierarchy, 1 + 2 L values,
  // each > 0); computed when empty. Callers that already have them skip
  // 1 + 2 L syntheses.
  std::vector<double> class_weights;
};

// Encodes a base mesh (topology and sharp flags; must pass require_manifold),
// a level count in 0..8 and the coarse-to-fine coefficient array of the
// analysis (base control points, then wavelet coefficients; world units, one
// per fine control point). Throws Error(InvalidArgument) for other levels, a
// step that is not positive, a wrong count, or a coefficient that is not
// finite or over 1e9 of its class's steps. Deterministic: the same input
// gives the same bytes on any number of threads. Cost: O(fine vertices) plus
// sorting the non-zero coefficients by importance; chunks coded in parallel.
std::string encode_isw(const PolygonMesh& base, int levels, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options = {});
// The same for a hierarchy already built (its base mesh and levels are coded).
// `ranked`, if given, receives (version 1 only) the indices of the non-zero
// quantized wavelet coefficients in the order the file sends them (as a decode lists them).
std::string encode_isw(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options = {},
                       std::vector<std::uint32_t>* ranked = nullptr);

// The unit normal of every entry's local frame (fine vertex count entries,
// zero where the patch is degenerate) that encode_isw() writes version 2 with
// for base control points `base` and frame step `frame_step` (world units,
// > 0): the normals of S^L of the base rounded to the frame step. A
// coefficient along its entry's normal has no tangential part. Throws
// Error(InvalidArgument) for too few, non-finite or huge base points. Cost:
// one synthesis, O(fine vertices).
std::vector<Vec3> isw_frame_normals(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base,
                                    double frame_step);

// What rewrite_isw() changes in a version 2 file.
struct IswRewrite {
  std::uint64_t stream_bytes = UINT64_MAX;  // keep at most this many plane stream bytes (any count decodes)
  std::vector<IswRatePoint> rate_table;     // the new RDTB, rows ascending in bytes; rows beyond stream_bytes dropped
  const IswMetadata* metadata = nullptr;    // the new META, when given
};
// A complete version 2 file rewritten; Error(InvalidArgument) for anything else.
std::string rewrite_isw(const std::string& file, const IswRewrite& rewrite);
// The plane stream bytes that keep `file` (version 2) within `max_bytes`
// bytes in all with an RDTB of `table_rows` rows. Error(InvalidArgument) when
// the headers alone exceed it.
std::uint64_t stream_bytes_within(const std::string& file, std::uint64_t max_bytes, std::size_t table_rows = 0);
// The plane stream bytes at each plane's end in a complete version 2 file
// (its packet table; nothing is decoded). Error(InvalidArgument) otherwise.
std::vector<std::uint64_t> stream_plane_ends(const std::string& file);

namespace detail {
struct PlaneValuesState;
}

// What a version 2 file's plane stream decodes to at each plane's end, known
// to the encoder without decoding: convert's rate control measures D there.
// coefficients_at(k, out) gives exactly the coefficients of decode_isw()
// with max_stream_bytes = plane_ends()[k]. Holds about 40 bytes per fine
// control point.
// Version 2: a plane stream's estimated bits by what they code: the sum, over
// the plane coder's adaptive decisions (it codes no direct bits), of -log2 of
// the probability the coder gave the bit it coded (so the range coder's
// output differs by its flush bytes only). Wavelet components are (normal,
// tangent, bitangent) in the local frames (docs/FORMAT.md, PLNS).
struct IswPlaneBits {
  double base = 0;  // every decision of the base control points' residuals
  // A wavelet coefficient's normal component: its bit "component 0 has bit b
  // set" (significance), its sign, its refinement bits.
  double normal_significance = 0, normal_sign = 0, normal_refinement = 0;
  // Its tangential components, and the node decisions "some not-yet-significant
  // component has bit b set" that cover only tangential components.
  double tangential_significance = 0, tangential_sign = 0, tangential_refinement = 0;
  // The node decisions that cover the normal and tangential components together.
  double joint_significance = 0;
  double descendants = 0;  // the tree: "some descendant reaches 2^b"

  double tangential() const { return tangential_significance + tangential_sign + tangential_refinement; }
  double normal() const { return normal_significance + normal_sign + normal_refinement; }
  double total() const { return base + normal() + tangential() + joint_significance + descendants; }
  // tangential() / total(), 0 for an empty stream.
  double tangential_share() const { return total() > 0 ? tangential() / total() : 0.0; }
};

class IswPlaneValues {
 public:
  IswPlaneValues();
  ~IswPlaneValues();
  IswPlaneValues(IswPlaneValues&&) noexcept;
  IswPlaneValues& operator=(IswPlaneValues&&) noexcept;

  // Plane stream bytes at each plane's end in the file written, ascending
  // (as stream_plane_ends()); empty before an encoding.
  const std::vector<std::uint64_t>& plane_ends() const;
  // The coefficients (base control points first, world units) after the
  // first k + 1 planes, into `out` (resized to the fine count).
  // Precondition: k < plane_ends().size(). Cost: O(fine vertices), parallel.
  void coefficients_at(std::size_t k, std::vector<Vec3>& out) const;
  // The unit normal of every entry's local frame in the file written (as
  // isw_frame_normals() of its frame base); empty before an encoding.
  const std::vector<Vec3>& frame_normals() const;
  // The estimated bits of the whole plane stream encoded (before any cut to
  // max_bytes), by what they code; zero before an encoding.
  const IswPlaneBits& plane_bits() const;

 private:
  friend std::string encode_isw(const SubdivisionHierarchy&, const std::vector<Vec3>&, const IswMetadata&,
                                const IswEncodeOptions&, IswPlaneValues&);
  std::unique_ptr<detail::PlaneValuesState> state_;
};

// encode_isw() of a version 2 file (Error(InvalidArgument) for another
// options.major_version), `planes` receiving what its plane ends decode to.
std::string encode_isw(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options, IswPlaneValues& planes);

// The coefficients exactly as encode_isw() stores them (version 1) (quantized per class
// with step / class_weights[c], then scaled back): lets a caller measure the
// quantization error before encoding. Errors as encode_isw(). Cost: O(fine vertices).
std::vector<Vec3> quantize_coefficients(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                                        double step, const std::vector<double>& class_weights);

struct IswSectionInfo {
  std::string tag;                 // 4 characters, e.g. "CHNK", "END "
  std::uint64_t offset = 0;        // of the section header in the file, bytes
  std::uint64_t bytes = 0;         // whole section: header, payload, CRC
  std::uint64_t coefficients = 0;  // CHNK only: the wavelet coefficients it sends
};

// Version 2: the plane stream of a decode.
struct IswStreamInfo {
  std::uint64_t offset = 0;   // file offset of the first packet byte
  std::uint64_t bytes = 0;    // packet bytes in the file
  std::uint64_t decoded = 0;  // packet bytes the decode read (complete packets, and the cut one)
  int top_plane = -1;         // -1: every coefficient below the step
  int planes = 0;             // planes in the file (the last may be cut, some of its packets missing)
  int planes_decoded = 0;     // planes decoded completely (every group's packet)
  std::vector<std::uint64_t> plane_ends;  // cumulative packet bytes at each plane's end, as the file's table says
  double tangential_factor = 1;
  double frame_step = 0;      // world units
  std::vector<IswRatePoint> rate_table;  // RDTB, if the file has one
  // PCNT (2.2), if the file has one: per plane from the top, the wavelet
  // coefficients non-zero once it is decoded; a coefficient limit then reads
  // a prefix (docs/FORMAT.md, "Percentages").
  std::vector<std::uint64_t> plane_counts;
  std::size_t groups = 0;           // the planes' independent groups
  std::size_t groups_decoded = 0;   // those decoded (all, but with a region of a 2.2 file)
};

// Wall-clock seconds of the decoder's phases (for benchmarks; not part of the
// decoded content).
struct IswDecodeTimings {
  double read = 0;        // read_isw: reading the file
  double headers = 0;     // the sections before the hierarchy starts (base mesh decoded and checked)
  double hierarchy = 0;   // building the subdivision hierarchy (on another thread, during the chunks)
  double hierarchy_wait = 0;  // waiting for it after the chunks
  double chunks = 0;      // range decoding the coefficient chunks
  double rank = 0;        // ranking each chunk's coefficients by importance
  double dequantize = 0;  // the coarse-to-fine coefficient array
};

struct RegionPatch;  // region.h

struct IswDecoded {
  std::uint16_t major_version = 0, minor_version = 0;  // the file's, from its header
  IswMetadata metadata;
  PolygonMesh base;  // topology and sharp flags (manifold); positions are the base control points
  int levels = 0;    // 0..8
  double step = 0;   // world units, > 0 (see IswEncodeOptions::step)
  std::vector<double> class_weights;  // 1 + 2 levels values, each > 0
  // Coarse-to-fine array (base control points, then wavelet coefficients);
  // coefficients not decoded (not yet sent, or quantized to zero) are zero.
  std::vector<Vec3> coefficients;
  // Importance rank order of the decoded wavelet coefficients: indices into
  // `coefficients`, most important first (the order the encoder ranked them),
  // or ascending with IswOrder::Index.
  std::vector<std::uint32_t> ranked;
  std::vector<IswSectionInfo> sections;  // in file order, unknown tags included
  // Bytes read from the file: all of them, but with options.region (a 2.2
  // file read by read_isw) the sections before the packets and the packets
  // of the groups the region needs.
  std::uint64_t file_bytes_read = 0;
  std::uint64_t file_bytes = 0;  // the file's size
  IswStreamInfo stream;                  // version 2
  // The subdivision hierarchy of `base` and `levels` (options.hierarchy when
  // that one matches the file); none after a region decode of a 2.2 file.
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  // That hierarchy's fine and base control points (set by every decode).
  std::size_t fine_vertices = 0, base_vertices = 0;
  // A region decode of a 2.2 file (options.region): the patch of the base
  // it built and decoded, in place of `hierarchy` and `coefficients`
  // (region.h).
  std::shared_ptr<const RegionPatch> patch;
  // Version 1: chunks the encoder wrote (QUAN) and those decoded; version 2:
  // planes (PLNS) and complete planes decoded.
  std::size_t chunks_total = 0;
  std::size_t chunks_decoded = 0;
  std::uint64_t coefficients_total = 0;  // non-zero coefficients the encoder wrote
  bool truncated = false;          // the file ends inside the coefficient chunks or before END
  std::string truncation_note;     // what was decoded, when truncated
  IswDecodeTimings seconds;
};

// The order of IswDecoded::ranked.
enum class IswOrder {
  Importance,  // most important first (the paper's ranking)
  Index,       // ascending index: no sort (version 2 without a coefficient limit only)
};

struct IswDecodeOptions {
  // Stop after this many ranked coefficients have been decoded (whole chunks
  // are read; the excess of the last one is discarded). A decode that stops
  // early is not truncated.
  std::uint64_t max_coefficients = UINT64_MAX;
  // The same limit as a percentage of full resolution, counted as the paper
  // does (see coefficients_for_percent), in [0, 100]; the smaller limit applies.
  double max_percent = 100;
  // Version 2: decode at most this many bytes of the plane stream, or the
  // prefix the file's RDTB gives for D <= max_error_cells (cells of the
  // file's cell_size; > 0; the whole stream when no row reaches it or there
  // is no RDTB; Error(InvalidArgument) for a file without a cell size or of
  // version 1); the smaller applies.
  std::uint64_t max_stream_bytes = UINT64_MAX;
  double max_error_cells = 0;
  // Decode only the first max_file_bytes bytes of the file (a prefix; for
  // version 2 any prefix past BPTS decodes). Not reported as truncated.
  std::uint64_t max_file_bytes = UINT64_MAX;
  // Version 2 without a coefficient limit: IswOrder::Index skips ranking
  // (a sort of every non-zero coefficient) when the caller needs only the
  // surface. A limit always ranks by importance.
  IswOrder order = IswOrder::Importance;
  // Version 2: what a coefficient limit keeps by (importance.h); `ranked`
  // then lists the kept ones by that oracle. Oracle::Greedy costs
  // keep_greedy()'s syntheses on top of the decode.
  Oracle oracle = Oracle::Weighted;
  // Read only the metadata, base mesh and section table (for `info`, and a
  // viewer's first frame): the base mesh's topology is checked, no hierarchy
  // built (IswDecoded::hierarchy is options.hierarchy when that one is the file's).
  bool headers_only = false;
  // A region decode with nothing kept outside (region_mesh()). Version 2.2:
  // decodes only the plane-stream groups whose coefficients the fine control
  // points near `region` depend on, over a patch of the base (IswDecoded::
  // patch) without the whole hierarchy; read_isw() then reads only those
  // groups' packets. Earlier versions decode every group.
  std::optional<RegionOfInterest> region;
  // Version 2.2, as `region` for the faces that may lie in this camera's
  // view frustum (a view decode); ignored with `region`.
  std::optional<Camera> frustum;
  // With `frustum`: what a 2.2 file's decode builds.
  enum class ViewScope {
    Whole,  // the whole hierarchy (a ViewRefiner, which refines wherever the camera turns)
    Patch,  // a patch around the frustum's faces, as for `region` (view_mesh() of this camera)
  };
  ViewScope view_scope = ViewScope::Whole;
  // A hierarchy the caller already has (convert checking its own output):
  // used when its base topology, sharp flags and level count equal the
  // file's, which saves building one (the hierarchy is the decode's largest
  // allocation); otherwise ignored.
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
};

// What decode_isw(bytes) returns, made without decoding the chunks (which is
// serial) when `bytes` is what encode_isw() wrote from the hierarchy, with
// `stored` = quantize_coefficients() of its coefficients and `ranked` the
// order encode_isw() reported: convert summarizes its file with it. Throws
// Error(InvalidArgument) when the file's levels or base topology differ from
// the hierarchy's or the counts do not match. Cost: the header sections.
IswDecoded expected_decode(const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, std::vector<Vec3> stored,
                          std::vector<std::uint32_t> ranked, const std::string& bytes, const std::string& name);

// The plane stream bytes a decode keeping `keep` wavelet coefficients reads
// of the file whose complete decode is `decoded`: with PCNT, the planes
// docs/FORMAT.md ("Percentages") names, else (or when they are all of them)
// decoded.stream.bytes. Cost: O(planes).
std::uint64_t stream_bytes_for_keep(const IswDecoded& decoded, std::uint64_t keep);

// Decodes an .isw file's bytes; `name` heads error messages. Errors:
// Error(Format) for anything that is not a well-formed file (naming the
// section and byte offset; "truncated" for a file cut before the coefficient
// stream, "corrupt" for a CRC mismatch or impossible values),
// Error(Unsupported) for another major version. Cost: linear in the bytes
// (the chunks are decoded serially), plus building the hierarchy on another
// thread meanwhile.
IswDecoded decode_isw(const std::string& bytes, const std::string& name, const IswDecodeOptions& options = {});

// Reads a file (Error(Io) if it cannot) and decodes it: the whole file, or
// with options.region only the bytes that region needs (a 2.2 file).
IswDecoded read_isw(const std::string& path, const IswDecodeOptions& options = {});

// Writes bytes atomically; refuses to replace an existing file unless
// `overwrite` (Error(Io)).
void write_isw(const std::string& path, const std::string& bytes, bool overwrite);

}  // namespace isowave
