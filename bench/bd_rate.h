#pragma once
// The Bjontegaard delta rate (BD-rate; Bjontegaard, VCEG-M33, 2001) of one
// rate-distortion curve against another, as issue #34 measures isowave
// against Draco: the mean of log rate(test, D) - log rate(anchor, D) over the
// range of log D both curves cover, reported as 100 (exp(mean) - 1) percent.
// Negative: the test curve needs fewer bits at equal distortion.
//
// Each curve is first reduced to its Pareto front (rate_distortion_front):
// the points no other point beats in both rate and distortion. Curves from
// prefixes or quantizer sweeps need not be monotone (a longer prefix can
// leave D where it was; a finer quantizer can cost more bits for no lower D),
// and the front makes log rate a strictly decreasing function of log D that
// interpolates safely. (Not the lower convex hull in (log D, log rate): a
// curve concave there, as Draco's quantizer sweep is, would be replaced by
// its chord, rates no setting reaches.) Between front points log rate is
// linear in log D (Bjontegaard fits a cubic; the piecewise linear form is
// exact for power laws rate = a D^-k and never overshoots), and the
// difference of the two curves is integrated exactly by the trapezoid rule
// over the union of both curves' breakpoints.
#include <vector>

namespace isowave::bench {

struct RatePoint {
  double rate = 0;        // bytes or bits, > 0 and finite
  double distortion = 0;  // any error measure, > 0 and finite
};

// The Pareto front of `points`: those with less rate than every point of
// less or equal distortion (of equal points, one), by increasing distortion
// and strictly decreasing rate. Points that are not positive and finite are
// dropped. Cost: O(n log n).
std::vector<RatePoint> rate_distortion_front(std::vector<RatePoint> points);

struct BdRate {
  // False when the curves' distortion ranges (of their fronts) share no
  // interval of positive length, or a curve has no valid point.
  bool overlap = false;
  double percent = 0;                      // 100 (exp(mean log rate ratio) - 1); with overlap
  double low_distortion = 0;               // the common range; with overlap
  double high_distortion = 0;
  // Without overlap (and both curves valid): rate(test) / rate(anchor) at the
  // two fronts' nearest ends (the test's end of least distortion against the
  // anchor's end of most, or the other way round), and the distortions there.
  double nearest_rate_ratio = 0;
  double nearest_test_distortion = 0, nearest_anchor_distortion = 0;
};

// The BD-rate of `test` against `anchor` (each any set of points; their
// fronts are taken). Cost: O(n log n) in the points of both.
BdRate bd_rate(const std::vector<RatePoint>& test, const std::vector<RatePoint>& anchor);

}  // namespace isowave::bench
