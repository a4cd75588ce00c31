#pragma once
// Private: what the .isw encoder and decoder must compute identically
// (docs/FORMAT.md, BASE, BPTS and CHNK): the coding contexts, the prediction
// of base control points, the importance order of the wavelet coefficients,
// and the format's size bounds.
#include <array>
#include <cstdint>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "range_coder.h"

namespace isowave::detail {

// Generous bounds that a hostile file cannot push the decoder past.
constexpr int kMaxLevels = 8;
constexpr std::uint64_t kMaxFineVertices = 1ull << 28;
constexpr std::uint64_t kFineVerticesPerFileByte = 4096;
// An adaptive binary decision costs at least ~0.02 bits and an integer at
// least six of them, so a coded byte holds at most ~64 integers.
constexpr std::uint64_t kMaxIntegersPerCodedByte = 64;
// The largest metadata text a version 2 file may inflate to.
constexpr std::uint32_t kMaxMetadataBytes = 1u << 20;
// Entries per TBB task in the per-coefficient loops.
constexpr std::size_t kParallelGrain = 1 << 14;

// One coefficient's (or base control point's) three quantized components.
using QuantizedVector = std::array<std::int64_t, 3>;

// Magnitude bucket of a quantized component: 0 for 0, 1 below 4, 2 below 64, else 3.
inline int magnitude_bucket(std::int64_t value) {
  const std::uint64_t m = static_cast<std::uint64_t>(value < 0 ? -value : value);
  return m == 0 ? 0 : (m < 4 ? 1 : (m < 64 ? 2 : 3));
}

// Coefficient chunk contexts: significance flags by class and previous flag;
// components by class, component and the previous coefficient's magnitude
// bucket. Fresh for every chunk.
struct ChunkModels {
  std::vector<std::array<Probability, 2>> flags;
  std::vector<IntegerModel> components;
  explicit ChunkModels(int classes)
      : flags(static_cast<std::size_t>(classes), {kProbabilityHalf, kProbabilityHalf}),
        components(static_cast<std::size_t>(classes) * 3 * 4) {}
  IntegerModel& component(int cls, int axis, int bucket) {
    return components[(static_cast<std::size_t>(cls) * 3 + static_cast<std::size_t>(axis)) * 4 +
                      static_cast<std::size_t>(bucket)];
  }
};

// BASE contexts: face size - 3, first index (delta to the previous face's),
// other indices (delta to the first), sharp vertex gaps.
struct BaseModels {
  IntegerModel face_size, first_index, other_index, sharp_gap;
};

// Neighbours of each base vertex with a smaller index: the decoded ones when
// base control points are decoded in index order. Cost: O(corners log valence).
std::vector<std::vector<std::uint32_t>> earlier_neighbours(const PolygonMesh& base);

// Prediction of base control point `index` from `q` (the points before it):
// the rounded mean of its earlier neighbours, else the previous point, else 0.
QuantizedVector predict_base(const std::vector<QuantizedVector>& q, const std::vector<std::uint32_t>& neighbours,
                             std::size_t index);

// The quantization step of class `cls`: step / weights[cls] (world units).
inline double class_step(double step, const std::vector<double>& weights, int cls) {
  return step / weights[static_cast<std::size_t>(cls)];
}

// Importance of a non-zero quantized coefficient: class weight times the
// dequantized magnitude. Encoder and decoder compute it from the same integers
// and weights, so they agree exactly.
double importance_key(int cls, const QuantizedVector& q, double step, const std::vector<double>& weights);

struct RankedEntry {
  double key;
  std::uint32_t index;
  std::uint32_t position;  // in the caller's list before sorting
};

// Sorts by importance (largest first), ties by index: a strict total order,
// so the result does not depend on the method. Cost: O(n) radix passes for
// large lists in index order with positive keys, else O(n log n).
void sort_by_importance(std::vector<RankedEntry>& entries);

}  // namespace isowave::detail
