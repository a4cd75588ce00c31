#include "isw_models.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <utility>

#include <tbb/parallel_sort.h>

namespace isowave::detail {

std::vector<std::vector<std::uint32_t>> earlier_neighbours(const PolygonMesh& base) {
  std::vector<std::vector<std::uint32_t>> result(base.vertex_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t n = base.face_size(f);
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t a = base.face_begin(f)[k], b = base.face_begin(f)[(k + 1) % n];
      if (a < b) result[b].push_back(a);
      else result[a].push_back(b);
    }
  }
  for (auto& list : result) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return result;
}

QuantizedVector predict_base(const std::vector<QuantizedVector>& q, const std::vector<std::uint32_t>& neighbours,
                             std::size_t index) {
  if (neighbours.empty()) return index == 0 ? QuantizedVector{0, 0, 0} : q[index - 1];
  QuantizedVector p{};
  for (int axis = 0; axis < 3; ++axis) {
    std::int64_t sum = 0;
    for (std::uint32_t n : neighbours) sum += q[n][axis];
    const auto count = static_cast<std::int64_t>(neighbours.size());
    p[axis] = sum >= 0 ? (sum + count / 2) / count : -((-sum + count / 2) / count);
  }
  return p;
}

double importance_key(int cls, const QuantizedVector& q, double step, const std::vector<double>& weights) {
  const auto c = static_cast<std::size_t>(cls);
  const double s = step / weights[c];
  return weights[c] * norm(Vec3{q[0] * s, q[1] * s, q[2] * s});
}

void sort_by_importance(std::vector<RankedEntry>& entries) {
  const auto by_index = [](const RankedEntry& a, const RankedEntry& b) { return a.index < b.index; };
  const bool positive_keys = std::all_of(entries.begin(), entries.end(), [](const RankedEntry& e) {
    return e.key > 0 && e.key <= std::numeric_limits<double>::max();
  });
  if (entries.size() < (1u << 16) || !positive_keys || !std::is_sorted(entries.begin(), entries.end(), by_index)) {
    tbb::parallel_sort(entries.begin(), entries.end(), [](const RankedEntry& a, const RankedEntry& b) {
      return a.key > b.key || (a.key == b.key && a.index < b.index);
    });
    return;
  }
  // Entries in index order, keys positive and finite, whose bit patterns
  // order as their values: a stable radix sort on the complemented bits
  // (largest first) keeps ties in index order, several times faster than
  // a comparison sort of millions of entries.
  constexpr int kDigitBits = 16;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  const auto digit = [](double key, int shift) {
    std::uint64_t bits;
    std::memcpy(&bits, &key, sizeof bits);
    return static_cast<std::size_t>((~bits >> shift) & (kBuckets - 1));
  };
  std::vector<RankedEntry> buffer(entries.size());
  std::vector<std::size_t> start(kBuckets);
  for (int shift = 0; shift < 64; shift += kDigitBits) {
    std::fill(start.begin(), start.end(), 0);
    for (const RankedEntry& e : entries) ++start[digit(e.key, shift)];
    if (start[digit(entries.front().key, shift)] == entries.size()) continue;  // one digit: nothing moves
    std::size_t sum = 0;
    for (std::size_t& count : start) sum += std::exchange(count, sum);
    for (const RankedEntry& e : entries) buffer[start[digit(e.key, shift)]++] = e;
    entries.swap(buffer);
  }
}

}  // namespace isowave::detail
