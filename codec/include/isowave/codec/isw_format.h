#pragma once
// The .isw file: a wavelet-compressed isosurface (documented in docs/FORMAT.md).
//
//   header   8-byte magic "\x89ISW\r\n\x1a\n", u16 major version, u16 minor version, u32 zero
//   sections [4-byte tag][u64 payload size][u32 CRC-32 of tag and size][payload][u32 CRC-32 of tag and payload]:
//            META  metadata as UTF-8 "key=value" lines
//            BASE  base mesh: counts, face sizes and indices (range coded), sharp flags
//            QUAN  quantization step and per-class wavelet weights
//            BPTS  base control points, quantized, predicted from decoded neighbours, range coded
//            CHNK  (several) wavelet coefficients, most important first: chunk k holds the coefficients
//                  ranked in [start_k, end_k) by importance, coded by significance flags over the
//                  coefficients not yet sent plus quantized components
//            END   empty
//
// Progressive: a reader may stop after any chunk and still rebuild a valid
// approximation. Every count is checked against the bytes present before
// anything is allocated; a corrupt section (bad CRC, impossible values) is an
// Error(Format) naming the section; a file cut inside the coefficient chunks
// decodes the complete chunks and says so.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

constexpr std::uint16_t kIswMajorVersion = 1;
constexpr std::uint16_t kIswMinorVersion = 0;

struct IswMetadata {
  // Free-form but conventional keys: source, isovalue, spacing, origin,
  // cell_size, levels, extracted_vertices, quantization_rmse, options, ...
  std::map<std::string, std::string> values;

  double number(const std::string& key, double fallback) const;
  std::string text(const std::string& key, const std::string& fallback = {}) const;
};

struct IswEncodeOptions {
  // Quantization step for importance-weighted coefficients, in world units:
  // a coefficient of class c is quantized with step / weight_c, so every kept
  // coefficient adds about the same error to the fine control points. The
  // expected RMSE added over the fine points is about step / 2.
  double step = 0.01;
  // Chunk boundaries in percent of full resolution (fine control points),
  // ascending; the remaining coefficients form the last chunk.
  std::vector<double> chunk_percents{1, 2, 3.5, 5, 7.5, 10, 15, 20, 30, 50, 75};
  // Per-class wavelet weights (wavelet_norms of the hierarchy); computed when
  // empty. Callers that already have them skip 1 + 2 L syntheses.
  std::vector<double> class_weights;
};

// Encodes a base mesh (topology and sharp flags; must pass require_manifold),
// a level count and the coarse-to-fine coefficient array of the analysis
// (base control points, then wavelet coefficients). Throws Error on invalid
// input. Cost: O(fine vertices log fine vertices).
std::string encode_isw(const PolygonMesh& base, int levels, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options = {});
// The same for a hierarchy already built (its base mesh and levels are coded).
// `ranked`, if given, receives the indices of the non-zero quantized wavelet
// coefficients in the order the file sends them (as a decode lists them).
std::string encode_isw(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options = {},
                       std::vector<std::uint32_t>* ranked = nullptr);

// The coefficients exactly as encode_isw() stores them (quantized per class
// with step / class_weights[c], then scaled back): lets a caller measure the
// quantization error before encoding.
std::vector<Vec3> quantize_coefficients(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                                        double step, const std::vector<double>& class_weights);

struct IswSectionInfo {
  std::string tag;
  std::uint64_t offset = 0;  // of the section header in the file
  std::uint64_t bytes = 0;   // whole section: header, payload, CRC
  std::uint64_t coefficients = 0;  // CHNK only
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

struct IswDecoded {
  std::uint16_t major_version = 0, minor_version = 0;  // the file's, from its header
  IswMetadata metadata;
  PolygonMesh base;  // topology and sharp flags; positions are the base control points
  int levels = 0;
  double step = 0;
  std::vector<double> class_weights;
  // Coarse-to-fine array (base control points, then wavelet coefficients);
  // coefficients not decoded (not yet sent, or quantized to zero) are zero.
  std::vector<Vec3> coefficients;
  // Importance rank order of the decoded wavelet coefficients: indices into
  // `coefficients`, most important first (the order the encoder ranked them).
  std::vector<std::uint32_t> ranked;
  std::vector<IswSectionInfo> sections;
  // The subdivision hierarchy of `base` and `levels` (options.hierarchy when
  // that one matches the file).
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  std::size_t chunks_total = 0;    // chunks the encoder wrote (from QUAN)
  std::size_t chunks_decoded = 0;
  std::uint64_t coefficients_total = 0;  // non-zero coefficients the encoder wrote
  bool truncated = false;          // the file ended inside the coefficient chunks
  std::string truncation_note;     // what was decoded, when truncated
  IswDecodeTimings seconds;
};

struct IswDecodeOptions {
  // Stop after this many ranked coefficients have been decoded (whole chunks
  // are read; the excess of the last one is discarded).
  std::uint64_t max_coefficients = UINT64_MAX;
  // The same limit as a percentage of full resolution, counted as the paper
  // does (see coefficients_for_percent); the smaller limit applies.
  double max_percent = 100;
  // Read only the metadata, base mesh and section table (for `info`).
  bool headers_only = false;
  // A hierarchy the caller already has (convert checking its own output):
  // used when its base topology, sharp flags and level count equal the
  // file's, which saves building one (seconds and about 190 bytes per fine
  // vertex at the peak); otherwise ignored.
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

// Decodes an .isw file's bytes; `name` is used in error messages.
IswDecoded decode_isw(const std::string& bytes, const std::string& name, const IswDecodeOptions& options = {});

// Reads a whole file (Error(Io) if it cannot) and decodes it.
IswDecoded read_isw(const std::string& path, const IswDecodeOptions& options = {});

// Writes bytes atomically; refuses to replace an existing file unless
// `overwrite` (Error(Io)).
void write_isw(const std::string& path, const std::string& bytes, bool overwrite);

}  // namespace isowave
