#include "isowave/fit/correction.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/fit/trilinear.h"
#include "fitted_field.h"
#include "root_search.h"
#include "wrap_kernels.h"
#include "wrap_passes.h"

namespace isowave::wrap {

bool project_onto_isosurface(const WrapLevelMesh& mesh, const Box& box, const TrilinearGrid& field, double cell,
                             double iso, double range, std::size_t v, const Vec3& p, Vec3& target,
                             int parallel_axis) {
  const Vec3 pg = field.grid_point(p);
  const TrilinearSample s = field.sample_at(pg);
  const double h0 = s.value - iso;
  if (!std::isfinite(h0)) return false;
  if (h0 == 0) {
    target = p;
    return true;
  }
  Vec3 u = s.gradient;
  if (parallel_axis >= 0) u[parallel_axis] = 0.0;
  u = allowed_direction(mesh, v, u);
  const double slope = dot(s.gradient, u);
  if (!(slope > 0)) return false;
  double t_low, t_high;
  box.clip(p, u, t_low, t_high);
  const Vec3 ug = field.grid_direction(u);
  const auto h = [&](double t) { return field.value_at(pg + std::clamp(t, t_low, t_high) * ug) - iso; };
  double t = 0;
  const double tolerance = 1e-4 * cell;
  // Newton steps along the line (one or two samples near the surface), then
  // the bracketed search if they do not settle. Newton converges
  // quadratically (the trilinear field is a cubic along the line), so a
  // correction under 1e-2 cells leaves an error near 1e-4 cells: taken
  // without another sample to confirm it.
  const double settled = 1e-2 * cell;
  bool found = false;
  double newton = -h0 / slope;
  for (int step = 0; step < 3 && std::abs(newton) <= range; ++step) {
    const TrilinearSample sample = field.sample_at(pg + std::clamp(newton, t_low, t_high) * ug);
    const double along = dot(sample.gradient, u);
    if (!(along > 0) || !std::isfinite(sample.value)) break;
    const double correction = (sample.value - iso) / along;
    newton -= correction;
    if (std::abs(correction) <= settled) {
      found = std::abs(newton) <= range && newton >= t_low && newton <= t_high;
      break;
    }
  }
  if (found) t = newton;
  else if (!detail::find_root_along_line(h, h0, -h0 / slope, range, 0.25 * cell, tolerance, t)) return false;
  target = place(mesh, box, v, p + std::clamp(t, t_low, t_high) * u);
  return is_finite(target);
}

namespace {

// Rounds of retrying failed corrections from the neighbours' centroid.
constexpr int kCorrectionRetryRounds = 5;
// The last search of the correction reaches this many times its range.
constexpr double kWideSearchRanges = 3.0;
// How far a stranded vertex may move to the extracted surface (see
// CorrectionStatistics::from_extracted_surface), in cells.
constexpr double kStrandedReachCells = 16.0;

struct CorrectionPartial {
  std::size_t movable = 0, corrected = 0, nearest = 0, along_box = 0;
  double move_sum = 0, move_max = 0;
  std::vector<std::uint32_t> failed;  // no root found: left where they were
};

// A point of the zero set of `distance` reached from p by steps along its
// gradient (kept in the box, within `range` of p); false if they do not
// settle. Newton's steps, or with `unit_steps` the distance itself along
// the unit gradient wherever the gradient is shorter than 1: the field is a
// distance, and where its gradient is short (near the medial axis between
// two sheets, where the corrections that need this sit) Newton's step
// overshoots.
bool zero_along_gradient(const TrilinearGrid& distance, const Box& box, double cell, double range, const Vec3& p,
                         bool unit_steps, Vec3& x) {
  x = p;
  for (int step = 0; step < 20; ++step) {
    const TrilinearSample s = distance.sample(x);
    const double length = norm(s.gradient);
    if (!(length > 0) || !std::isfinite(s.value)) return false;
    const Vec3 move = (s.value / (length * (unit_steps ? std::max(length, 1.0) : length))) * s.gradient;
    x = box.clamp(x - move);
    if (!(norm(x - p) <= range)) return false;
    if (norm(move) <= 1e-4 * cell) return true;
  }
  return false;
}

// Zeros of `distance` near p from both step rules (see
// zero_along_gradient), nearer first; returns how many (0 to 2).
int nearest_zeros(const TrilinearGrid& distance, const Box& box, double cell, double range, const Vec3& p,
                  Vec3 zeros[2]) {
  int count = 0;
  Vec3 x;
  for (const bool unit_steps : {true, false})
    if (zero_along_gradient(distance, box, cell, range, p, unit_steps, x)) zeros[count++] = x;
  if (count == 2 && squared_norm(zeros[1] - p) < squared_norm(zeros[0] - p)) std::swap(zeros[0], zeros[1]);
  return count;
}

// The axis of the box face within one cell of p (the nearest), or -1.
int near_box_axis(const Box& box, double cell, const Vec3& p) {
  int axis = -1;
  double nearest = cell;
  for (int a = 0; a < 3; ++a)
    for (const double plane : {box.low[a], box.high[a]})
      if (std::abs(p[a] - plane) < nearest) {
        nearest = std::abs(p[a] - plane);
        axis = a;
      }
  return axis;
}

// A root of f - iso along a direction from p.
struct Root {
  double distance;
  Vec3 at;
};

// The first root of f - iso from p along each of `count` unit directions
// (within the box and `range`), each probed every quarter cell and its
// bracket refined; stored in `roots` nearest first, returns their number.
int roots_along(const TrilinearGrid& field, const Box& box, double cell, double iso, double range, const Vec3& p,
                const Vec3* directions, int count, Root* roots) {
  const double h0 = field.value(p) - iso;
  if (!std::isfinite(h0)) return 0;
  const double step = 0.25 * cell, tolerance = 1e-4 * cell;
  int found = 0;
  for (int k = 0; k < count; ++k) {
    const Vec3& d = directions[k];
    double t_low, t_high, t;
    box.clip(p, d, t_low, t_high);
    const auto h = [&](double s) { return field.value(p + s * d) - iso; };
    if (detail::find_root_along_line(h, h0, step, std::min(range, t_high), step, tolerance, t))
      roots[found++] = {t, p + t * d};
  }
  std::sort(roots, roots + found, [](const Root& a, const Root& b) { return a.distance < b.distance; });
  return found;
}

constexpr int kPlaneDirections = 16;

// The kPlaneDirections unit directions of the plane normal to `axis`.
void plane_directions(int axis, Vec3 directions[kPlaneDirections]) {
  constexpr double kPi = 3.14159265358979323846;
  for (int k = 0; k < kPlaneDirections; ++k) {
    const double angle = 2.0 * kPi * k / kPlaneDirections;
    directions[k] = Vec3{};
    directions[k][(axis + 1) % 3] = std::cos(angle);
    directions[k][(axis + 2) % 3] = std::sin(angle);
  }
}

// The nearest root of f - iso within the plane through p normal to `axis`
// (a box face's; the target stays on the face), within `range`
// (roots_along the plane's directions). For points pressed onto a box face
// where the field's gradient is normal to it, so that the search along its
// part within the face has nowhere to go (a volume cut through the material
// at a box face, whose gradient points into the box).
bool nearest_root_in_plane(const TrilinearGrid& field, const Box& box, double cell, double iso, double range,
                           const Vec3& p, int axis, Vec3& target) {
  Vec3 directions[kPlaneDirections];
  plane_directions(axis, directions);
  Root roots[kPlaneDirections];
  if (roots_along(field, box, cell, iso, range, p, directions, kPlaneDirections, roots) == 0) return false;
  target = roots[0].at;
  return true;
}

// The 26 unit directions to a cube's neighbours.
struct CubeDirections {
  Vec3 directions[26];
  CubeDirections() {
    int k = 0;
    for (int z = -1; z <= 1; ++z)
      for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x)
          if (x || y || z) {
            const Vec3 d{double(x), double(y), double(z)};
            directions[k++] = (1.0 / norm(d)) * d;
          }
  }
};

// The correction of one movable vertex v (see correct_with), in place and
// counted in `partial`; false if it found no root and left v where it was.
bool correct_vertex(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell, double iso,
                    double range, const TrilinearGrid* nearest, std::size_t v, std::vector<Vec3>& positions,
                    CorrectionPartial& partial) {
  ++partial.movable;
  const Vec3 p = positions[v];
  Vec3 target, starts[2];
  if (!project_onto_isosurface(mesh, box, field, cell, iso, range, v, p, target)) {
    const bool free = mesh.role[v] == WrapRole::Free && mesh.box_face[v] < 0;
    // The distance field's zeros a little farther (see
    // ShrinkWrapOptions::correction_from_nearest_point).
    const int zeros = free && nearest ? nearest_zeros(*nearest, box, cell, 1.5 * range, p, starts) : 0;
    int from = 0;
    while (from < zeros && !project_onto_isosurface(mesh, box, field, cell, iso, range, v, starts[from], target)) ++from;
    if (from < zeros) {
      ++partial.nearest;
    } else {
      // Within the plane of a box face: the vertex's own, or for a free one
      // the nearest face's within a cell.
      const int axis = free ? near_box_axis(box, cell, p) : mesh.box_face[v] >= 0 ? mesh.box_face[v] >> 1 : -1;
      if (axis < 0 || !((free && project_onto_isosurface(mesh, box, field, cell, iso, range, v, p, target, axis)) ||
                        nearest_root_in_plane(field, box, cell, iso, range, p, axis, target))) {
        partial.failed.push_back(static_cast<std::uint32_t>(v));
        return false;
      }
      ++partial.along_box;
    }
  }
  positions[v] = target;
  ++partial.corrected;
  const double moved = norm(target - p) / cell;
  partial.move_sum += moved;
  partial.move_max = std::max(partial.move_max, moved);
  return true;
}

// The faces of `surface` near `points` (a first corner within `reach` plus
// two cells of one: the extracted triangles are under a cell across, so
// this holds every face within `reach`), each with its own corners. Keeps
// the bins of the stranded vertices' search small.

PolygonMesh faces_near(const PolygonMesh& surface, const Box& box, double cell, double reach,
                       const std::vector<Vec3>& points) {
  // Marked blocks of 8 x 8 x 8 cells.
  const double block = 8 * cell;
  std::int64_t dims[3];
  for (int a = 0; a < 3; ++a)
    dims[a] = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil((box.high[a] - box.low[a]) / block)) + 1);
  const auto block_along = [&](int a, double x) {
    return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((x - box.low[a]) / block)), 0, dims[a] - 1);
  };
  const auto block_of = [&](const Vec3& p) {
    return static_cast<std::size_t>(block_along(0, p.x) +
                                    dims[0] * (block_along(1, p.y) + dims[1] * block_along(2, p.z)));
  };
  std::vector<std::uint8_t> marked(static_cast<std::size_t>(dims[0] * dims[1] * dims[2]), 0);
  const double margin = reach + 2 * cell;
  for (const Vec3& p : points)
    for (std::int64_t z = block_along(2, p.z - margin); z <= block_along(2, p.z + margin); ++z)
      for (std::int64_t y = block_along(1, p.y - margin); y <= block_along(1, p.y + margin); ++y)
        for (std::int64_t x = block_along(0, p.x - margin); x <= block_along(0, p.x + margin); ++x)
          marked[static_cast<std::size_t>(x + dims[0] * (y + dims[1] * z))] = 1;
  const std::vector<std::vector<std::uint32_t>> chosen = for_blocks<std::vector<std::uint32_t>>(
      surface.face_count(), [&](std::size_t first, std::size_t last, std::vector<std::uint32_t>& faces) {
        for (std::size_t f = first; f < last; ++f)
          if (marked[block_of(surface.positions[surface.face_begin(f)[0]])])
            faces.push_back(static_cast<std::uint32_t>(f));
      });
  PolygonMesh near;
  std::vector<std::uint32_t> corners;
  for (const std::vector<std::uint32_t>& faces : chosen)
    for (const std::uint32_t f : faces) {
      corners.clear();
      for (std::size_t k = 0; k < surface.face_size(f); ++k) {
        corners.push_back(static_cast<std::uint32_t>(near.positions.size()));
        near.positions.push_back(surface.positions[surface.face_begin(f)[k]]);
      }
      near.add_face(corners.data(), corners.size());
    }
  return near;
}

// The vertices a correction has not placed yet (Jacobi: each pass computes
// targets from the positions before it, then moves), and its statistics.
struct Pending {
  const WrapLevelMesh& mesh;
  const TrilinearGrid& field;
  const Box& box;
  const double cell, iso, range;
  std::vector<Vec3>& positions;
  CorrectionStatistics stats;
  double sum = 0;  // of the moves, cells
  std::vector<std::uint32_t> failed;
  std::vector<Vec3> target;
  std::vector<std::uint8_t> found;

  // Moves each failed vertex with found[i] to target[i], counted also in
  // `counter`; the rest stay failed. False if none moved.
  bool move_found(std::size_t& counter) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < failed.size(); ++i) {
      if (!found[i]) {
        failed[kept++] = failed[i];
        continue;
      }
      const double moved = norm(target[i] - positions[failed[i]]) / cell;  // from where the fit left it
      positions[failed[i]] = target[i];
      sum += moved;
      stats.max_move_cells = std::max(stats.max_move_cells, moved);
      ++stats.corrected;
      ++counter;
    }
    const bool any = kept < failed.size();
    failed.resize(kept);
    return any;
  }
};

// The first pass over every movable vertex (correct_vertex), in parallel.
void correct_movable(Pending& run, const TrilinearGrid* nearest) {
  const WrapLevelMesh& mesh = run.mesh;
  const TrilinearGrid& field = run.field;
  std::vector<Vec3>& positions = run.positions;
  const std::vector<CorrectionPartial> partials = for_blocks<CorrectionPartial>(
      mesh.vertex_count, [&](std::size_t begin, std::size_t end, CorrectionPartial& partial) {
        for (std::size_t v = begin; v < end; ++v) {
          if (v + kPrefetchDistance < end) field.prefetch_at(field.grid_point(positions[v + kPrefetchDistance]));
          if (mesh.role[v] != WrapRole::Fixed)
            correct_vertex(mesh, field, run.box, run.cell, run.iso, run.range, nearest, v, positions, partial);
        }
      });
  CorrectionStatistics& stats = run.stats;
  for (const CorrectionPartial& partial : partials) {
    stats.movable += partial.movable;
    stats.corrected += partial.corrected;
    stats.from_nearest_point += partial.nearest;
    stats.along_box_face += partial.along_box;
    run.sum += partial.move_sum;
    stats.max_move_cells = std::max(stats.max_move_cells, partial.move_max);
    run.failed.insert(run.failed.end(), partial.failed.begin(), partial.failed.end());
  }
}

// A vertex without a root tries again from its neighbours' centroid, most
// of whose corners found the isosurface; Jacobi rounds while they help.
void retry_from_neighbours(Pending& run) {
  const WrapLevelMesh& mesh = run.mesh;
  const Box& box = run.box;
  std::vector<std::uint32_t>& failed = run.failed;
  for (int round = 0; round < kCorrectionRetryRounds && !failed.empty(); ++round) {
    run.target.resize(failed.size());
    run.found.assign(failed.size(), 0);
    for_vertices(failed.size(), [&](std::size_t i) {
      const std::uint32_t v = failed[i];
      Vec3 centroid;
      run.found[i] = relaxation_centroid(mesh, v, run.positions, centroid) &&
                     project_onto_isosurface(mesh, box, run.field, run.cell, run.iso, run.range, v,
                                             place(mesh, box, v, centroid), run.target[i]);
    });
    if (!run.move_found(run.stats.from_neighbours)) break;
  }
}

// With wide_search_sign (the expected sign of face normals against the
// gradient, see face_folded), the roots within kWideSearchRanges ranges
// along the 26 directions to a cube's neighbours (within its face's plane for
// a vertex held on a box face): the nearest at which no more of the vertex's
// faces are folded than before. Each vertex is judged with the others where
// they were (Jacobi). A last resort (up to 624 samples each): for at most 1%
// of the vertices (at least 10,000), the first by index.
void wide_search(Pending& run, double wide_search_sign) {
  const WrapLevelMesh& mesh = run.mesh;
  const TrilinearGrid& field = run.field;
  const std::vector<Vec3>& positions = run.positions;
  const std::vector<std::uint32_t>& failed = run.failed;
  std::vector<Vec3>& target = run.target;
  std::vector<std::uint8_t>& found = run.found;
  const CubeDirections cube;
  const std::size_t searched = std::min(failed.size(), std::max<std::size_t>(10000, mesh.vertex_count / 100));
  target.resize(searched);
  found.assign(failed.size(), 0);
  for_vertices(searched, [&](std::size_t i) {
    const std::uint32_t v = failed[i];
    Vec3 in_plane[kPlaneDirections];
    const Vec3* directions = cube.directions;
    int count = 26;
    if (mesh.box_face[v] >= 0) {
      plane_directions(mesh.box_face[v] >> 1, in_plane);
      directions = in_plane;
      count = kPlaneDirections;
    }
    Root roots[26];
    const int found_roots = roots_along(field, run.box, run.cell, run.iso, kWideSearchRanges * run.range, positions[v],
                                        directions, count, roots);
    const int before = folded_faces_around(mesh, field, wide_search_sign, positions, v, positions[v]);
    for (int r = 0; r < found_roots && !found[i]; ++r) {
      const Vec3& at = roots[r].at;
      if (is_finite(at) && folded_faces_around(mesh, field, wide_search_sign, positions, v, at) <= before) {
        target[i] = at;
        found[i] = 1;
      }
    }
  });
  run.move_found(run.stats.from_wide_search);
}

// The stranded vertices: those a cell or more from the extracted surface by
// its distance field, which no search along the field finds (beyond the
// band, or where the field is flat), start from the nearest point of that
// surface within kStrandedReachCells.
void from_extracted_surface(Pending& run, const PolygonMesh& surface, const TrilinearGrid& distance) {
  const WrapLevelMesh& mesh = run.mesh;
  const Box& box = run.box;
  const double cell = run.cell;
  const std::vector<Vec3>& positions = run.positions;
  const std::vector<std::uint32_t>& failed = run.failed;
  std::vector<std::uint8_t> far(failed.size(), 0);
  std::vector<Vec3> stranded;
  for (std::size_t i = 0; i < failed.size(); ++i)
    if (std::abs(distance.value(positions[failed[i]])) >= cell) {
      far[i] = 1;
      stranded.push_back(positions[failed[i]]);
    }
  const double reach = kStrandedReachCells * cell;
  const PolygonMesh near = stranded.empty() ? PolygonMesh{} : faces_near(surface, box, cell, reach, stranded);
  if (near.face_count() > 0) {  // none: every stranded vertex is beyond reach
    const BinnedSurfaceDistance surface_distance(near);
    run.found.assign(failed.size(), 0);
    run.target.resize(failed.size());
    for_vertices(failed.size(), [&](std::size_t i) {
      if (!far[i]) return;
      const std::uint32_t v = failed[i];
      const Vec3 q = surface_distance.closest_point(positions[v]);
      run.found[i] = norm(q - positions[v]) <= reach &&
                     project_onto_isosurface(mesh, box, run.field, cell, run.iso, run.range, v, place(mesh, box, v, q),
                                             run.target[i]);
    });
    run.move_found(run.stats.from_extracted_surface);
  }
}

}  // namespace

// correct_to_isosurface(); with `nearest` (the signed-distance field), a free
// vertex whose gradient line has no root within range starts again from a
// nearby point of the distance field's zero set (see
// ShrinkWrapOptions::correction_from_nearest_point). A free vertex still without
// a root searches within the plane parallel to the nearest box face within a
// cell (see CorrectionStatistics::along_box_face). With `surface` and
// `distance` (the extracted surface and its signed-distance field), a vertex
// left a cell or more from it starts again from its nearest point
// (CorrectionStatistics::from_extracted_surface).
CorrectionStatistics correct_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                  double iso, double max_move_cells, std::vector<Vec3>& positions,
                                  const TrilinearGrid* nearest, double wide_search_sign, const PolygonMesh* surface,
                                  const TrilinearGrid* distance) {
  assert(positions.size() >= mesh.vertex_count);
  Pending run{mesh, field, box, cell, iso, max_move_cells * cell, positions, {}, 0.0, {}, {}, {}};
  correct_movable(run, nearest);
  retry_from_neighbours(run);
  if (wide_search_sign != 0 && !run.failed.empty()) wide_search(run, wide_search_sign);
  if (surface && distance && surface->face_count() > 0 && !run.failed.empty())
    from_extracted_surface(run, *surface, *distance);
  run.stats.failed = run.failed.size();
  run.stats.mean_move_cells = run.stats.corrected ? run.sum / double(run.stats.corrected) : 0.0;
  return run.stats;
}

std::size_t settle_pulled_points(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                 double iso, Orientation orientation, double max_move_cells,
                                 const TrilinearGrid* nearest,
                                 const std::vector<PulledPoint>& pulled, std::vector<Vec3>& positions) {
  const double expected_sign = unfolded_sign(orientation);
  std::vector<std::uint8_t> back(pulled.size(), 0);
  for_blocks<char>(pulled.size(), [&](std::size_t first, std::size_t last, char&) {
    CorrectionPartial partial;
    for (std::size_t i = first; i < last; ++i)
      back[i] = !correct_vertex(mesh, field, box, cell, iso, max_move_cells * cell, nearest, pulled[i].vertex,
                                positions, partial);
  });
  // Judged with every other pulled point in its new place, then applied.
  for_vertices(pulled.size(), [&](std::size_t i) {
    if (back[i]) return;
    const std::uint32_t v = pulled[i].vertex;
    const int now = folded_faces_around(mesh, field, expected_sign, positions, v, positions[v]);
    back[i] = now > 0 && now > folded_faces_around(mesh, field, expected_sign, positions, v, pulled[i].from);
  });
  std::size_t count = 0;
  for (std::size_t i = 0; i < pulled.size(); ++i)
    if (back[i]) {
      positions[pulled[i].vertex] = pulled[i].from;
      ++count;
    }
  return count;
}

}  // namespace isowave::wrap

namespace isowave {

CorrectionStatistics correct_to_isosurface(const WrapLevelMesh& mesh, const Volume& field, double iso,
                                           double max_move_cells, std::vector<Vec3>& positions,
                                           const CorrectionFallbacks& fallbacks) {
  assert(!fallbacks.surface_distance || fallbacks.surface_distance->dims == field.dims);
  std::optional<TrilinearGrid> distance;
  if (fallbacks.surface_distance) distance.emplace(*fallbacks.surface_distance);
  const detail::FittedField fitted(field, iso);
  const double wide_search_sign = fallbacks.wide_search ? wrap::unfolded_sign(*fallbacks.wide_search) : 0.0;
  return wrap::correct_with(mesh, fitted.grid(), wrap::Box(field), field.cell_size(), iso, max_move_cells, positions,
                            nullptr, wide_search_sign, fallbacks.surface, distance ? &*distance : nullptr);
}

}  // namespace isowave
