// Staadt, Gross and Weber's greedy oracle (importance.h, keep_greedy).
#include <algorithm>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/codec/importance.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {
namespace {

constexpr std::size_t kGrain = 1 << 14;

// The error each candidate's rejection adds (Eq. 7): |c|^2 ||psi||^2 + 2 c . g,
// g = S^T S c_R (empty before the first rejection).
void score_candidates(const std::vector<Vec3>& coefficients, const std::vector<double>& squared_norms,
                      const std::vector<Vec3>& gradient, const std::vector<std::uint32_t>& candidates,
                      std::vector<double>& score) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), kGrain), [&](const auto& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      const std::uint32_t i = candidates[k];
      const Vec3& c = coefficients[i];
      double s = squared_norms[i] * dot(c, c);
      if (!gradient.empty()) s += 2 * dot(c, gradient[i]);
      score[i] = s;
    }
  });
}

// S^T S applied to the rejected coefficients (base entries zero): the cross
// terms of every later rejection with all earlier ones.
std::vector<Vec3> rejected_gradient(const SubdivisionHierarchy& hierarchy, std::vector<Vec3> rejected) {
  synthesize(hierarchy, rejected);
  for (int level = hierarchy.levels(); level >= 1; --level) synthesize_level_transpose(hierarchy, level, rejected);
  return rejected;
}

}  // namespace

std::vector<std::uint32_t> keep_greedy(const SubdivisionHierarchy& hierarchy, std::vector<Vec3>& coefficients,
                                       std::size_t keep, double smallest_batch) {
  assert(smallest_batch > 0 && coefficients.size() >= hierarchy.fine_vertex_count());
  const CoefficientClasses classes(hierarchy);
  std::vector<std::uint32_t> candidates;
  for (std::size_t i = classes.base(); i < classes.fine(); ++i)
    if (!(coefficients[i] == Vec3{})) candidates.push_back(static_cast<std::uint32_t>(i));
  const std::size_t total = candidates.size();
  const std::vector<double> squared_norms = wavelet_squared_norms(hierarchy);

  // Reject in rounds, each half of what is left but at least the smallest
  // batch, re-scoring against everything rejected so far.
  const auto least = std::max<std::size_t>(1, static_cast<std::size_t>(smallest_batch * static_cast<double>(keep)));
  std::vector<double> score(classes.fine(), 0.0);
  std::vector<Vec3> rejected(classes.fine()), gradient;
  const auto by_score = [&](std::uint32_t a, std::uint32_t b) { return score[a] < score[b] || (score[a] == score[b] && a < b); };
  while (candidates.size() > keep) {
    const std::size_t left = candidates.size() - keep;
    // Keeping none leaves nothing to choose.
    const std::size_t batch = keep == 0 ? left : std::min(left, std::max(least, (left + 1) / 2));
    score_candidates(coefficients, squared_norms, gradient, candidates, score);
    std::nth_element(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(batch), candidates.end(), by_score);
    for (std::size_t k = 0; k < batch; ++k) std::swap(rejected[candidates[k]], coefficients[candidates[k]]);
    candidates.erase(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(batch));
    if (candidates.size() > keep) gradient = rejected_gradient(hierarchy, rejected);
  }

  // The kept ones, by what their rejection would have added in the last
  // round (largest first).
  if (candidates.size() == total) score_candidates(coefficients, squared_norms, gradient, candidates, score);
  std::sort(candidates.begin(), candidates.end(), [&](std::uint32_t a, std::uint32_t b) { return by_score(b, a); });
  return candidates;
}

}  // namespace isowave
