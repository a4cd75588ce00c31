#pragma once
// The contouring's sample rules (contour.cpp), in one place for the code that
// must reproduce its connectivity exactly (the topology tolerance): which
// side a sample is on, where an edge's crossing lies, and which diagonal an
// ambiguous face joins.
#include <algorithm>
#include <cmath>
#include <limits>

namespace isowave::contour_rules {

// A crossing is kept this fraction of the edge away from both samples, so
// samples exactly at the isovalue never make zero-area triangles.
inline constexpr double kMinEdgeFraction = 1e-3;

// Inside: finite and >= iso; NaN and +-Inf are outside.
inline bool is_inside(float value, double iso) {
  const double v = value;
  return v >= iso && v <= std::numeric_limits<double>::max();
}

// The crossing on the edge from a sample of value `from` to one of value `to`
// on the other side, as a fraction of the edge from the first: the linear
// interpolation, clamped as above; the midpoint when a value is not finite.
inline double crossing_fraction(double from, double to, double iso) {
  if (!std::isfinite(from) || !std::isfinite(to)) return 0.5;
  const double t = (iso - from) / (to - from);
  return std::min(std::max(t, kMinEdgeFraction), 1.0 - kMinEdgeFraction);
}

// Asymptotic decider on an ambiguous face whose corners, in cyclic order,
// have values minus iso f0..f3 (corners 0 and 2 on one side): are its two
// inside corners joined? Commutative products only, so both cells sharing
// the face agree exactly; a NaN joins the outside pair.
inline bool inside_corners_joined(double f0, double f1, double f2, double f3, bool corner0_inside) {
  const double even = f0 * f2, odd = f1 * f3;
  return corner0_inside ? even >= odd : odd >= even;
}

}  // namespace isowave::contour_rules
