#pragma once
// What a volume's samples hold, for choosing an isovalue and for catching a
// misread file (a wrong --endian or --type reads as noise or as values near
// the float limits) before a conversion runs on it: the finite range, the
// NaN/Inf counts, a histogram and warnings.
#include <cstddef>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/core/volume.h"

namespace isowave {

struct ValueSummary {
  double min = 0, max = 0;  // of the finite samples (both 0 when there are none)
  std::size_t finite = 0, nan = 0, infinite = 0;
  // Mean |f(i+1, j, k) - f(i, j, k)| over pairs of finite samples along x, as
  // a share of max - min (0 for a constant field): sampled fields lie well
  // under 0.1; bytes read as the wrong type look like noise, about 1/3.
  double neighbour_step = 0;
  // The same measure with every sample's bytes in the other order, for int16
  // and uint16 samples (else -1), which the floats keep exactly: a file read
  // in the wrong order is many times smoother so. (Floats in the wrong order
  // show as NaN and values near the float limits instead.)
  double swapped_neighbour_step = -1;
};

// One pass over the samples: O(samples).
ValueSummary summarize_values(const Volume& volume);

// "values LOW .. HIGH, N NaN, M Inf" (or "no finite values, N NaN, M Inf").
std::string value_range_text(const ValueSummary& summary);

// Magnitudes beyond this are taken for misread samples: no simulation or
// scanner writes them, and byte-swapped floats reach up to 3.4e38.
constexpr double kAbsurdMagnitude = 1e30;
// A neighbour_step above this is taken for noise from misread bytes.
constexpr double kNoiseNeighbourStep = 0.2;
// A swapped_neighbour_step this many times smaller than neighbour_step is
// taken for samples read in the wrong byte order.
constexpr double kSwappedSmootherFactor = 4;

// One line each (no trailing period) for NaN/Inf samples, finite magnitudes
// beyond kAbsurdMagnitude, a neighbour_step above kNoiseNeighbourStep and a
// swapped_neighbour_step kSwappedSmootherFactor times smaller, each naming
// --endian and --type as the likely cause; empty when the samples look sound.
std::vector<std::string> value_warnings(const ValueSummary& summary);

// Counts of the finite samples in `bins` equal-width bins over
// [summary.min, summary.max] (the last bin closed); all in bin 0 for a
// constant field. bins >= 1. O(samples).
std::vector<std::size_t> value_histogram(const Volume& volume, const ValueSummary& summary, int bins);

// The error for an isosurface with no faces at `iso` (Error(EmptyResult):
// exit code 1, as for any failure that is not a usage error), naming the
// source, the isovalue and where it lies against the finite values; or, when
// a topology tolerance of `tolerance_cells` (> 0) removed every component,
// saying so.
Error empty_isosurface_error(const std::string& source, double iso, const Volume& volume,
                             double tolerance_cells = 0);

}  // namespace isowave
