#include "isowave/simplify/collapse_error.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <vector>

namespace isowave::simplify {

CollapseErrorTerms collapse_error_terms(const Vec3& d, const Vec3* cross_products, std::size_t k) {
  constexpr std::size_t kChunk = 64;
  double squared_norms[kChunk];
  if (k > kChunk) {
    std::vector<double> squared(k);
    for (std::size_t i = 0; i < k; ++i) squared[i] = squared_norm(cross_products[i]);
    return collapse_error_terms(d, cross_products, squared.data(), k);
  }
  for (std::size_t i = 0; i < k; ++i) squared_norms[i] = squared_norm(cross_products[i]);
  return collapse_error_terms(d, cross_products, squared_norms, k);
}

CollapseErrorTerms collapse_error_terms(const Vec3& d, const Vec3* cross_products, const double* squared_norms,
                                        std::size_t k) {
  CollapseErrorTerms terms;
  const Vec3 half_d = d * 0.5;
  Vec3 normal_sum;
  double max_length = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const double length = std::sqrt(squared_norms[i]);  // = norm(cross_products[i]), bit for bit
    max_length = std::max(max_length, length);
    if (length <= 0) continue;
    const Vec3 unit = cross_products[i] * (1.0 / length);
    normal_sum += unit;
    terms.delta_e0 = std::max(terms.delta_e0, std::abs(dot(half_d, unit)));
  }
  const Vec3 average_normal = normalized(normal_sum * (1.0 / static_cast<double>(k)));
  double ratio = 0;
  if (max_length > 0) {
    double min_projection = dot(cross_products[0], average_normal);
    for (std::size_t i = 1; i < k; ++i) min_projection = std::min(min_projection, dot(cross_products[i], average_normal));
    ratio = min_projection / max_length;
  }
  terms.delta_e1 = std::max(terms.delta_e0, kMinDeltaError);
  // (2 - ratio)^16 by repeated squaring.
  double w = 2.0 - ratio;
  w *= w;
  w *= w;
  w *= w;
  w *= w;
  terms.weight = w;
  terms.delta_e = w * terms.delta_e1;
  return terms;
}

namespace {
const double kLowest = std::log(1e-10);
const double kRange = std::log(1e10) - std::log(1e-10);
}  // namespace

std::uint32_t priority_bucket(double error, std::uint32_t bucket_count) {
  if (!(error == error)) return 0;  // NaN: lowest priority
  if (error <= 0) return bucket_count - 1;
  const double priority = -std::log(error);  // log(1/E)
  const double position = (priority - kLowest) / kRange * bucket_count;
  if (!(position > 0)) return 0;
  if (position >= bucket_count) return bucket_count - 1;
  return static_cast<std::uint32_t>(position);
}

std::uint32_t priority_bucket_span(double error_factor, std::uint32_t bucket_count) {
  assert(error_factor >= 1);
  const double span = std::log(error_factor) / kRange * bucket_count;
  return span >= bucket_count ? bucket_count : static_cast<std::uint32_t>(span);
}

}  // namespace isowave::simplify
