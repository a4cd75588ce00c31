#include "normal_targets.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "root_search.h"

namespace isowave::detail {
namespace {

constexpr std::size_t kGrain = 4096;

// d with its component along `axis` removed, normalized (zero if nothing is left).
Vec3 in_plane(Vec3 d, int axis) {
  d[axis] = 0;
  const double length = std::sqrt(squared_norm(d));
  return length > 0 ? d * (1.0 / length) : Vec3{};
}

// The box face p lies farthest beyond (axis * 2 + 0 low / 1 high), or -1 inside.
int outside_face(const Vec3& p, const Vec3& low, const Vec3& high) {
  int face = -1;
  double worst = 0;
  for (int axis = 0; axis < 3; ++axis) {
    if (low[axis] - p[axis] > worst) worst = low[axis] - p[axis], face = 2 * axis;
    if (p[axis] - high[axis] > worst) worst = p[axis] - high[axis], face = 2 * axis + 1;
  }
  return face;
}

Vec3 unit_or_zero(const Vec3& v) {
  const double length = std::sqrt(squared_norm(v));
  return length > 0 && std::isfinite(length) ? v * (1.0 / length) : Vec3{};
}

}  // namespace

bool pierce(const TrilinearGrid& grid, double iso, const Vec3& p, const Vec3& d, double facing, double reach,
            double step, double tolerance, double& t) {
  const Vec3 g0 = grid.grid_point(p), gd = grid.grid_direction(d);
  const auto h = [&](double s) { return grid.value_at(g0 + gd * s) - iso; };
  // A crossing inside the box (the field is clamped beyond it, so its
  // isosurface would go on outside) on the side the surface allows: the
  // field's slope along d has the sign `facing`.
  const auto admissible = [&](double root) {
    return grid.inside(g0 + gd * root) &&
           (facing == 0 || dot(grid.sample_at(g0 + gd * root).gradient, d) * facing >= 0);
  };
  const double h0 = h(0);
  if (h0 == 0 && admissible(0)) {
    t = 0;
    return true;
  }
  double forward = 0, h_forward = h0, backward = 0, h_backward = h0;
  bool forward_open = true, backward_open = true;
  const int steps = static_cast<int>(std::ceil(reach / step));
  for (int k = 1; k <= steps && (forward_open || backward_open); ++k) {
    const double at = std::min(k * step, reach);
    if (forward_open) {
      const double ha = h(at);
      if (root_side(ha) != root_side(h_forward)) {
        const double root = refine_bracket(h, forward, h_forward, at, ha, tolerance);
        if (admissible(root)) {
          t = root;
          return true;
        }
      }
      forward = at, h_forward = ha;
    }
    if (backward_open) {
      const double hb = h(-at);
      if (root_side(hb) != root_side(h_backward)) {
        const double root = refine_bracket(h, backward, h_backward, -at, hb, tolerance);
        if (admissible(root)) {
          t = root;
          return true;
        }
      }
      backward = -at, h_backward = hb;
    }
    if (at >= reach) forward_open = backward_open = false;
  }
  return false;
}

LevelTargets level_targets(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions,
                           const std::vector<Vec3>& directions, const TrilinearGrid& grid, const Volume& box,
                           double iso, double facing, double reach, const BinnedSurfaceDistance* surface) {
  const std::size_t n = mesh.vertex_count;
  const double cell = box.cell_size(), step = 0.25 * cell, tolerance = 1e-4 * cell;
  const Vec3 low = volume_box_min(box), high = volume_box_max(box);
  LevelTargets targets;
  targets.plane_normal.assign(n, Vec3{});
  targets.plane_offset.assign(n, 0.0);
  targets.box_axis.assign(n, -1);
  targets.box_offset.assign(n, 0.0);
  targets.off_line.assign(n, 0);
  targets.pull_offset.assign(n, Vec3{});
  targets.pulled.assign(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v) {
      if (mesh.role[v] == WrapRole::Fixed) continue;
      const Vec3& p = positions[v];
      const int face = mesh.box_face[v] >= 0 ? mesh.box_face[v] : outside_face(p, low, high);
      const int axis = face >= 0 ? face / 2 : -1;
      if (axis >= 0) {
        targets.box_axis[v] = static_cast<std::int8_t>(axis);
        targets.box_offset[v] = (face % 2 ? high[axis] : low[axis]) - p[axis];
      }
      const auto held = [&](const Vec3& d) { return axis >= 0 ? in_plane(d, axis) : unit_or_zero(d); };
      // A point held on a face searches within the face's plane, from its
      // foot there (a point outside the box would find nothing inside it).
      Vec3 origin = p;
      if (axis >= 0) origin[axis] += targets.box_offset[v];
      const Vec3 gradient = grid.sample(origin).gradient;
      const bool along_normal = squared_norm(directions[v]) > 0;
      Vec3 d = held(along_normal ? directions[v] : gradient);
      double t = 0;
      bool found = squared_norm(d) > 0 &&
                   pierce(grid, iso, origin, d, along_normal ? facing : 0.0, reach, step, tolerance, t);
      if (!found && along_normal) {
        d = held(gradient);
        found = squared_norm(d) > 0 && pierce(grid, iso, origin, d, 0.0, reach, step, tolerance, t);
        targets.off_line[v] = 1;
      }
      Vec3 target = origin + d * t;
      if (!found && surface) {
        target = surface->closest_point(origin);
        if (axis >= 0) target[axis] = origin[axis];
        d = unit_or_zero(target - origin);
        found = true;
        targets.off_line[v] = 1;
      }
      if (!found) continue;
      Vec3 m = grid.sample(target).gradient;
      m = axis >= 0 ? in_plane(m, axis) : unit_or_zero(m);
      if (!(squared_norm(m) > 0)) m = d;
      targets.plane_normal[v] = m;
      targets.plane_offset[v] = dot(m, target - p);
    }
  });
  for (std::size_t v = 0; v < n; ++v)
    targets.unpierced += mesh.role[v] != WrapRole::Fixed && !(squared_norm(targets.plane_normal[v]) > 0);
  return targets;
}

void add_coverage_pull(CoveragePull& pull, const WrapLevelMesh& mesh, const std::vector<Vec3>& positions,
                       double reach, LevelTargets& targets) {
  std::vector<Vec3> moved = positions;
  std::vector<PulledPoint> pulled;
  pull.apply(mesh, moved, reach, &pulled);
  targets.pull_offset.assign(positions.size(), Vec3{});
  targets.pulled.assign(positions.size(), 0);
  for (const PulledPoint& p : pulled) {
    targets.pulled[p.vertex] = 1;
    targets.pull_offset[p.vertex] = moved[p.vertex] - positions[p.vertex];
  }
}

double mean_edge_length(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions) {
  const std::size_t stride = std::max<std::size_t>(1, mesh.vertex_count / 65536);
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t v = 0; v < mesh.vertex_count; v += stride)
    for (std::uint32_t k = mesh.neighbour_offsets[v]; k < mesh.neighbour_offsets[v + 1]; ++k) {
      sum += std::sqrt(squared_norm(positions[mesh.neighbours[k]] - positions[v]));
      ++count;
    }
  return count ? sum / double(count) : 0.0;
}

}  // namespace isowave::detail
