#pragma once
// Rate-distortion table of an .isw file, as the paper's Table 1: for each
// percentage of full resolution, the coefficients kept (base vertices
// included), the RMS and maximum distance over the fine control points
// between the reconstruction and the full-resolution decode, and the bytes a
// progressive reader needs to reach it. error_table() is the one definition
// convert and stats report (docs/FORMAT.md, "Errors").
#include <functional>
#include <string>
#include <vector>

#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"

namespace isowave {

struct RateDistortionRow {
  double percent = 0;                // of the fine control points, in (0, 100]
  std::size_t kept = 0;              // base vertices + kept wavelet coefficients
  std::size_t wavelet_coefficients = 0;
  double rms = 0;                    // world units, >= 0
  double max = 0;                    // world units, >= 0
  std::uint64_t bytes = 0;           // file prefix a reader needs (headers, base, and the chunks or planes the row reads)
  bool is_base = false;              // the row of the base mesh alone (the last)
};

// How far the full-resolution decode lies from the fitted fine control points
// (world units, over the fine control points): the error the quantization
// step adds, which no row shows. The encoder measures it (it alone has the
// fitted points) and records it in the file's metadata.
struct QuantizationError {
  double rms = 0;
  double max = 0;         // NaN when the file records the RMS alone (files of older encoders)
  bool recorded = false;  // false for files written without it: unknown, not zero
};

// What convert and stats report for a file: rows against the full-resolution
// decode (what a reader gets at 100%, so that row is zero) and, separately,
// the quantization error recorded in the metadata.
struct ErrorTable {
  std::vector<RateDistortionRow> rows;
  QuantizationError quantization;
};

// `decoded` must be a complete decode (all chunks; else Error(InvalidArgument)).
// Rows for each percent in [0, 100] (in the given order), then the base mesh
// alone. Errors are measured against `reference` (fine control points, at
// least as many as the fine level has) if given, else against the
// full-resolution decode. Cost: one synthesis per row, but rows keeping every
// decoded coefficient need none without `reference` (they are zero) or with
// `all_decoded_errors` (the errors of the synthesis of every decoded
// coefficient against `reference`, which the caller measured already); plus
// the full decode without `reference`.
// `visit`, if given, is called with each row's index, its wavelet
// coefficient count and the fine control points its synthesis gave (rows
// keeping every decoded coefficient have none), which it may use as
// scratch: convert measures each row's D there.
// `prefix_values`, if given, puts into its second argument the coefficients
// (base control points first, world units) a decode of the first
// `stream_bytes` plane stream bytes has: a row whose count reads a prefix
// (stream_bytes_for_keep()) then keeps the most important of those, as
// `decode --percent` does, and its `bytes` are that prefix (one call per
// distinct prefix, rows in the given order); other rows, and all without
// it, keep the complete decode's most important coefficients.
using RowSurfaceVisitor = std::function<void(std::size_t row, std::size_t wavelets, std::vector<Vec3>& surface)>;
using PrefixValues = std::function<void(std::uint64_t stream_bytes, std::vector<Vec3>& coefficients)>;
std::vector<RateDistortionRow> rate_distortion(const IswDecoded& decoded, const std::vector<double>& percents,
                                               const std::vector<Vec3>* reference = nullptr,
                                               const PointErrors* all_decoded_errors = nullptr,
                                               const RowSurfaceVisitor& visit = nullptr,
                                               const PrefixValues& prefix_values = nullptr);

// PrefixValues from a file's bytes (`file` must outlive it): one decode of
// the prefix per call.
PrefixValues decode_prefixes(const std::string& file);

// The error table of a complete decode (see rate_distortion; `prefix_values`
// as there) for `percents`, the base-mesh row last. `full_decode`, if given,
// must be the synthesis of every decoded coefficient (the caller has it
// already): it saves one synthesis. Throws Error(InvalidArgument) for a truncated decode. Cost: one
// synthesis per row below 100%, and the full decode unless given.
ErrorTable error_table(const IswDecoded& decoded, const std::vector<double>& percents,
                       const std::vector<Vec3>* full_decode = nullptr, const RowSurfaceVisitor& visit = nullptr,
                       const PrefixValues& prefix_values = nullptr);

// Writes `errors` (the full decode against the fitted points, world units)
// into the metadata keys quantization_rmse and quantization_max; the
// quantization error error_table() reads back.
void record_quantization_error(const PointErrors& errors, IswMetadata& metadata);
QuantizationError recorded_quantization_error(const IswMetadata& metadata);

// One line for users: the quantization error in percent of `cell_size`, or
// that the file does not record it.
std::string describe_quantization_error(const QuantizationError& error, double cell_size);

// Control points of level `level` (-1: the finest; else 0..levels) from the
// `keep` most important decoded coefficients (base always kept; a `keep`
// beyond the decoded ones keeps them all), world units. Throws
// Error(InvalidArgument) for a decode without a hierarchy (headers only).
// Cost: one synthesis, O(fine vertices).
std::vector<Vec3> reconstruct(const IswDecoded& decoded, std::size_t keep, int level = -1);
// The same, synthesizing in the decoded coefficient array itself, which it
// takes out of `decoded` (left empty; the other members stay valid): spares
// a copy of a fine-mesh-sized array when one reconstruction is all the caller
// needs.
std::vector<Vec3> take_reconstruction(IswDecoded& decoded, std::size_t keep, int level = -1);

}  // namespace isowave
