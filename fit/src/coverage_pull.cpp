#include "coverage_pull.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/huge_page_vector.h"

namespace isowave {
namespace {

constexpr std::uint32_t kNone = WrapLevelMesh::kNone;
// Bins of 2 x 2 x 2 volume cells: a search to the default reach of 4 cells
// then scans at most 125 bins (against 729 of single cells, most of the time
// spent waiting for the bins' offsets).
constexpr int kBinCells = 2;

// Whether p lies within sqrt(squared) of a face around control point v or
// around one of its neighbours (polygons as fans). The neighbours' faces
// matter where faces are stretched: a point can lie next to a long face and
// still far from that face's corners.
bool near_faces(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, std::uint32_t v, const Vec3& p,
                double squared) {
  const auto near_fan = [&](std::uint32_t u) {
    for (std::uint32_t k = mesh.vertex_face_offsets[u]; k < mesh.vertex_face_offsets[u + 1]; ++k) {
      const std::uint32_t f = mesh.vertex_faces[k];
      const std::uint32_t* face = mesh.face_vertices.data() + mesh.face_offsets[f];
      const std::uint32_t size = mesh.face_offsets[f + 1] - mesh.face_offsets[f];
      // A neighbour's face around v was tested with v's own (on a regular
      // quad mesh 8 of the 20 faces visited).
      if (u != v && std::find(face, face + size, v) != face + size) continue;
      // Most faces are far: their bounding box, no nearer than the face,
      // rules them out with no closest-point computation.
      Vec3 low = positions[face[0]], high = low;
      for (std::uint32_t j = 1; j < size; ++j) {
        const Vec3& q = positions[face[j]];
        low = component_min(low, q);
        high = component_max(high, q);
      }
      const Vec3 gap = component_max(Vec3{}, component_max(low - p, p - high));
      if (squared_norm(gap) > squared) continue;
      for (std::uint32_t j = 1; j + 1 < size; ++j)
        if (squared_norm(p - closest_point_on_triangle(p, positions[face[0]], positions[face[j]], positions[face[j + 1]])) <=
            squared)
          return true;
    }
    return false;
  };
  if (near_fan(v)) return true;
  for (std::uint32_t k = mesh.neighbour_offsets[v]; k < mesh.neighbour_offsets[v + 1]; ++k)
    if (near_fan(mesh.neighbours[k])) return true;
  return false;
}

}  // namespace

CoveragePull::CoveragePull(const std::vector<Vec3>& samples, const Volume& grid, double covered)
    : samples_(samples),
      origin_(grid.origin),
      spacing_(kBinCells * grid.spacing),
      covered_squared_(covered * covered),
      min_spacing_(std::min({spacing_.x, spacing_.y, spacing_.z})),
      hint_(samples.size(), kNone) {
  assert(covered > 0 && min_spacing_ > 0);
  for (int a = 0; a < 3; ++a) {
    const std::int64_t grid_cells = std::max<std::int64_t>(1, static_cast<std::int64_t>(grid.dims[a]) - 1);
    bins_[a] = (grid_cells + kBinCells - 1) / kBinCells;
  }
}

std::int64_t CoveragePull::bin_along(int axis, double coordinate) const {
  const double c = std::floor((coordinate - origin_[axis]) / spacing_[axis]);
  return c >= 0 ? std::min<std::int64_t>(bins_[axis] - 1, static_cast<std::int64_t>(std::min(c, 1e15))) : 0;
}

std::size_t CoveragePull::bin_of(const Vec3& p, std::int64_t bin[3]) const {
  for (int a = 0; a < 3; ++a) bin[a] = bin_along(a, p[a]);
  return static_cast<std::size_t>(bin[0] + bins_[0] * (bin[1] + bins_[1] * bin[2]));
}

CoveragePullStatistics CoveragePull::apply(const WrapLevelMesh& mesh, std::vector<Vec3>& positions, double reach,
                                           std::vector<PulledPoint>* pulled) {
  assert(positions.size() >= mesh.vertex_count && reach * reach >= covered_squared_);
  sort_by_bin(positions, mesh.vertex_count);
  const std::vector<std::uint32_t> nearest = find_uncovered(mesh, positions, reach);
  return move_to_means(mesh, nearest, positions, pulled);
}

void CoveragePull::sort_by_bin(const std::vector<Vec3>& positions, std::size_t n) {
  // Counting sort of the control points by bin (serial, so the order in a
  // bin, and with it every tie, does not depend on the threads).
  const std::size_t bin_count = static_cast<std::size_t>(bins_[0] * bins_[1] * bins_[2]);
  // The buffers on huge pages faulted in on all threads: the scatter below
  // and the copy of the positions in bin order write and read them at random,
  // where a first touch on one thread and TLB misses would cost most of the
  // sort's time.
  reserve_on_huge_pages(vertex_bin_, n);
  reserve_on_huge_pages(order_, n);
  reserve_on_huge_pages(sorted_, n);
  vertex_bin_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    std::int64_t bin[3];
    for (std::size_t v = r.begin(); v < r.end(); ++v) vertex_bin_[v] = static_cast<std::uint32_t>(bin_of(positions[v], bin));
  });
  first_.assign(bin_count + 1, 0);
  for (std::size_t v = 0; v < n; ++v) ++first_[vertex_bin_[v] + 1];
  for (std::size_t c = 0; c < bin_count; ++c) first_[c + 1] += first_[c];
  order_.resize(n);
  for (std::size_t v = 0; v < n; ++v) order_[first_[vertex_bin_[v]]++] = static_cast<std::uint32_t>(v);
  // Their positions in that order, relative to the grid's origin in single
  // precision: the scans then read each bin's points from one place instead
  // of from n random ones.
  sorted_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      sorted_[i] = to_local(positions[order_[i]]);
    }
  });
  for (std::size_t c = bin_count; c > 0; --c) first_[c] = first_[c - 1];
  first_[0] = 0;
}

std::vector<std::uint32_t> CoveragePull::find_uncovered(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions,
                                                        double reach) {
  const std::size_t n = mesh.vertex_count;
  const double covered_distance = std::sqrt(covered_squared_);
  const std::int64_t max_ring = static_cast<std::int64_t>(std::ceil(reach / min_spacing_));
  std::vector<std::uint32_t> nearest(samples_.size(), kNone);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples_.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t s = r.begin(); s < r.end(); ++s) {
      const Vec3& p = samples_[s];
      // The control point that covered the sample, or was its nearest, on
      // the last call (a coarser level's vertex keeps its index on the finer
      // ones): tried first, it often settles the covered test at once and
      // otherwise bounds the search.
      const std::uint32_t hint = hint_[s] < n ? hint_[s] : kNone;
      const double hint_distance = hint != kNone ? squared_distance(to_local(positions[hint]), p - origin_) : 0.0;
      if (hint != kNone && hint_distance <= covered_squared_) continue;
      if (const std::uint32_t covering = covering_point(p, covered_distance); covering != kNone) {
        hint_[s] = covering;
        continue;
      }
      Candidate best{reach * reach, kNone};
      if (hint != kNone && hint_distance < best.squared_distance) best = {hint_distance, hint};
      const std::uint32_t best_vertex = nearest_point(p, max_ring, best);
      hint_[s] = best_vertex;
      if (best_vertex != kNone && !near_faces(mesh, positions, best_vertex, p, covered_squared_))
        nearest[s] = best_vertex;
    }
  });
  return nearest;
}

double CoveragePull::squared_distance(const FloatPoint& q, const Vec3& local) {
  const double dx = q.x - local.x, dy = q.y - local.y, dz = q.z - local.z;
  return dx * dx + dy * dy + dz * dz;
}

std::pair<std::uint32_t, std::uint32_t> CoveragePull::row(std::int64_t y, std::int64_t z, std::int64_t x0,
                                                          std::int64_t x1) const {
  const std::size_t start = static_cast<std::size_t>(bins_[0] * (y + bins_[1] * z));
  return {first_[start + static_cast<std::size_t>(x0)], first_[start + static_cast<std::size_t>(x1) + 1]};
}

std::uint32_t CoveragePull::covering_point(const Vec3& p, double covered_distance) const {
  // The bins of one row (fixed y and z) are consecutive in bin order, so the
  // control points of any run of bins along x are one contiguous range of
  // sorted_: the scans go row by row, with no per-bin work. Here the (at
  // most 2 x 2) rows of bins that the ball around p overlaps.
  const Vec3 local = p - origin_;
  std::int64_t low[3], high[3];
  bin_of(p - Vec3{covered_distance, covered_distance, covered_distance}, low);
  bin_of(p + Vec3{covered_distance, covered_distance, covered_distance}, high);
  for (std::int64_t z = low[2]; z <= high[2]; ++z)
    for (std::int64_t y = low[1]; y <= high[1]; ++y) {
      const auto [begin, end] = row(y, z, low[0], high[0]);
      for (std::uint32_t i = begin; i < end; ++i)
        if (squared_distance(sorted_[i], local) <= covered_squared_) return order_[i];
    }
  return kNone;
}

std::uint32_t CoveragePull::nearest_point(const Vec3& p, std::int64_t max_ring, Candidate start) const {
  // Ties to the lower index, so the result does not depend on the scan's
  // order. Rows ring by ring around p's (ring k: rows k bins away in y or z),
  // each scanned only where it overlaps the ball of the best distance so far.
  const Vec3 local = p - origin_;
  double best = start.squared_distance;
  std::uint32_t best_vertex = start.vertex;
  std::int64_t centre[3];
  bin_of(p, centre);
  const auto gap = [&](int axis, std::int64_t bin) {
    const double lo = origin_[axis] + double(bin) * spacing_[axis];
    return std::max({0.0, lo - p[axis], p[axis] - lo - spacing_[axis]});
  };
  const auto scan_row = [&](std::int64_t y, std::int64_t z) {
    if (y < 0 || y >= bins_[1]) return;
    const double gy = gap(1, y), gz = gap(2, z), across = gy * gy + gz * gz;
    if (across > best) return;
    const double half = std::sqrt(best - across);
    const auto [begin, end] = row(y, z, bin_along(0, p.x - half), bin_along(0, p.x + half));
    for (std::uint32_t i = begin; i < end; ++i) {
      const double d = squared_distance(sorted_[i], local);
      if (d < best || (d == best && best_vertex != kNone && order_[i] < best_vertex)) best = d, best_vertex = order_[i];
    }
  };
  for (std::int64_t k = 0; k <= max_ring; ++k) {
    for (std::int64_t z = std::max<std::int64_t>(0, centre[2] - k); z <= std::min(bins_[2] - 1, centre[2] + k); ++z) {
      if (std::abs(z - centre[2]) == k) {
        for (std::int64_t y = centre[1] - k; y <= centre[1] + k; ++y) scan_row(y, z);
      } else {
        scan_row(centre[1] - k, z);
        scan_row(centre[1] + k, z);
      }
    }
    // A control point in a farther ring lies at least k bins away.
    const double bound = double(k) * std::min(spacing_.y, spacing_.z);
    if (best < bound * bound) break;
  }
  return best_vertex;
}

CoveragePullStatistics CoveragePull::move_to_means(const WrapLevelMesh& mesh, const std::vector<std::uint32_t>& nearest,
                                                   std::vector<Vec3>& positions, std::vector<PulledPoint>* pulled) const {
  // Each picked control point moves to the mean of its samples.
  CoveragePullStatistics stats;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> picks;
  for (std::size_t s = 0; s < samples_.size(); ++s)
    if (nearest[s] != kNone) picks.emplace_back(nearest[s], static_cast<std::uint32_t>(s));
  stats.uncovered_samples = picks.size();
  tbb::parallel_sort(picks.begin(), picks.end());
  if (pulled) pulled->clear();
  for (std::size_t i = 0; i < picks.size();) {
    const std::uint32_t v = picks[i].first;
    Vec3 sum;
    std::size_t j = i;
    for (; j < picks.size() && picks[j].first == v; ++j) sum += samples_[picks[j].second];
    if (mesh.role[v] != WrapRole::Fixed) {
      if (pulled) pulled->push_back({v, positions[v]});
      Vec3 mean = (1.0 / double(j - i)) * sum;
      // A point held on a box face moves within it (its boundary curve
      // stretches toward what it left out there).
      if (const int face = mesh.box_face[v]; face >= 0) mean[face >> 1] = positions[v][face >> 1];
      positions[v] = mean;
      ++stats.pulled_vertices;
    }
    i = j;
  }
  return stats;
}

}  // namespace isowave
