#pragma once
// Rate-distortion table of an .isw file, as the paper's Table 1: for each
// percentage of full resolution, the coefficients kept (base vertices
// included), the RMS and maximum distance over the fine control points
// between the reconstruction and the full-resolution decode, and the bytes a
// progressive reader needs to reach it.
#include <vector>

#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"

namespace isowave {

struct RateDistortionRow {
  double percent = 0;                // of the fine control points
  std::size_t kept = 0;              // base vertices + kept wavelet coefficients
  std::size_t wavelet_coefficients = 0;
  double rms = 0;                    // world units
  double max = 0;                    // world units
  std::uint64_t bytes = 0;           // file prefix a reader needs (headers, base, chunks up to this rank)
  bool is_base = false;
};

// `decoded` must be a complete decode (all chunks). Rows for each percent (in
// the given order), then the base mesh alone. Errors are measured against
// `reference` (fine control points, e.g. the unquantized fitted ones) if
// given, else against the full-resolution decode. Cost: one synthesis per row,
// except that with `reference` and `all_decoded_errors` (the errors of the
// synthesis of every decoded coefficient against it, which the caller
// measured already, e.g. before encoding them) rows keeping every decoded
// coefficient take those errors instead.
std::vector<RateDistortionRow> rate_distortion(const IswDecoded& decoded, const std::vector<double>& percents,
                                               const std::vector<Vec3>* reference = nullptr,
                                               const PointErrors* all_decoded_errors = nullptr);

// Control points of the finest level from the `keep` most important decoded
// coefficients (base always kept).
std::vector<Vec3> reconstruct(const IswDecoded& decoded, std::size_t keep, int level = -1);
// The same, synthesizing in the decoded coefficient array itself, which it
// takes out of `decoded` (left empty; the other members stay valid): spares
// a copy of a fine-mesh-sized array when one reconstruction is all the caller
// needs.
std::vector<Vec3> take_reconstruction(IswDecoded& decoded, std::size_t keep, int level = -1);

}  // namespace isowave
