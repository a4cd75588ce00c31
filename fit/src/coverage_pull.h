#pragma once
// The coverage pull of the shrink-wrap (not in the paper; see
// ShrinkWrapOptions::surface). The attraction moves each control point to
// the surface along its own normal, so it never goes where no control point
// points: bumps, filaments and sheets a few cells across that the base mesh
// cut off stay left out. The pull goes the other way, from the surface: every
// extracted vertex farther than `covered` from the mesh (nearest control
// point, then the faces around it and its neighbours) picks its nearest
// control point within `reach`, and each picked point moves to the mean of
// the vertices that picked it; the attraction that follows (on the finest
// level, the correction) puts it on the isosurface.
//
// Control points are binned by 2 x 2 x 2 volume cells (a counting sort,
// arrays reused for every level), so a covered extracted vertex costs a scan
// of the at most 8 bins its `covered` ball overlaps; only uncovered ones
// search farther, ring by ring of rows of bins. A row's bins are consecutive
// in bin order, so each row is one contiguous run of points, clipped to the
// ball of the best distance so far. Each extracted vertex remembers the
// control point that covered it or was its nearest, which on the next
// (finer) level keeps its index: tried first, it settles most covered tests
// at once and bounds the search of the others. Neither changes which point
// is picked (nearest within reach, ties to the lower index).
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/wrap_level_mesh.h"

namespace isowave {

struct CoveragePullStatistics {
  std::size_t uncovered_samples = 0;  // extracted vertices farther than `covered` from the mesh
  std::size_t pulled_vertices = 0;    // control points moved
};

// A control point the pull moved, and where it was before.
struct PulledPoint {
  std::uint32_t vertex;
  Vec3 from;
};

class CoveragePull {
 public:
  // samples: the extracted isosurface's vertices (kept by reference);
  // covered in world units, > 0.
  CoveragePull(const std::vector<Vec3>& samples, const Volume& grid, double covered);

  // One pull of the control points of `mesh` that are not fixed (those held
  // on a box face keep their coordinate across it, so that boundary curves
  // there stretch along the face) toward the uncovered samples within
  // `reach` (world units, >= covered), in place (measured first, moved
  // after); with `pulled`, the moved points are listed there, ascending.
  // Deterministic for any thread count;
  // O(samples * rows scanned + vertices) time, the rows scanned for an
  // uncovered sample growing with the square of reach and the points with
  // the cube of its distance to the nearest; 20 bytes of memory per control
  // point, 8 per sample and 4 per bin.
  CoveragePullStatistics apply(const WrapLevelMesh& mesh, std::vector<Vec3>& positions, double reach,
                               std::vector<PulledPoint>* pulled = nullptr);

 private:
  // The bin holding p (clamped into the grid), its coordinates into `bin`.
  std::size_t bin_of(const Vec3& p, std::int64_t bin[3]) const;
  // The bin coordinate along one axis (clamped into the grid).
  std::int64_t bin_along(int axis, double coordinate) const;

  struct FloatPoint {
    float x, y, z;
  };
  // A control point (kNone for none) and its squared distance to a sample.
  struct Candidate {
    double squared_distance;
    std::uint32_t vertex;
  };
  // The steps of apply: the counting sort of the first n control points by
  // bin into first_, order_ and sorted_; per sample, the control point it
  // picks (kNone where covered or with none within reach), updating hint_;
  // each picked point moved to the mean of its samples.
  void sort_by_bin(const std::vector<Vec3>& positions, std::size_t n);
  std::vector<std::uint32_t> find_uncovered(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, double reach);
  CoveragePullStatistics move_to_means(const WrapLevelMesh& mesh, const std::vector<std::uint32_t>& nearest,
                                       std::vector<Vec3>& positions, std::vector<PulledPoint>* pulled) const;
  // A control point within sqrt(covered_squared_) of p (= covered_distance),
  // or kNone; the first in bin order.
  std::uint32_t covering_point(const Vec3& p, double covered_distance) const;
  // The control point nearest to p within start's distance (ties to the
  // lower index), else start.vertex; searches at most max_ring rings of rows
  // of bins around p's.
  std::uint32_t nearest_point(const Vec3& p, std::int64_t max_ring, Candidate start) const;
  // The control points of bins x0 .. x1 of row (y, z): order_[first .. second).
  std::pair<std::uint32_t, std::uint32_t> row(std::int64_t y, std::int64_t z, std::int64_t x0, std::int64_t x1) const;
  // |q - local|^2, q converted to double.
  static double squared_distance(const FloatPoint& q, const Vec3& local);

  const std::vector<Vec3>& samples_;
  Vec3 origin_, spacing_;
  std::int64_t bins_[3];
  double covered_squared_, min_spacing_;
  // Control points by bin (2 x 2 x 2 volume cells): those
  // of bin c are order_[first_[c] .. first_[c + 1]).
  std::vector<std::uint32_t> first_, order_, vertex_bin_;
  std::vector<FloatPoint> sorted_;  // to_local(positions[order_[i]])
  // Per sample, the control point that covered it or was its nearest on
  // the last call (kNone before the first).
  std::vector<std::uint32_t> hint_;

  FloatPoint to_local(const Vec3& p) const {
    return {float(p.x - origin_.x), float(p.y - origin_.y), float(p.z - origin_.z)};
  }
};

}  // namespace isowave
