#include "isowave/fit/normal_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "isowave/core/error.h"
#include "isowave/fit/trilinear.h"
#include "isowave/fit/wrap_level_mesh.h"
#include "isowave/transform/wavelet_transform.h"
#include "fitted_field.h"
#include "coverage_pull.h"
#include "normal_targets.h"
#include "wrap_kernels.h"

namespace isowave {

std::size_t NormalFitResult::non_normal_count() const {
  return static_cast<std::size_t>(std::count(non_normal.begin(), non_normal.end(), std::uint8_t{1}));
}

namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kGrain = 8192;
// Levenberg-Marquardt damping of each round's step, relative to a unit
// coefficient's own weight: keeps points without a target where they are.
constexpr double kDamping = 1e-3;
// The coverage pull: an extracted vertex farther than kCoveredCells from the
// level's points pulls the nearest within kPullReachCells.
constexpr double kCoveredCells = 1.0;
constexpr double kPullReachCells = 4.0;
constexpr double kPullMaxEdgeCells = 1.0;

template <class Body>
void for_each_index(std::size_t n, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) body(i);
  });
}

// Sum over i of term(i), the same for any thread count (fixed blocks).
template <class Term>
double deterministic_sum(std::size_t n, const Term& term) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, n, kGrain), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double sum) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) sum += term(i);
        return sum;
      },
      [](double a, double b) { return a + b; });
}

// The unknowns of one least-squares problem: the first vertex_count(level)
// entries of the coarse-to-fine array (base points, then the coefficients of
// levels 1..level), each a free 3-vector or a scalar along its unit direction.
// Lifted wavelets have (nearly) no mean, so what S leaves off the surface
// smoothly can only come from coarser entries: every level's fit moves them all.
struct Unknowns {
  int level = 1;                                  // the synthesis depth they feed
  const std::vector<Vec3>* directions = nullptr;  // per entry of the fine array
  const std::vector<std::uint8_t>* free = nullptr;  // per entry: 1 = a 3-vector
  std::size_t size = 0;
  Vec3 project(std::size_t k, const Vec3& x) const {
    if ((*free)[k]) return x;
    const Vec3& n = (*directions)[k];
    return n * dot(n, x);
  }
};

// The linearized problem of one round: minimize over x (in the unknowns'
// space) sum_v |residual_v(W x)|^2 + damping |x|^2, W the synthesis from the
// unknowns to level `level`'s control points.
class LevelSystem {
 public:
  LevelSystem(const SubdivisionHierarchy& h, const Unknowns& unknowns, const detail::LevelTargets& targets)
      : h_(h), u_(unknowns), t_(targets), n_(h.vertex_count(unknowns.level)) {}

  // x -> W x (moves of the level's control points).
  void moves(const std::vector<Vec3>& x, std::vector<Vec3>& out) const {
    out.assign(n_, Vec3{});
    for_each_index(u_.size, [&](std::size_t k) { out[k] = u_.project(k, x[k]); });
    synthesize(h_, out, u_.level);
  }

  // Per control point: J^T J applied to its move (the residuals' normal
  // matrix): the tangent plane's normal, the box face's axis; a pulled
  // point's whole move.
  Vec3 residual_gram(std::size_t v, const Vec3& d) const {
    if (t_.pulled[v]) return d;
    const Vec3& m = t_.plane_normal[v];
    Vec3 out = m * dot(m, d);
    if (t_.box_axis[v] >= 0) out[t_.box_axis[v]] += d[t_.box_axis[v]];
    return out;
  }
  // Per control point: J^T of its target offsets.
  Vec3 residual_target(std::size_t v) const {
    if (t_.pulled[v]) return t_.pull_offset[v];
    Vec3 out = t_.plane_normal[v] * t_.plane_offset[v];
    if (t_.box_axis[v] >= 0) out[t_.box_axis[v]] += t_.box_offset[v];
    return out;
  }

  bool free(std::size_t k) const { return (*u_.free)[k]; }

  // g over the level's control points -> W^T g over the unknowns, in place
  // (g ends with one entry per unknown).
  void gather(std::vector<Vec3>& g) const {
    for (int level = u_.level; level >= 1; --level) synthesize_level_transpose(h_, level, g);
    g.resize(u_.size);
    for_each_index(u_.size, [&](std::size_t k) { g[k] = u_.project(k, g[k]); });
  }

  void apply(const std::vector<Vec3>& x, std::vector<Vec3>& out) const {
    moves(x, out);
    for_each_index(n_, [&](std::size_t v) { out[v] = residual_gram(v, out[v]); });
    gather(out);
    for_each_index(u_.size, [&](std::size_t k) { out[k] += kDamping * x[k]; });
  }

  void right_side(std::vector<Vec3>& out) const {
    out.resize(n_);
    for_each_index(n_, [&](std::size_t v) { out[v] = residual_target(v); });
    gather(out);
  }

 private:
  const SubdivisionHierarchy& h_;
  const Unknowns& u_;
  const detail::LevelTargets& t_;
  std::size_t n_;
};

double inner(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return deterministic_sum(a.size(), [&](std::size_t i) { return dot(a[i], b[i]); });
}

// Class of an entry for the preconditioner: 0 for the base, then f and e
// entries of each level.
std::vector<std::uint8_t> entry_classes(const SubdivisionHierarchy& h, int level) {
  std::vector<std::uint8_t> classes(h.vertex_count(level), 0);
  for (int l = 1; l <= level; ++l) {
    const RefinementStep& s = h.step(l);
    for (std::size_t i = h.vertex_count(l - 1); i < h.vertex_count(l); ++i)
      classes[i] = static_cast<std::uint8_t>(2 * l - 1 + (i >= s.first_edge_vertex()));
  }
  return classes;
}

// A Jacobi preconditioner by class: the mean over each class of the squared
// columns of W (estimated as (W^T z)^2 for random signs z, one probe), plus
// the damping. Cost: one transposed synthesis.
std::vector<double> class_diagonal(const LevelSystem& system, std::size_t points,
                                   const std::vector<std::uint8_t>& classes) {
  const std::size_t n = classes.size();
  std::vector<Vec3> z(points);
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  for (Vec3& v : z)
    for (int c = 0; c < 3; ++c) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      v[c] = (state >> 63) ? 1.0 : -1.0;
    }
  system.gather(z);
  const std::size_t count = *std::max_element(classes.begin(), classes.end()) + 1u;
  std::vector<double> sum(count, 0.0), members(count, 0.0);
  // A free entry's three components each, a normal entry's one.
  for (std::size_t k = 0; k < n; ++k) {
    sum[classes[k]] += squared_norm(z[k]) / (system.free(k) ? 3.0 : 1.0);
    members[classes[k]] += 1;
  }
  for (std::size_t c = 0; c < count; ++c) sum[c] = (members[c] > 0 ? sum[c] / members[c] : 0.0) + kDamping;
  return sum;
}

// Preconditioned conjugate gradients on the round's normal equations from x = 0.
std::vector<Vec3> solve_round(const LevelSystem& system, std::size_t points, std::size_t unknowns,
                              const std::vector<std::uint8_t>& classes, int iterations) {
  const std::vector<double> diagonal = class_diagonal(system, points, classes);
  std::vector<Vec3> x(unknowns), r, z(unknowns), p, q;
  system.right_side(r);
  const auto precondition = [&] {
    for_each_index(unknowns, [&](std::size_t k) { z[k] = r[k] * (1.0 / diagonal[classes[k]]); });
  };
  precondition();
  p = z;
  double rz = inner(r, z);
  const double stop = 1e-12 * rz;
  for (int it = 0; it < iterations && rz > stop && rz > 0; ++it) {
    system.apply(p, q);
    const double pq = inner(p, q);
    if (!(pq > 0)) break;
    const double alpha = rz / pq;
    for_each_index(unknowns, [&](std::size_t k) {
      x[k] += alpha * p[k];
      r[k] -= alpha * q[k];
    });
    precondition();
    const double next = inner(r, z);
    const double beta = next / rz;
    rz = next;
    for_each_index(unknowns, [&](std::size_t k) { p[k] = z[k] + beta * p[k]; });
  }
  return x;
}

struct FitInputs {
  const SubdivisionHierarchy& hierarchy;
  const Volume& field;
  const TrilinearGrid& grid;
  double iso;
  double facing;  // the field's slope along an outward normal: wrap::unfolded_sign(orientation)
  const BinnedSurfaceDistance* surface;
  const NormalFitOptions& options;
  CoveragePull* pull;  // nullptr without the extracted surface
};

// Level `level`'s control points from the coarse-to-fine array `data`.
std::vector<Vec3> synthesize_points(const SubdivisionHierarchy& h, int level, const std::vector<Vec3>& data) {
  std::vector<Vec3> points(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(h.vertex_count(level)));
  synthesize(h, points, level);
  return points;
}

// The residual figures of the level's control points at their targets.
void measure(const detail::LevelTargets& targets, double cell, NormalFitLevelStatistics& stats) {
  const std::size_t n = targets.plane_offset.size();
  double sum = 0, worst = 0;
  std::size_t count = 0;
  for (std::size_t v = 0; v < n; ++v)
    if (squared_norm(targets.plane_normal[v]) > 0) {
      const double d = std::abs(targets.plane_offset[v]) / cell;
      sum += d * d;
      worst = std::max(worst, d);
      ++count;
    }
  stats.rms_cells = count ? std::sqrt(sum / double(count)) : 0.0;
  stats.max_cells = worst;
  stats.unpierced = targets.unpierced;
}

// Adds `step` to the unknowns of `data` and moves `points` with it; a step
// that would move some point farther than the reach is shortened to it (a
// linearization holds near the targets only).
void take_step(const SubdivisionHierarchy& h, const Unknowns& u, const std::vector<Vec3>& step, double reach,
               std::vector<Vec3>& data, std::vector<Vec3>& points) {
  std::vector<Vec3> moved(h.vertex_count(u.level));
  for_each_index(u.size, [&](std::size_t k) { moved[k] = u.project(k, step[k]); });
  synthesize(h, moved, u.level);
  const double longest = std::sqrt(tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, moved.size(), kGrain), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double m) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) m = std::max(m, squared_norm(moved[i]));
        return m;
      },
      [](double a, double b) { return std::max(a, b); }));
  if (!std::isfinite(longest)) return;  // a failed solve changes nothing
  const double scale = longest > reach ? reach / longest : 1.0;
  for_each_index(u.size, [&](std::size_t k) { data[k] += u.project(k, step[k]) * scale; });
  for_each_index(points.size(), [&](std::size_t v) { points[v] += moved[v] * scale; });
}

// The coefficients of [first, end) whose points' lines had no admissible
// crossing become free 3-vectors, aimed along the field gradient from now on.
void free_off_line(const detail::LevelTargets& targets, std::size_t first, std::size_t end,
                   std::vector<std::uint8_t>& free, std::vector<Vec3>& aim) {
  for (std::size_t i = first; i < end; ++i) {
    const bool off = !(squared_norm(targets.plane_normal[i]) > 0) || targets.off_line[i];
    if (!off || free[i]) continue;
    free[i] = 1;
    aim[i] = Vec3{};  // the field gradient (level_targets)
  }
}

double level_reach(const FitInputs& in, const WrapLevelMesh& mesh, const std::vector<Vec3>& points) {
  return std::max(in.options.min_reach_cells * in.field.cell_size(),
                  in.options.reach_edges * detail::mean_edge_length(mesh, points));
}

// One level's fit: Gauss-Newton rounds on every entry up to `level` (the
// free ones as 3-vectors, the others along `directions`), each retargeting
// the level's control points and adding one solve's step; after the first
// half of the rounds, the level's own coefficients whose points' lines have
// no admissible crossing become free.
NormalFitLevelStatistics fit_level(const FitInputs& in, int level, const std::vector<Vec3>& directions,
                                   std::vector<std::uint8_t>& free, std::vector<Vec3>& data) {
  const auto start = Clock::now();
  const SubdivisionHierarchy& h = in.hierarchy;
  std::vector<Vec3> points = synthesize_points(h, level, data);
  const WrapLevelMesh mesh = make_wrap_level_mesh(h, level, points, in.field, in.iso);
  const std::size_t first = h.vertex_count(level - 1), end = h.vertex_count(level);
  // Free: boundary curves (held in their box face) and degenerate patches (no normal).
  for (std::size_t i = first; i < end; ++i)
    if (mesh.role[i] != WrapRole::Free || !(squared_norm(directions[i]) > 0)) free[i] = 1;
  const Unknowns u{level, &directions, &free, end};
  std::vector<std::uint8_t> classes = entry_classes(h, level);
  const double reach = level_reach(in, mesh, points);
  // The pull only where the level samples the surface finely (as the
  // shrink-wrap's), and not before the last round, which puts the pulled
  // points back on the isosurface where they now are.
  const bool fine_level = detail::mean_edge_length(mesh, points) <= kPullMaxEdgeCells * in.field.cell_size();
  std::vector<Vec3> aim(directions.begin(), directions.begin() + static_cast<std::ptrdiff_t>(end));
  const auto retarget = [&](bool pull) {
    detail::LevelTargets t =
        detail::level_targets(mesh, points, aim, in.grid, in.field, in.iso, in.facing, reach, in.surface);
    if (pull && fine_level && in.pull)
      detail::add_coverage_pull(*in.pull, mesh, points, kPullReachCells * in.field.cell_size(), t);
    return t;
  };
  const int rounds = in.options.rounds, free_after = std::max(1, rounds / 2);
  detail::LevelTargets targets = retarget(rounds > 1);
  for (int round = 0; round < rounds; ++round) {
    const LevelSystem system(h, u, targets);
    const std::vector<Vec3> step = solve_round(system, points.size(), u.size, classes, in.options.cg_iterations);
    take_step(h, u, step, reach, data, points);
    targets = retarget(round + 2 < rounds);
    if (round + 1 == free_after) free_off_line(targets, first, end, free, aim);
  }
  NormalFitLevelStatistics stats;
  stats.level = level;
  stats.vertices = end;
  stats.coefficients = end - first;
  stats.non_normal = static_cast<std::size_t>(std::count(free.begin() + static_cast<std::ptrdiff_t>(first),
                                                         free.begin() + static_cast<std::ptrdiff_t>(end), std::uint8_t{1}));
  measure(targets, in.field.cell_size(), stats);
  stats.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return stats;
}

// Starts from `previous`, a fit of the same base to fewer levels: its
// entries, its non-normal flags and level statistics. Returns the first
// level left to fit.
int start_from(const NormalFitResult& previous, const SubdivisionHierarchy& h, std::vector<Vec3>& data,
               std::vector<std::uint8_t>& free, NormalFitResult& result) {
  const std::size_t base_count = h.vertex_count(0), n = previous.coefficients.size();
  const int done = static_cast<int>(previous.levels.size());
  if (done >= h.levels() || n != h.vertex_count(done) || previous.non_normal.size() + base_count != n ||
      previous.frame_base.size() != base_count)
    throw Error(ErrorKind::InvalidArgument, "the normal fit's start is not a fit of the same base to fewer levels");
  for (std::size_t i = 0; i < n; ++i) {
    free[i] = i < base_count ? 1 : previous.non_normal[i - base_count];
    data[i] = previous.coefficients[i];
  }
  result.levels = previous.levels;
  result.frame_base = previous.frame_base;
  return done + 1;
}

// The directions of the frame base `result.frame_base`, and the normal
// entries of `data` turned onto them.
std::vector<Vec3> take_directions(const NormalDirections& directions, std::size_t fine, std::size_t fitted,
                                  const std::vector<std::uint8_t>& free, std::vector<Vec3>& data,
                                  const NormalFitResult& result) {
  std::vector<Vec3> normals = directions(result.frame_base);
  if (normals.size() != fine)
    throw Error(ErrorKind::InvalidArgument, "the normal fit's directions must have one entry per fine vertex");
  for (std::size_t i = 0; i < fitted; ++i)
    if (!free[i]) data[i] = normals[i] * dot(normals[i], data[i]);
  return normals;
}

void check_inputs(const SubdivisionHierarchy& h, const std::vector<Vec3>& base, const Volume& field,
                  const NormalFitOptions& o) {
  if (base.size() < h.vertex_count(0))
    throw Error(ErrorKind::InvalidArgument, "the normal fit needs " + std::to_string(h.vertex_count(0)) +
                                                " base positions, got " + std::to_string(base.size()));
  for (std::size_t v = 0; v < h.vertex_count(0); ++v)
    if (!std::isfinite(base[v].x) || !std::isfinite(base[v].y) || !std::isfinite(base[v].z))
      throw Error(ErrorKind::InvalidArgument, "base position " + std::to_string(v) + " is not finite");
  if (field.dims[0] < 2 || field.dims[1] < 2 || field.dims[2] < 2)
    throw Error(ErrorKind::InvalidArgument, "the normal fit needs at least 2 samples along every axis");
  if (o.rounds < 1 || o.rounds > 50 || o.cg_iterations < 1 || o.cg_iterations > 500 || !(o.reach_edges > 0) ||
      !(o.min_reach_cells > 0) || !std::isfinite(o.reach_edges) || !std::isfinite(o.min_reach_cells))
    throw Error(ErrorKind::InvalidArgument, "a normal-fit option is out of its range");
}

}  // namespace

NormalFitResult normal_fit(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                           const Volume& field, double iso, const NormalDirections& directions,
                           const NormalFitOptions& options, ProgressSink& progress) {
  check_inputs(hierarchy, base_positions, field, options);
  progress.begin_stage("normal fit");
  const detail::FittedField fitted(field, iso);
  std::optional<BinnedSurfaceDistance> surface;
  if (options.surface) surface.emplace(*options.surface);
  const double facing = wrap::unfolded_sign(options.orientation);
  std::optional<CoveragePull> pull;
  if (options.surface && options.coverage_pull)
    pull.emplace(options.surface->positions, field, kCoveredCells * field.cell_size());
  const FitInputs in{hierarchy, field, fitted.grid(), iso, facing, surface ? &*surface : nullptr, options,
                     pull ? &*pull : nullptr};
  const int levels = hierarchy.levels();
  const std::size_t base_count = hierarchy.vertex_count(0), fine = hierarchy.fine_vertex_count();
  NormalFitResult result;
  std::vector<Vec3> data(fine);
  std::vector<std::uint8_t> free(fine, 0);
  std::fill(free.begin(), free.begin() + static_cast<std::ptrdiff_t>(base_count), std::uint8_t{1});
  int first_level = 1;
  if (options.start) {
    first_level = start_from(*options.start, hierarchy, data, free, result);
  } else {
    std::copy(base_positions.begin(), base_positions.begin() + static_cast<std::ptrdiff_t>(base_count), data.begin());
    result.frame_base.assign(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(base_count));
  }
  std::vector<Vec3> normals =
      take_directions(directions, fine, hierarchy.vertex_count(first_level - 1), free, data, result);
  for (int level = first_level; level <= levels; ++level) {
    // The frame base: the base as the first level's fit leaves it (the base
    // points are free to the finest level, but move little after it), so
    // that the coder's base refinement from it costs few bits.
    if (level == 2) {
      result.frame_base.assign(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(base_count));
      normals = take_directions(directions, fine, hierarchy.vertex_count(1), free, data, result);
    }
    result.levels.push_back(fit_level(in, level, normals, free, data));
    progress.update(double(level) / double(levels));
  }
  result.non_normal.assign(free.begin() + static_cast<std::ptrdiff_t>(base_count), free.end());
  result.positions = synthesize_points(hierarchy, levels, data);
  result.coefficients = std::move(data);
  progress.end_stage();
  return result;
}

}  // namespace isowave
