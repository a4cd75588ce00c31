#pragma once
// One-dimensional root searches along a line, shared by the signed-distance
// seeding, the attraction step and the final isosurface correction.
#include <cmath>
#include <cstdlib>

namespace isowave::detail {

// "Inside" as in extraction: h >= 0 (NaN is outside).
inline bool root_side(double h) { return h >= 0; }

// Refines a bracket [a, b] (root_side(ha) != root_side(hb)) by the Illinois
// variant of regula falsi, falling back to bisection when a value is not
// finite, until the bracket is narrower than `tolerance` or a value is within
// `value_tolerance` of 0 (for distance fields, whose slope is 1, the two agree
// and the value test ends the search sooner). Returns the end of the final
// bracket with the smaller |h| (the inside end on a tie).
template <class H>
double refine_bracket(const H& h, double a, double ha, double b, double hb, double tolerance,
                      double value_tolerance = 0.0) {
  double weight_a = ha, weight_b = hb;  // Illinois: the stale end's value is halved
  int stale_side = 0;                   // which end stayed put last time
  for (int iteration = 0; iteration < 100 && std::abs(b - a) > tolerance; ++iteration) {
    double t;
    if (std::isfinite(weight_a) && std::isfinite(weight_b) && weight_a != weight_b) {
      t = a - weight_a * (b - a) / (weight_b - weight_a);
      const double lo = std::fmin(a, b), hi = std::fmax(a, b), margin = 1e-3 * (hi - lo);
      if (!(t > lo + margin && t < hi - margin)) t = 0.5 * (a + b);
    } else {
      t = 0.5 * (a + b);
    }
    const double ht = h(t);
    if (std::abs(ht) <= value_tolerance) return t;
    if (root_side(ht) == root_side(ha)) {
      a = t;
      ha = weight_a = ht;
      if (stale_side == 1) weight_b *= 0.5;
      stale_side = 1;
    } else {
      b = t;
      hb = weight_b = ht;
      if (stale_side == -1) weight_a *= 0.5;
      stale_side = -1;
    }
  }
  if (!std::isfinite(hb)) return a;
  if (!std::isfinite(ha)) return b;
  return std::abs(ha) <= std::abs(hb) ? a : b;
}

// Finds a root of h along t starting from 0 (h(0) = h0 != 0) in the direction
// of `guess` (a first-order estimate of the root), probing `guess` itself and
// then every `step` further out, up to |t| <= range. On success stores the
// refined root in `t` and returns true.
template <class H>
bool find_root_along_line(const H& h, double h0, double guess, double range, double step, double tolerance,
                          double& t) {
  if (h0 == 0) {
    t = 0;
    return true;
  }
  if (!std::isfinite(guess) || guess == 0) return false;
  const double direction = guess > 0 ? 1.0 : -1.0;
  double a = 0, ha = h0;
  double b = direction * std::fmin(std::abs(guess), range);
  for (;;) {
    const double hb = h(b);
    if (root_side(hb) != root_side(ha)) {
      t = refine_bracket(h, a, ha, b, hb, tolerance);
      return true;
    }
    if (std::abs(b) >= range) return false;
    a = b;
    ha = hb;
    b = direction * std::fmin(std::abs(b) + step, range);
  }
}

}  // namespace isowave::detail
