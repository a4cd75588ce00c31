#include "bd_rate.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace isowave::bench {

namespace {

// A curve in (x, y) = (log distortion, log rate).
using LogPoint = std::pair<double, double>;

// y on the front at x, linear between its points; precondition: x within its range.
double log_rate_at(const std::vector<LogPoint>& front, double x) {
  const auto above = std::lower_bound(front.begin(), front.end(), LogPoint{x, -HUGE_VAL});
  if (above == front.begin()) return above->second;
  if (above == front.end()) return front.back().second;
  const auto below = above - 1;
  const double t = (x - below->first) / (above->first - below->first);
  return below->second + t * (above->second - below->second);
}

std::vector<LogPoint> log_front(const std::vector<RatePoint>& points) {
  std::vector<LogPoint> front;
  for (const RatePoint& p : rate_distortion_front(points)) front.emplace_back(std::log(p.distortion), std::log(p.rate));
  return front;
}

}  // namespace

std::vector<RatePoint> rate_distortion_front(std::vector<RatePoint> points) {
  std::vector<RatePoint> valid;
  for (const RatePoint& p : points)
    if (p.rate > 0 && p.distortion > 0 && std::isfinite(p.rate) && std::isfinite(p.distortion)) valid.push_back(p);
  std::sort(valid.begin(), valid.end(), [](const RatePoint& a, const RatePoint& b) {
    return a.distortion < b.distortion || (a.distortion == b.distortion && a.rate < b.rate);
  });
  std::vector<RatePoint> front;
  for (const RatePoint& p : valid)
    if (front.empty() || p.rate < front.back().rate) front.push_back(p);
  return front;
}

BdRate bd_rate(const std::vector<RatePoint>& test, const std::vector<RatePoint>& anchor) {
  BdRate result;
  const std::vector<LogPoint> a = log_front(test), b = log_front(anchor);
  if (a.empty() || b.empty()) return result;
  const double low = std::max(a.front().first, b.front().first), high = std::min(a.back().first, b.back().first);
  if (!(low < high)) {
    // The test lies wholly at lower distortion than the anchor, or wholly higher.
    const bool test_lower = a.back().first <= b.front().first;
    const LogPoint& at_test = test_lower ? a.back() : a.front();
    const LogPoint& at_anchor = test_lower ? b.front() : b.back();
    result.nearest_rate_ratio = std::exp(at_test.second - at_anchor.second);
    result.nearest_test_distortion = std::exp(at_test.first);
    result.nearest_anchor_distortion = std::exp(at_anchor.first);
    return result;
  }
  // Both fronts are linear between their points: the trapezoid rule over the
  // union of their breakpoints inside the range integrates the difference exactly.
  std::vector<double> xs{low, high};
  for (const auto* front : {&a, &b})
    for (const LogPoint& p : *front)
      if (p.first > low && p.first < high) xs.push_back(p.first);
  std::sort(xs.begin(), xs.end());
  double integral = 0;
  for (std::size_t i = 1; i < xs.size(); ++i) {
    const double d0 = log_rate_at(a, xs[i - 1]) - log_rate_at(b, xs[i - 1]);
    const double d1 = log_rate_at(a, xs[i]) - log_rate_at(b, xs[i]);
    integral += 0.5 * (d0 + d1) * (xs[i] - xs[i - 1]);
  }
  result.overlap = true;
  result.percent = 100 * (std::exp(integral / (high - low)) - 1);
  result.low_distortion = std::exp(low);
  result.high_distortion = std::exp(high);
  return result;
}

}  // namespace isowave::bench
