#pragma once
// The error estimate of one edge collapse and its bucket priority, paper
// Sec. 4.1, equations (4.1)-(4.3). Pure functions of a few vectors so that the
// formulas can be tested on hand-built neighbourhoods.
#include <cstddef>
#include <cstdint>

#include "isowave/core/vec3.h"

namespace isowave::simplify {

// The parts of (4.1)-(4.2) for one collapse.
struct CollapseErrorTerms {
  double delta_e0 = 0;  // (4.1): max_i |(d/2) . n_i|
  double delta_e1 = 0;  // max(delta_e0, 1e-8)
  double weight = 0;    // (2 - min_i(c_i . n) / max_i |c_i|)^16, in [1, 3^16]
  double delta_e = 0;   // (4.2): weight * delta_e1
};

// Lower clamp of (4.1), "to allow priority distinctions in skewed/tangled
// planar neighbourhoods".
constexpr double kMinDeltaError = 1e-8;

// Evaluates (4.1) and (4.2).
//   d:              v_j - v_i, the collapsed edge as a vector.
//   cross_products: c_0..c_{k-1}, the cross products (w_t - p) x (w_{t+1} - p)
//                   of consecutive ring edges around the new vertex p, i.e. the
//                   (unnormalised) normals of the k triangles around p after the
//                   collapse; k >= 1.
// n_i = c_i / |c_i| (a zero c_i contributes a zero normal). The paper calls
// n = (1/k) sum n_i the "unit average normal"; we normalise that average so
// that it is a unit vector as the text says (a zero average gives n = 0 and
// hence the largest weight for a tangled ring of ratio 0). If every c_i is
// zero the ratio min(c_i . n) / max|c_i| is taken as 0. O(k).
CollapseErrorTerms collapse_error_terms(const Vec3& d, const Vec3* cross_products, std::size_t k);
// The same with squared_norms[i] = squared_norm(cross_products[i]) supplied
// by a caller that has them already (the collapse evaluation does).
CollapseErrorTerms collapse_error_terms(const Vec3& d, const Vec3* cross_products, const double* squared_norms,
                                        std::size_t k);

// Priority bucket of a total error E (4.3): the priority log(1/E) is
// discretised into bucket_count equal buckets over [log 1e-10, log 1e10];
// bucket bucket_count - 1 holds the highest priority (E <= 1e-10) and bucket 0
// the lowest (E >= 1e10); values outside the range are clamped, E <= 0 or NaN
// go to the highest and lowest bucket respectively. bucket_count >= 1.
std::uint32_t priority_bucket(double error, std::uint32_t bucket_count);
// The number of whole buckets spanned by errors within a factor
// `error_factor` (>= 1) of each other: floor(log(error_factor) / bucket width).
std::uint32_t priority_bucket_span(double error_factor, std::uint32_t bucket_count);

}  // namespace isowave::simplify
