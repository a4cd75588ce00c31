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
// approximation. Decoding treats every byte as hostile: every count is checked
// against the bytes present before anything is allocated and the work is
// linear in the file size; a corrupt section (bad CRC, impossible values) is
// an Error(Format) naming the section; a file cut inside the coefficient
// chunks decodes the complete chunks and says so (IswDecoded::truncated).
// Sources: isw_sections (framing, CRCs), isw_encoder, isw_decoder (one
// function per section), isw_models (what both must compute alike).
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// A reader decodes every minor version of its major version (it skips the
// sections it does not know) and refuses other majors (Error(Unsupported)).
constexpr std::uint16_t kIswMajorVersion = 1;
constexpr std::uint16_t kIswMinorVersion = 0;

struct IswMetadata {
  // Free-form but conventional keys (docs/FORMAT.md, META): source, isovalue,
  // spacing, origin, cell_size, levels, extracted_vertices, quantization_rmse,
  // options, ... Keys lose '=' and line breaks when written, values line breaks.
  std::map<std::string, std::string> values;

  // The value of `key` as a finite number, else `fallback` (missing or not a number).
  double number(const std::string& key, double fallback) const;
  std::string text(const std::string& key, const std::string& fallback = {}) const;
};

struct IswEncodeOptions {
  // Quantization step for importance-weighted coefficients, in world units,
  // finite and > 0: a coefficient of class c is quantized with step / weight_c,
  // so every kept coefficient adds about the same error to the fine control
  // points. The expected RMSE added over the fine points is about step / 2.
  double step = 0.01;
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
// `ranked`, if given, receives the indices of the non-zero quantized wavelet
// coefficients in the order the file sends them (as a decode lists them).
std::string encode_isw(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                       const IswMetadata& metadata, const IswEncodeOptions& options = {},
                       std::vector<std::uint32_t>* ranked = nullptr);

// The coefficients exactly as encode_isw() stores them (quantized per class
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
  PolygonMesh base;  // topology and sharp flags (manifold); positions are the base control points
  int levels = 0;    // 0..8
  double step = 0;   // world units, > 0 (see IswEncodeOptions::step)
  std::vector<double> class_weights;  // 1 + 2 levels values, each > 0
  // Coarse-to-fine array (base control points, then wavelet coefficients);
  // coefficients not decoded (not yet sent, or quantized to zero) are zero.
  std::vector<Vec3> coefficients;
  // Importance rank order of the decoded wavelet coefficients: indices into
  // `coefficients`, most important first (the order the encoder ranked them).
  std::vector<std::uint32_t> ranked;
  std::vector<IswSectionInfo> sections;  // in file order, unknown tags included
  // The subdivision hierarchy of `base` and `levels` (options.hierarchy when
  // that one matches the file).
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  std::size_t chunks_total = 0;    // chunks the encoder wrote (from QUAN)
  std::size_t chunks_decoded = 0;  // chunks_total unless truncated or stopped at the limit
  std::uint64_t coefficients_total = 0;  // non-zero coefficients the encoder wrote
  bool truncated = false;          // the file ends inside the coefficient chunks or before END
  std::string truncation_note;     // what was decoded, when truncated
  IswDecodeTimings seconds;
};

struct IswDecodeOptions {
  // Stop after this many ranked coefficients have been decoded (whole chunks
  // are read; the excess of the last one is discarded). A decode that stops
  // early is not truncated.
  std::uint64_t max_coefficients = UINT64_MAX;
  // The same limit as a percentage of full resolution, counted as the paper
  // does (see coefficients_for_percent), in [0, 100]; the smaller limit applies.
  double max_percent = 100;
  // Read only the metadata, base mesh and section table (for `info`).
  bool headers_only = false;
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

// Decodes an .isw file's bytes; `name` heads error messages. Errors:
// Error(Format) for anything that is not a well-formed file (naming the
// section and byte offset; "truncated" for a file cut before the coefficient
// stream, "corrupt" for a CRC mismatch or impossible values),
// Error(Unsupported) for another major version. Cost: linear in the bytes
// (the chunks are decoded serially), plus building the hierarchy on another
// thread meanwhile.
IswDecoded decode_isw(const std::string& bytes, const std::string& name, const IswDecodeOptions& options = {});

// Reads a whole file (Error(Io) if it cannot) and decodes it.
IswDecoded read_isw(const std::string& path, const IswDecodeOptions& options = {});

// Writes bytes atomically; refuses to replace an existing file unless
// `overwrite` (Error(Io)).
void write_isw(const std::string& path, const std::string& bytes, bool overwrite);

}  // namespace isowave
