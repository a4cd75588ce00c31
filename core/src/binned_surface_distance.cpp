#include "isowave/core/binned_surface_distance.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "isowave/core/error.h"

namespace isowave {

namespace {

Vec3 closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double length_squared = squared_norm(ab);
  if (!(length_squared > 0)) return a;
  return a + std::clamp(dot(p - a, ab) / length_squared, 0.0, 1.0) * ab;
}

}  // namespace

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  // A triangle with (nearly) collinear or coincident corners is its edges:
  // the regions below divide by edge lengths and the area, which vanish.
  if (squared_norm(cross(ab, ac)) <= 1e-20 * squared_norm(ab) * squared_norm(ac)) {
    Vec3 best = closest_point_on_segment(p, a, b);
    for (const Vec3& q : {closest_point_on_segment(p, b, c), closest_point_on_segment(p, c, a)})
      if (squared_norm(p - q) < squared_norm(p - best)) best = q;
    return best;
  }
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denominator = va + vb + vc;
  return a + (vb / denominator) * ab + (vc / denominator) * ac;
}

BinnedSurfaceDistance::BinnedSurfaceDistance(const PolygonMesh& mesh) : positions_(mesh.positions) {
  const std::size_t n = positions_.size();
  const bool finite = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 1 << 14), true,
      [&](const tbb::blocked_range<std::size_t>& r, bool ok) {
        for (std::size_t v = r.begin(); v < r.end() && ok; ++v) ok = is_finite(positions_[v]);
        return ok;
      },
      [](bool a, bool b) { return a && b; });
  if (!finite) throw Error(ErrorKind::InvalidArgument, "distance to a mesh with a non-finite vertex position");
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < mesh.face_size(f); ++k) triangles_.insert(triangles_.end(), {face[0], face[k], face[k + 1]});
  }
  const std::size_t count = triangle_count();
  if (count == 0) throw Error(ErrorKind::InvalidArgument, "distance to a mesh without faces");

  // Bins of twice the mean edge: a query near the surface then scans its own
  // bin and a few neighbours, each with a handful of triangles.
  Vec3 low = positions_[triangles_[0]], high = low;
  double edge_sum = 0;
  for (std::size_t t = 0; t < count; ++t) {
    const Vec3 &a = positions_[triangles_[3 * t]], &b = positions_[triangles_[3 * t + 1]], &c = positions_[triangles_[3 * t + 2]];
    low = component_min(low, component_min(a, component_min(b, c)));
    high = component_max(high, component_max(a, component_max(b, c)));
    edge_sum += norm(b - a) + norm(c - b) + norm(a - c);
  }
  const Vec3 extent = high - low;
  const double largest = std::max({extent.x, extent.y, extent.z});
  bin_ = 2 * edge_sum / (3 * double(count));
  if (!(bin_ > 0)) bin_ = largest > 0 ? largest : 1.0;
  // At most 8 bins per triangle (and 2^21 along an axis): a few far-apart
  // small triangles would otherwise ask for a huge, empty grid.
  const double max_bins = std::max(4096.0, 8.0 * double(count));
  for (;;) {
    double bins = 1;
    for (int a = 0; a < 3; ++a) bins *= std::max(1.0, std::ceil(extent[a] / bin_));
    if (bins <= max_bins && largest / bin_ < double(1 << 21)) break;
    bin_ *= std::max(1.01, std::cbrt(bins / max_bins));
    bin_ = std::max(bin_, largest / double(1 << 20));
  }
  origin_ = low;
  std::size_t bin_count = 1;
  for (int a = 0; a < 3; ++a) {
    dims_[a] = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(extent[a] / bin_)));
    bin_count *= static_cast<std::size_t>(dims_[a]);
  }

  // Counting sort of the (bin, triangle) pairs by bin; triangles in a bin
  // stay in ascending order.
  const auto for_each_bin = [&](std::size_t t, const auto& body) {
    const Vec3 &a = positions_[triangles_[3 * t]], &b = positions_[triangles_[3 * t + 1]], &c = positions_[triangles_[3 * t + 2]];
    const Vec3 lo = component_min(a, component_min(b, c)), hi = component_max(a, component_max(b, c));
    const std::int64_t x0 = bin_along(0, lo.x), x1 = bin_along(0, hi.x), y0 = bin_along(1, lo.y),
                       y1 = bin_along(1, hi.y), z0 = bin_along(2, lo.z), z1 = bin_along(2, hi.z);
    for (std::int64_t z = z0; z <= z1; ++z)
      for (std::int64_t y = y0; y <= y1; ++y)
        for (std::int64_t x = x0; x <= x1; ++x) body(static_cast<std::size_t>(x + dims_[0] * (y + dims_[1] * z)));
  };
  first_.assign(bin_count + 1, 0);
  std::size_t pairs = 0;
  for (std::size_t t = 0; t < count; ++t)
    for_each_bin(t, [&](std::size_t bin) {
      ++first_[bin + 1];
      ++pairs;
    });
  if (pairs > std::numeric_limits<std::uint32_t>::max() || count > std::numeric_limits<std::uint32_t>::max())
    throw Error(ErrorKind::InvalidArgument, "distance to a mesh of too many triangles for 32-bit bin lists");
  for (std::size_t bin = 0; bin < bin_count; ++bin) first_[bin + 1] += first_[bin];
  listed_.resize(pairs);
  for (std::size_t t = 0; t < count; ++t)
    for_each_bin(t, [&](std::size_t bin) { listed_[first_[bin]++] = static_cast<std::uint32_t>(t); });
  for (std::size_t bin = bin_count; bin > 0; --bin) first_[bin] = first_[bin - 1];
  first_[0] = 0;
}

std::int64_t BinnedSurfaceDistance::bin_along(int axis, double coordinate) const {
  const double c = std::floor((coordinate - origin_[axis]) / bin_);
  if (!(c > 0)) return 0;
  return std::min<std::int64_t>(dims_[axis] - 1, static_cast<std::int64_t>(std::min(c, 1e15)));
}

double BinnedSurfaceDistance::squared_distance_to_triangle(const Vec3& p, std::uint32_t triangle, double best,
                                                           Vec3* closest) const {
  const std::uint32_t* t = triangles_.data() + 3 * std::size_t{triangle};
  const Vec3 &a = positions_[t[0]], &b = positions_[t[1]], &c = positions_[t[2]];
  // Most triangles of a bin are farther than the best so far: their bounding
  // box, no nearer than the triangle, rules them out more cheaply.
  const Vec3 gap = component_max(Vec3{}, component_max(component_min(a, component_min(b, c)) - p,
                                                       p - component_max(a, component_max(b, c))));
  if (squared_norm(gap) >= best) return best;
  const Vec3 q = closest_point_on_triangle(p, a, b, c);
  const double squared = squared_norm(p - q);
  if (!(squared < best)) return best;
  if (closest) *closest = q;
  return squared;
}

double BinnedSurfaceDistance::squared_distance(const Vec3& p, Vec3* closest) const {
  std::int64_t centre[3];
  for (int a = 0; a < 3; ++a) centre[a] = bin_along(a, p[a]);
  double best = std::numeric_limits<double>::infinity();
  // Distance from p to bin `bin`'s slab along `axis`.
  const auto gap = [&](int axis, std::int64_t bin) {
    const double lo = origin_[axis] + double(bin) * bin_;
    return std::max({0.0, lo - p[axis], p[axis] - lo - bin_});
  };
  const auto scan = [&](std::int64_t y, std::int64_t z, std::int64_t x0, std::int64_t x1) {
    const std::size_t row = static_cast<std::size_t>(dims_[0] * (y + dims_[1] * z));
    for (std::uint32_t i = first_[row + static_cast<std::size_t>(x0)], end = first_[row + static_cast<std::size_t>(x1) + 1];
         i < end; ++i)
      best = squared_distance_to_triangle(p, listed_[i], best, closest);
  };
  for (std::int64_t k = 0;; ++k) {
    // Ring k: the bins k steps from the centre's in at least one axis.
    for (std::int64_t z = std::max<std::int64_t>(0, centre[2] - k); z <= std::min(dims_[2] - 1, centre[2] + k); ++z) {
      const double gz = gap(2, z);
      if (gz * gz > best) continue;
      for (std::int64_t y = std::max<std::int64_t>(0, centre[1] - k); y <= std::min(dims_[1] - 1, centre[1] + k); ++y) {
        const double gy = gap(1, y), across = gy * gy + gz * gz;
        if (across > best) continue;
        const std::int64_t x0 = std::max<std::int64_t>(0, centre[0] - k), x1 = std::min(dims_[0] - 1, centre[0] + k);
        if (std::abs(z - centre[2]) == k || std::abs(y - centre[1]) == k) {
          // A whole row of the ring: only where it comes within `best`.
          std::int64_t from = x0, to = x1;
          if (best < std::numeric_limits<double>::infinity()) {
            const double half = std::sqrt(best - across);
            from = std::max(x0, bin_along(0, p.x - half));
            to = std::min(x1, bin_along(0, p.x + half));
          }
          if (from <= to) scan(y, z, from, to);
        } else {
          // The row's two ends.
          if (centre[0] - k >= 0) {
            const double gx = gap(0, centre[0] - k);
            if (gx * gx + across <= best) scan(y, z, centre[0] - k, centre[0] - k);
          }
          if (centre[0] + k < dims_[0]) {
            const double gx = gap(0, centre[0] + k);
            if (gx * gx + across <= best) scan(y, z, centre[0] + k, centre[0] + k);
          }
        }
      }
    }
    // A bin of a farther ring lies beyond the ring's faces on some axis.
    double bound = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (centre[a] + k + 1 < dims_[a]) bound = std::min(bound, origin_[a] + double(centre[a] + k + 1) * bin_ - p[a]);
      if (centre[a] - k - 1 >= 0) bound = std::min(bound, p[a] - (origin_[a] + double(centre[a] - k) * bin_));
    }
    if (bound == std::numeric_limits<double>::infinity()) return best;  // every bin scanned
    if (bound > 0 && bound * bound >= best) return best;
  }
}

double BinnedSurfaceDistance::distance(const Vec3& p) const {
  if (!is_finite(p)) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(squared_distance(p));
}

Vec3 BinnedSurfaceDistance::closest_point(const Vec3& p) const {
  assert(is_finite(p));
  Vec3 closest = p;
  squared_distance(p, &closest);
  return closest;
}

std::vector<double> BinnedSurfaceDistance::distances(const std::vector<Vec3>& points) const {
  std::vector<double> out(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) out[i] = distance(points[i]);
  });
  return out;
}

}  // namespace isowave
