#include "history_inverse.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <string>

#include "isowave/core/error.h"

namespace isowave {

namespace {

// Rounding tolerance on a barycentric weight before a point counts as a fallback.
constexpr double kOutside = -1e-6;

[[noreturn]] void invalid(const std::string& what) {
  throw Error(ErrorKind::InvalidArgument, "surface map history: " + what);
}

// Whether chart triangle `corners` of an operation's chart has positive area.
bool has_area(const std::array<double, 2>* chart, const std::array<std::uint8_t, 3>& corners) {
  Corners tri;
  for (int k = 0; k < 3; ++k) tri[k] = {chart[corners[k]][0], chart[corners[k]][1]};
  return cross(tri[1] - tri[0], tri[2] - tri[0]) > 0;
}

bool offsets_valid(const std::vector<std::uint32_t>& begin, std::size_t operations, std::size_t size) {
  if (begin.size() != operations + 1 || begin.back() != size) return false;
  return std::is_sorted(begin.begin(), begin.end());
}

// Carries one point from its base triangle back to the input; returns the
// surface point and whether rounding put it outside at some step.
Vec3 walk(const simplify::SurfaceMapHistory& h, const std::vector<Vec3>& positions, const MapPoint& q,
          bool& outside) {
  const std::uint32_t inputs = static_cast<std::uint32_t>(h.input_corners.size());
  std::uint32_t version = h.base_version[q.triangle];
  std::array<double, 3> w = {1.0 - q.u - q.v, q.u, q.v};
  outside = false;
  while (version >= inputs) {
    // Step 1: the operation that made the triangle, and the point in its chart.
    const std::size_t r =
        static_cast<std::size_t>(std::upper_bound(h.made_begin.begin(), h.made_begin.end(), version) -
                                 h.made_begin.begin()) - 1;
    const std::array<double, 2>* chart = h.chart.data() + h.chart_begin[r];
    const auto& made = h.made_corners[version - inputs];
    Vec2 p;
    for (int k = 0; k < 3; ++k) p = p + w[k] * Vec2{chart[made[k]][0], chart[made[k]][1]};
    // Step 2: the consumed triangle that holds it (the largest smallest weight).
    double best_min = -1e300;
    std::uint32_t best = version;
    std::array<double, 3> best_w{};
    for (std::uint32_t c = h.consumed_begin[r]; c < h.consumed_begin[r + 1]; ++c) {
      const auto& corners = h.consumed_corners[c];
      if (!has_area(chart, corners)) continue;  // flattened onto a chord
      Corners tri;
      for (int k = 0; k < 3; ++k) tri[k] = {chart[corners[k]][0], chart[corners[k]][1]};
      std::array<double, 3> b{};
      barycentric(tri, p, b);
      const double smallest = std::min({b[0], b[1], b[2]});
      if (smallest > best_min) {
        best_min = smallest;
        best = h.consumed[c];
        best_w = b;
      }
      if (smallest >= 0) break;
    }
    assert(best != version && "check_history: every operation consumed a triangle with area");
    // Step 3: clamp what rounding put outside, and go on from there.
    outside = outside || best_min < kOutside;
    double sum = 0;
    for (double& b : best_w) sum += b = std::max(0.0, b);
    for (double& b : best_w) b /= sum;
    w = best_w;
    version = best;
  }
  const auto& corners = h.input_corners[version];
  return w[0] * positions[corners[0]] + w[1] * positions[corners[1]] + w[2] * positions[corners[2]];
}

}  // namespace

void check_history(const simplify::SurfaceMapHistory& h, std::size_t map_triangles, std::size_t surface_vertices) {
  const std::size_t operations = h.operation_count();
  const std::size_t inputs = h.input_corners.size();
  if (h.base_version.size() != map_triangles) invalid("one base version per map triangle expected");
  if (h.made_begin.empty() || h.made_begin.front() != inputs ||
      !offsets_valid(h.made_begin, operations, inputs + h.made_corners.size()))
    invalid("made triangles' offsets");
  if (!offsets_valid(h.chart_begin, operations, h.chart.size()) ||
      !offsets_valid(h.consumed_begin, operations, h.consumed.size()) ||
      h.consumed_corners.size() != h.consumed.size())
    invalid("chart or consumed triangles' offsets");
  for (const auto& corners : h.input_corners)
    for (const std::uint32_t v : corners)
      if (v >= surface_vertices) invalid("input corner out of range");
  for (const auto& xy : h.chart)
    if (!std::isfinite(xy[0]) || !std::isfinite(xy[1])) invalid("non-finite chart position");
  for (const std::uint32_t v : h.base_version)
    if (v >= h.made_begin.back()) invalid("base version out of range");
  for (std::size_t r = 0; r < operations; ++r) {
    const std::uint32_t chart_size = h.chart_begin[r + 1] - h.chart_begin[r];
    const auto within = [&](const std::array<std::uint8_t, 3>& corners) {
      return corners[0] < chart_size && corners[1] < chart_size && corners[2] < chart_size;
    };
    bool any_area = false;
    for (std::uint32_t c = h.consumed_begin[r]; c < h.consumed_begin[r + 1]; ++c) {
      if (h.consumed[c] >= h.made_begin[r] || !within(h.consumed_corners[c]))
        invalid("a consumed triangle is not older than its operation or not in its chart");
      any_area = any_area || has_area(h.chart.data() + h.chart_begin[r], h.consumed_corners[c]);
    }
    if (!any_area) invalid("an operation consumed no triangle with area");
    for (std::uint32_t v = h.made_begin[r]; v < h.made_begin[r + 1]; ++v)
      if (!within(h.made_corners[v - inputs])) invalid("a made triangle is not in its chart");
  }
}

InverseMapResult inverse_map_by_history(const simplify::SurfaceMapHistory& history,
                                        const std::vector<Vec3>& surface_positions,
                                        const std::vector<MapPoint>& queries) {
  InverseMapResult result;
  result.points.resize(queries.size());
  std::atomic<std::size_t> outside{0};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 2048), [&](const auto& range) {
    std::size_t local = 0;
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      bool out = false;
      result.points[i] = walk(history, surface_positions, queries[i], out);
      local += out ? 1 : 0;
    }
    outside += local;
  });
  result.fallback_points = outside;
  return result;
}

}  // namespace isowave
