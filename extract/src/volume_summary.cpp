// The value range, histogram and misread-sample warnings of a volume.
#include "isowave/extract/volume_summary.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>

namespace isowave {
namespace {

std::string format(const char* pattern, double a, double b = 0) {
  char text[160];
  std::snprintf(text, sizeof text, pattern, a, b);
  return text;
}

template <typename T>
T byte_swapped(T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  std::reverse(bytes, bytes + sizeof(T));
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

// Mean |g(i+1, j, k) - g(i, j, k)| along x over pairs of finite g, as a share
// of the range of the finite g (0 when constant), g = read(sample).
template <class Read>
double relative_neighbour_step(const std::vector<float>& values, std::size_t nx, const Read& read) {
  double low = std::numeric_limits<double>::infinity(), high = -low, sum = 0, previous = 0;
  std::size_t steps = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double g = read(values[i]);
    if (!std::isfinite(g)) continue;
    low = std::min(low, g);
    high = std::max(high, g);
    if (i % nx != 0 && std::isfinite(read(values[i - 1]))) {
      sum += std::abs(g - previous);
      ++steps;
    }
    previous = g;
  }
  return steps > 0 && high > low ? sum / double(steps) / (high - low) : 0.0;
}

}  // namespace

ValueSummary summarize_values(const Volume& volume) {
  ValueSummary s;
  double low = std::numeric_limits<double>::infinity(), high = -low;
  for (const float value : volume.values) {
    if (std::isnan(value)) {
      ++s.nan;
    } else if (std::isinf(value)) {
      ++s.infinite;
    } else {
      ++s.finite;
      low = std::min(low, double(value));
      high = std::max(high, double(value));
    }
  }
  if (s.finite == 0) return s;
  s.min = low;
  s.max = high;
  s.neighbour_step = relative_neighbour_step(volume.values, volume.dims[0], [](float value) { return value; });
  switch (volume.source_type) {
    case ScalarType::UInt16:
      s.swapped_neighbour_step = relative_neighbour_step(volume.values, volume.dims[0], [](float value) {
        return float(byte_swapped(static_cast<std::uint16_t>(value)));
      });
      break;
    case ScalarType::Int16:
      s.swapped_neighbour_step = relative_neighbour_step(volume.values, volume.dims[0], [](float value) {
        return float(byte_swapped(static_cast<std::int16_t>(value)));
      });
      break;
    default: break;
  }
  return s;
}

std::string value_range_text(const ValueSummary& s) {
  const std::string counts = ", " + std::to_string(s.nan) + " NaN, " + std::to_string(s.infinite) + " Inf";
  if (s.finite == 0) return "no finite values" + counts;
  return format("values %.9g .. %.9g", s.min, s.max) + counts;
}

std::vector<std::string> value_warnings(const ValueSummary& s) {
  const std::string cause = "a wrong --endian or --type?";
  std::vector<std::string> warnings;
  if (s.nan + s.infinite > 0) {
    const double share = double(s.nan + s.infinite) / double(s.nan + s.infinite + s.finite);
    warnings.push_back(std::to_string(s.nan + s.infinite) + " samples are NaN or Inf (" +
                       format("%.3g%%", 100 * share) + ", read as outside the surface): " + cause);
  }
  if (s.finite > 0 && std::max(std::abs(s.min), std::abs(s.max)) > kAbsurdMagnitude)
    warnings.push_back(format("values reach %.3g, beyond what any instrument or simulation writes: ",
                              std::abs(s.min) > std::abs(s.max) ? s.min : s.max) +
                       cause);
  if (s.swapped_neighbour_step >= 0 && s.swapped_neighbour_step * kSwappedSmootherFactor < s.neighbour_step)
    warnings.push_back(format("in the other byte order the samples would be %.0f times smoother: ",
                              s.neighbour_step / std::max(s.swapped_neighbour_step, 1e-300)) +
                       cause);
  if (s.neighbour_step > kNoiseNeighbourStep)
    warnings.push_back(format("neighbouring samples differ by %.0f%% of the value range on average, as in noise: ",
                              100 * s.neighbour_step) +
                       cause);
  return warnings;
}

std::vector<std::size_t> value_histogram(const Volume& volume, const ValueSummary& summary, int bins) {
  assert(bins >= 1);
  std::vector<std::size_t> counts(static_cast<std::size_t>(bins), 0);
  const double width = (summary.max - summary.min) / bins;
  for (const float value : volume.values) {
    if (!std::isfinite(value)) continue;
    const double position = width > 0 ? (double(value) - summary.min) / width : 0.0;
    counts[static_cast<std::size_t>(std::clamp(position, 0.0, double(bins - 1)))]++;
  }
  return counts;
}

Error empty_isosurface_error(const std::string& source, double iso, const Volume& volume, double tolerance_cells) {
  if (tolerance_cells > 0)
    return Error(ErrorKind::EmptyResult,
                 source + ": the topology tolerance of " + format("%g", tolerance_cells) +
                     " cells removed the whole isosurface at " + format("%.9g", iso) +
                     " (every component is smaller); a smaller --topology-tolerance keeps it");
  const ValueSummary s = summarize_values(volume);
  std::string where;
  if (s.finite == 0) where = " (no finite samples)";
  else if (iso > s.max) where = format(" (every finite sample is below it: values range %.9g .. %.9g)", s.min, s.max);
  else if (iso <= s.min) where = format(" (every finite sample is at or above it: values range %.9g .. %.9g)", s.min, s.max);
  else where = format(" (values range %.9g .. %.9g)", s.min, s.max);
  return Error(ErrorKind::EmptyResult, source + ": the isosurface at " + format("%.9g", iso) + " is empty" + where);
}

}  // namespace isowave
