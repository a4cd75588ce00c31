#include "isowave/core/point_set_distance.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"

namespace isowave {

namespace {

// Bins of a sweep's grid at most (16 MB of offsets): a larger grid gets larger bins.
constexpr double kMaxBins = double(1 << 22);
// Each sweep's radius is this many times the last one's.
constexpr double kRadiusGrowth = 4;

// A squared distance as ordered bits (non-negative doubles order as their bit patterns).
std::uint64_t bits_of(double value) {
  std::uint64_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}
double value_of(std::uint64_t bits) {
  double value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

struct Box {
  Vec3 low, high;
};

// Some points binned in a uniform grid (counting sort, one offset per bin).
class PointGrid {
 public:
  PointGrid(const std::vector<Vec3>& points, std::vector<std::uint32_t> which, double bin) : listed_(std::move(which)) {
    Box box{points[listed_[0]], points[listed_[0]]};
    for (const std::uint32_t i : listed_) {
      box.low = component_min(box.low, points[i]);
      box.high = component_max(box.high, points[i]);
    }
    origin_ = box.low;
    const Vec3 extent = box.high - box.low;
    bin_ = bin;
    for (;;) {
      double bins = 1;
      for (int a = 0; a < 3; ++a) bins *= std::floor(extent[a] / bin_) + 1;
      if (bins <= kMaxBins) break;
      bin_ *= std::max(1.01, std::cbrt(bins / kMaxBins));
    }
    std::size_t count = 1;
    for (int a = 0; a < 3; ++a) {
      dims_[a] = static_cast<std::int64_t>(std::floor(extent[a] / bin_)) + 1;
      count *= static_cast<std::size_t>(dims_[a]);
    }
    first_.assign(count + 1, 0);
    std::vector<std::uint32_t> bin_of(listed_.size());
    for (std::size_t k = 0; k < listed_.size(); ++k) {
      const Vec3& p = points[listed_[k]];
      bin_of[k] = static_cast<std::uint32_t>(along(0, p.x) + dims_[0] * (along(1, p.y) + dims_[1] * along(2, p.z)));
      ++first_[bin_of[k] + 1];
    }
    for (std::size_t b = 0; b < count; ++b) first_[b + 1] += first_[b];
    std::vector<std::uint32_t> sorted(listed_.size());
    std::vector<std::uint32_t> next(first_.begin(), first_.end() - 1);
    for (std::size_t k = 0; k < listed_.size(); ++k) sorted[next[bin_of[k]]++] = listed_[k];
    listed_ = std::move(sorted);
  }

  // Calls visit(point index) for every point in a bin the box overlaps.
  template <class Visit>
  void for_each_near(const Box& box, const Visit& visit) const {
    std::int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const double l = std::floor((box.low[a] - origin_[a]) / bin_), h = std::floor((box.high[a] - origin_[a]) / bin_);
      if (h < 0 || l >= double(dims_[a])) return;
      lo[a] = l < 0 ? 0 : static_cast<std::int64_t>(l);
      hi[a] = std::min<std::int64_t>(dims_[a] - 1, static_cast<std::int64_t>(h));
    }
    for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
        const std::size_t row = static_cast<std::size_t>(dims_[0] * (y + dims_[1] * z));
        for (std::uint32_t k = first_[row + static_cast<std::size_t>(lo[0])],
                           end = first_[row + static_cast<std::size_t>(hi[0]) + 1];
             k < end; ++k)
          visit(listed_[k]);
      }
  }

 private:
  std::int64_t along(int axis, double coordinate) const {
    return std::min<std::int64_t>(dims_[axis] - 1, static_cast<std::int64_t>((coordinate - origin_[axis]) / bin_));
  }

  Vec3 origin_;
  double bin_ = 1;
  std::int64_t dims_[3] = {1, 1, 1};
  std::vector<std::uint32_t> first_;   // per bin, then the end
  std::vector<std::uint32_t> listed_;  // point indices, bin by bin
};

// The mesh's bounding box; Error(InvalidArgument) for a non-finite position or no face.
Box checked_bounds(const PolygonMesh& mesh) {
  if (mesh.face_count() == 0 || mesh.positions.empty())
    throw Error(ErrorKind::InvalidArgument, "distance to a mesh without faces");
  const Vec3 infinite{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                      std::numeric_limits<double>::infinity()};
  const Box empty{infinite, -1.0 * infinite};
  const Box box = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.positions.size(), 1 << 14), empty,
      [&](const tbb::blocked_range<std::size_t>& r, Box b) {
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
          const Vec3& p = mesh.positions[v];
          if (!is_finite(p)) throw Error(ErrorKind::InvalidArgument, "distance to a mesh with a non-finite vertex position");
          b.low = component_min(b.low, p);
          b.high = component_max(b.high, p);
        }
        return b;
      },
      [](const Box& a, const Box& b) { return Box{component_min(a.low, b.low), component_max(a.high, b.high)}; });
  return box;
}

// Faces per block: consecutive faces lie near each other in the meshes
// measured (the fine level of a hierarchy, extracted meshes), so a block's
// bounding box is small, and a sweep gathers the points near it once for
// all its faces. Any face order gives the same distances, only slower.
constexpr std::size_t kBlockFaces = 16;

// The bounding box of every block of faces, in parallel.
std::vector<Box> block_boxes(const PolygonMesh& mesh) {
  const std::size_t faces = mesh.face_count(), blocks = (faces + kBlockFaces - 1) / kBlockFaces;
  std::vector<Box> boxes(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t k) {
    Box box{mesh.positions[mesh.face_begin(k * kBlockFaces)[0]], mesh.positions[mesh.face_begin(k * kBlockFaces)[0]]};
    for (std::size_t f = k * kBlockFaces; f < std::min(faces, (k + 1) * kBlockFaces); ++f)
      for (const std::uint32_t* v = mesh.face_begin(f); v != mesh.face_begin(f) + mesh.face_size(f); ++v) {
        box.low = component_min(box.low, mesh.positions[*v]);
        box.high = component_max(box.high, mesh.positions[*v]);
      }
    boxes[k] = box;
  });
  return boxes;
}

double squared_gap(const Box& box, const Vec3& p) {
  return squared_norm(component_max(Vec3{}, component_max(box.low - p, p - box.high)));
}

// One sweep: every fan triangle lowers the best squared distance of the
// grid's points within `radius` of its block's bounding box.
void sweep(const PolygonMesh& mesh, const std::vector<Box>& blocks, const std::vector<Vec3>& points,
           const PointGrid& grid, double radius, std::atomic<std::uint64_t>* best) {
  const Vec3 reach{radius, radius, radius};
  const double reach_squared = radius * radius;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 4), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::uint32_t> near;
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      near.clear();
      grid.for_each_near(Box{blocks[k].low - reach, blocks[k].high + reach}, [&](std::uint32_t i) {
        if (squared_gap(blocks[k], points[i]) <= reach_squared) near.push_back(i);
      });
      if (near.empty()) continue;
      for (std::size_t f = k * kBlockFaces; f < std::min(mesh.face_count(), (k + 1) * kBlockFaces); ++f) {
        const std::uint32_t* face = mesh.face_begin(f);
        const Vec3& a = mesh.positions[face[0]];
        for (std::uint32_t j = 1; j + 1 < mesh.face_size(f); ++j) {
          const Vec3 &b = mesh.positions[face[j]], &c = mesh.positions[face[j + 1]];
          const Box box{component_min(a, component_min(b, c)), component_max(a, component_max(b, c))};
          for (const std::uint32_t i : near) {
            const Vec3& p = points[i];
            std::uint64_t current = best[i].load(std::memory_order_relaxed);
            // The bounding box is no nearer than the triangle: a cheap
            // rejection of triangles beyond the best so far or the radius
            // (a point with none within the radius goes to the next sweep).
            const double gap = squared_gap(box, p);
            if (!(gap < value_of(current)) || gap > reach_squared) continue;
            const std::uint64_t found = bits_of(squared_norm(p - closest_point_on_triangle(p, a, b, c)));
            while (found < current && !best[i].compare_exchange_weak(current, found, std::memory_order_relaxed)) {
            }
          }
        }
      }
    }
  });
}

}  // namespace

PointSetDistance::PointSetDistance(std::vector<Vec3> points, double radius) : points_(std::move(points)), radius_(radius) {
  if (points_.empty() || points_.size() > std::numeric_limits<std::uint32_t>::max())
    throw Error(ErrorKind::InvalidArgument, "point set distance: between 1 and 2^32 - 1 points are needed");
  if (!(radius_ > 0) || !std::isfinite(radius_))
    throw Error(ErrorKind::InvalidArgument, "point set distance: the search radius must be positive and finite");
  for (const Vec3& p : points_)
    if (!is_finite(p)) throw Error(ErrorKind::InvalidArgument, "point set distance: a point is not finite");
}

std::vector<double> PointSetDistance::distances(const PolygonMesh& mesh) const {
  Box box = checked_bounds(mesh);
  for (const Vec3& p : points_) box = Box{component_min(box.low, p), component_max(box.high, p)};
  // A sweep of this radius reaches every triangle from every point.
  const double diameter = std::max(norm(box.high - box.low), 1e-300);
  const std::size_t n = points_.size();
  const std::unique_ptr<std::atomic<std::uint64_t>[]> best(new std::atomic<std::uint64_t>[n]);
  for (std::size_t i = 0; i < n; ++i) best[i].store(bits_of(std::numeric_limits<double>::infinity()));
  std::vector<std::uint32_t> left(n);
  for (std::size_t i = 0; i < n; ++i) left[i] = static_cast<std::uint32_t>(i);
  const std::vector<Box> blocks = block_boxes(mesh);
  for (double radius = radius_; !left.empty(); radius *= kRadiusGrowth) {
    radius = std::min(radius, diameter);
    sweep(mesh, blocks, points_, PointGrid(points_, left, radius), radius, best.get());
    if (radius == diameter) break;
    // Exact where a triangle lies within the radius; the others go on.
    const std::uint64_t reached = bits_of(radius * radius);
    left.erase(std::remove_if(left.begin(), left.end(), [&](std::uint32_t i) { return best[i].load() <= reached; }),
               left.end());
  }
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = std::sqrt(value_of(best[i].load()));
  return out;
}

}  // namespace isowave
