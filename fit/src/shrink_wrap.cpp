#include "isowave/fit/shrink_wrap.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/fit/trilinear.h"
#include "isowave/transform/wavelet_transform.h"
#include "coverage_pull.h"
#include "droplets.h"
#include "wrap_kernels.h"
#include "wrap_passes.h"

namespace isowave::wrap {
namespace {

// Throws Error(InvalidArgument) naming the first of positions[0 .. count)
// more than a cell outside the volume's box. A base from another volume
// (other spacing or origin) would be pressed onto the box and fitted to
// nothing; one from this volume's isosurface lies inside its box.
void require_inside_box(const std::vector<Vec3>& positions, std::size_t count, const Volume& field) {
  const Vec3 low = volume_box_min(field), high = volume_box_max(field);
  const double cell = field.cell_size();
  for (std::size_t v = 0; v < count; ++v) {
    const Vec3& p = positions[v];
    const double outside = norm(component_max(Vec3{}, component_max(low - p, p - high)));
    if (!(outside > cell)) continue;
    std::ostringstream message;
    message << "base vertex " << v << " at (" << p.x << ", " << p.y << ", " << p.z << ") lies " << outside / cell
            << " cells outside the volume's box (" << low.x << ", " << low.y << ", " << low.z << ") .. (" << high.x
            << ", " << high.y << ", " << high.z << "): is the base mesh from this volume (same spacing and origin)?";
    throw Error(ErrorKind::InvalidArgument, message.str());
  }
}

// Throws Error(InvalidArgument) naming the first vertex on a boundary edge
// of the base (level 0's `mesh`) more than a cell from every face of the
// volume's box. An extracted isosurface has boundaries only on those faces
// (NaN samples count as outside, so the surface closes around them), and
// simplification keeps its boundary vertices there; a base with a hole
// elsewhere would be fitted with the hole left open.
void require_boundary_on_box(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, const Volume& field) {
  const Vec3 low = volume_box_min(field), high = volume_box_max(field);
  const double cell = field.cell_size();
  for (std::size_t v = 0; v < mesh.vertex_count; ++v) {
    if (mesh.boundary_neighbours[2 * v] == WrapLevelMesh::kNone) continue;
    const Vec3& p = positions[v];
    double to_box = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) to_box = std::min({to_box, std::abs(p[a] - low[a]), std::abs(high[a] - p[a])});
    if (to_box <= cell) continue;
    std::ostringstream message;
    message << "base vertex " << v << " at (" << p.x << ", " << p.y << ", " << p.z << ") lies on a boundary of the base"
            << " mesh " << to_box / cell << " cells from the volume's box, where an isosurface extracted from this"
            << " volume has none: is the base mesh from this volume, and closed where its isosurface is?";
    throw Error(ErrorKind::InvalidArgument, message.str());
  }
}

// Throws Error(InvalidArgument) when most base vertices have a normal (the
// sum of their faces' area vectors) pointing against the field's
// orientation (toward higher values, or lower ones with flip): a base
// extracted with the other --flip, on which the fit folds nearly every face
// (a sphere: nearly every fine face folded). Bases of the same field
// disagree at far fewer vertices.
void require_oriented_as_the_field(const PolygonMesh& base, const std::vector<Vec3>& positions, const Volume& field,
                                   Orientation orientation) {
  std::vector<Vec3> normals(base.vertex_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t* face = base.face_begin(f);
    const std::uint32_t size = base.face_size(f);
    const Vec3 newell = newell_vector(face, size, positions);
    for (std::uint32_t k = 0; k < size; ++k) normals[face[k]] += newell;
  }
  const TrilinearGrid grid(field);
  const double expected_sign = unfolded_sign(orientation);
  std::size_t counted = 0, against = 0;
  for (std::size_t v = 0; v < base.vertex_count(); ++v) {
    const double agreement = expected_sign * dot(normals[v], grid.sample(positions[v]).gradient);
    if (!(agreement != 0)) continue;  // no normal, no gradient, or NaN
    ++counted;
    against += agreement < 0 ? 1 : 0;
  }
  if (2 * against > counted)
    throw Error(ErrorKind::InvalidArgument,
                "the base mesh faces the other way: at " + std::to_string(against) + " of " + std::to_string(counted) +
                    " vertices its normals point toward " + (orientation == Orientation::TowardHigher ? "lower" : "higher") +
                    " field values (was it extracted with the other --flip?)");
}

// Mean length of the level's edges (each counted from both ends), world
// units; from the edges of every stride-th vertex, so that at most about
// 2^18 vertices are read.
double mean_edge_length(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions) {
  struct Sum {
    double length = 0;
    std::size_t count = 0;
  };
  const std::size_t stride = std::max<std::size_t>(1, mesh.vertex_count >> 18);
  const std::size_t sampled = (mesh.vertex_count + stride - 1) / stride;
  Sum total;
  for (const Sum& part : for_blocks<Sum>(sampled, [&](std::size_t first, std::size_t last, Sum& sum) {
         for (std::size_t i = first; i < last; ++i) {
           const std::size_t v = i * stride;
           for (std::uint32_t k = mesh.neighbour_offsets[v]; k < mesh.neighbour_offsets[v + 1]; ++k)
             sum.length += norm(positions[mesh.neighbours[k]] - positions[v]);
           sum.count += mesh.neighbour_offsets[v + 1] - mesh.neighbour_offsets[v];
         }
       })) {
    total.length += part.length;
    total.count += part.count;
  }
  return total.count ? total.length / double(total.count) : 0.0;
}

// Throws Error(InvalidArgument) for inputs shrink_wrap() cannot fit (see its
// contract); the base's boundary is checked later, with level 0's connectivity.
void require_valid_inputs(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                          const SignedDistanceField& distance, const Volume& field) {
  const std::size_t base_count = hierarchy.vertex_count(0);
  if (base_positions.size() < base_count)
    throw Error(ErrorKind::InvalidArgument, "shrink-wrap needs " + std::to_string(base_count) +
                                                " base positions, got " + std::to_string(base_positions.size()));
  for (std::size_t v = 0; v < base_count; ++v)
    if (!is_finite(base_positions[v]))
      throw Error(ErrorKind::InvalidArgument, "base vertex " + std::to_string(v) + " has a non-finite position");
  if (distance.distance.dims != field.dims || !(distance.distance.spacing == field.spacing) ||
      !(distance.distance.origin == field.origin) || distance.distance.values.size() != field.sample_count())
    throw Error(ErrorKind::InvalidArgument, "the signed-distance field and the scalar field have different grids");
  if (field.dims[0] < 2 || field.dims[1] < 2 || field.dims[2] < 2)
    throw Error(ErrorKind::InvalidArgument, "shrink-wrap needs at least 2 samples along each axis");
  require_inside_box(base_positions, base_count, field);
  require_oriented_as_the_field(hierarchy.base(), base_positions, field, orientation_from_flip(distance.flip));
}

// Throws Error(InvalidArgument) for an option out of its range.
void require_valid_options(const ShrinkWrapOptions& options) {
  if (options.iterations < 0 || options.iterations > 100 || options.final_level_iterations < 0 ||
      options.final_level_iterations > 100)
    throw Error(ErrorKind::InvalidArgument, "shrink-wrap iterations must be in 0..100");
  if (options.untangle_rounds < 0 || options.untangle_rounds > 100 || options.coarse_untangle_rounds < 0 ||
      options.coarse_untangle_rounds > 100)
    throw Error(ErrorKind::InvalidArgument, "untangle rounds must be in 0..100");
  if (options.unfold_rounds < 0 || options.unfold_rounds > 100 || !(options.unfold_max_folded_fraction >= 0) ||
      !(options.unfold_max_folded_fraction <= 1))
    throw Error(ErrorKind::InvalidArgument, "unfold rounds must be in 0..100 and its folded limit in [0, 1]");
  if (!(options.relaxation_weight > 0 && options.relaxation_weight <= 1))
    throw Error(ErrorKind::InvalidArgument, "relaxation weight must be in (0, 1]");
  if (!(options.attraction.reach_edges > 0) || !(options.attraction.min_reach_cells >= 0) ||
      !std::isfinite(options.attraction.reach_edges) || !std::isfinite(options.attraction.min_reach_cells))
    throw Error(ErrorKind::InvalidArgument, "attraction reach must be positive and finite");
  if (!(options.pull_covered_cells > 0) || !(options.pull_reach_cells >= options.pull_covered_cells) ||
      !std::isfinite(options.pull_reach_cells) || !(options.final_pull_reach_cells >= options.pull_covered_cells) ||
      !std::isfinite(options.final_pull_reach_cells) || !(options.pull_max_edge_cells >= 0) ||
      !std::isfinite(options.pull_max_edge_cells))
    throw Error(ErrorKind::InvalidArgument, "coverage pull: need 0 < covered <= reach, finite, and edge limit >= 0");
  if (!(options.correction_max_cells > 0) || !std::isfinite(options.correction_max_cells))
    throw Error(ErrorKind::InvalidArgument, "correction distance must be positive and finite");
  if (!(options.droplet_cells >= 0) || !std::isfinite(options.droplet_cells))
    throw Error(ErrorKind::InvalidArgument, "droplet size must be non-negative and finite");
}

// The scalar field as every search along it sees it: without the closed
// components extraction dropped and with its non-finite samples filled (see
// mirror_enclosed_samples, fill_non_finite_samples); on huge pages, as the
// searches sample it at scattered places.
HugePageVector<float> prepared_field_values(const Volume& field, const SignedDistanceField& distance) {
  HugePageVector<float> values;
  reserve_fresh_on_huge_pages(values, field.values.size());
  values.resize(field.values.size());
  mirror_enclosed_samples(field, distance, values.data());  // as many as the distance field flipped
  fill_non_finite_samples(field, distance.iso, values.data());
  return values;
}

// Everything the passes share: the inputs, the prepared fields, the buffers
// (sized for the finest level once, on huge pages, and reused by the
// coarser levels) and the result, whose positions are the current level's.
struct FitContext {
  FitContext(const SubdivisionHierarchy& hierarchy_, const std::vector<Vec3>& base_positions,
             const SignedDistanceField& distance_, const Volume& field_, const ShrinkWrapOptions& options_)
      : hierarchy(hierarchy_),
        distance(distance_),
        field(field_),
        options(options_),
        levels(hierarchy_.levels()),
        orientation(orientation_from_flip(distance_.flip)),
        iso(distance_.iso),
        box(field_),
        cell(field_.cell_size()) {
    const std::size_t fine_count = hierarchy.vertex_count(levels);
    reserve_on_huge_pages(positions, fine_count);
    reserve_on_huge_pages(scratch, fine_count);
    const std::size_t base_count = hierarchy.vertex_count(0);
    positions.assign(base_positions.begin(), base_positions.begin() + static_cast<std::ptrdiff_t>(base_count));
    reserve_on_huge_pages(face_normals, levels > 0 ? std::size_t{hierarchy.step(levels).face_offsets.back()} : 0);
    reserve_finest_wrap_level_mesh(hierarchy, mesh);
    field_values = prepared_field_values(field, distance);
    scalar_grid.emplace(field, field_values.data());
    if (options.coverage_pull && options.surface && !options.surface->positions.empty())
      pull = std::make_unique<CoveragePull>(options.surface->positions, field, options.pull_covered_cells * cell);
  }
  FitContext(const FitContext&) = delete;
  FitContext& operator=(const FitContext&) = delete;

  const SubdivisionHierarchy& hierarchy;
  const SignedDistanceField& distance;
  const Volume& field;
  const ShrinkWrapOptions& options;
  const int levels;  // L
  const Orientation orientation;
  const double iso;
  const Box box;
  const double cell;  // world units
  ShrinkWrapResult result;
  std::vector<Vec3>& positions = result.positions;  // the current level's control points
  std::vector<Vec3> scratch;                        // the second position buffer
  FaceNormals face_normals;
  WrapLevelMesh mesh;  // the current level's
  Droplets droplets;
  std::vector<std::uint8_t> tangent_only;  // per vertex: a droplet's (levels < L)
  HugePageVector<float> field_values;      // prepared_field_values()
  std::optional<TrilinearGrid> scalar_grid;  // over field_values
  const TrilinearGrid distance_grid{distance.distance};
  std::unique_ptr<CoveragePull> pull;  // with options.surface and coverage_pull
};

// What a level does, decided after its setup.
struct LevelPlan {
  int rounds = 0;           // relaxation + attraction
  bool tangential = false;  // droplets relax within their tangent planes
  bool pulls = false;       // the coverage pull runs on this level
  bool pull_last = false;   // on level L after the correction and untangle(), whose smoothing
                            // would otherwise take back part of what it covered
};

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Refines the positions to `level`, builds its connectivity, holds its
// boundary on the box and finds the level's droplets.
void set_up_level(FitContext& fit, int level, WrapLevelStatistics& stats) {
  WrapLevelMesh& mesh = fit.mesh;
  if (level > 0) subdivide_level(fit.hierarchy, level, fit.positions);
  fill_wrap_level_mesh(fit.hierarchy, level, fit.positions, fit.field, fit.iso, mesh);
  if (level == 0) require_boundary_on_box(mesh, fit.positions, fit.field);
  constrain_to_box(mesh, fit.field, fit.positions);
  stats.level = level;
  stats.vertices = mesh.vertex_count;
  struct RoleCounts {
    std::size_t boundary = 0, fixed = 0;
  };
  for (const RoleCounts& counts :
       for_blocks<RoleCounts>(mesh.vertex_count, [&](std::size_t first, std::size_t last, RoleCounts& counts) {
         for (std::size_t v = first; v < last; ++v) {
           counts.boundary += mesh.box_face[v] >= 0 ? 1 : 0;
           counts.fixed += mesh.role[v] == WrapRole::Fixed ? 1 : 0;
         }
       })) {
    stats.boundary_vertices += counts.boundary;
    stats.fixed_vertices += counts.fixed;
  }
  if (fit.options.droplet_vertices > 0) {
    if (level == 0)
      fit.droplets = find_droplets(fit.hierarchy, mesh, fit.positions, fit.options.droplet_vertices,
                                   fit.options.droplet_cells * fit.cell, fit.orientation);
    if (!fit.droplets.empty()) fit.droplets.set_level(fit.hierarchy, level, mesh);
  }
}

LevelPlan plan_level(FitContext& fit, int level, WrapLevelStatistics& stats) {
  LevelPlan plan;
  plan.rounds = level < fit.levels ? fit.options.iterations : fit.options.final_level_iterations;
  plan.tangential = !fit.droplets.empty() && level < fit.levels;
  if (plan.tangential) {
    fit.tangent_only.assign(fit.mesh.vertex_count, 0);
    for (const std::vector<std::uint32_t>& list : fit.droplets.vertices)
      for (const std::uint32_t v : list) fit.tangent_only[v] = 1;
  }
  if (fit.pull) stats.mean_edge_cells = mean_edge_length(fit.mesh, fit.positions) / fit.cell;
  plan.pulls = fit.pull && stats.mean_edge_cells <= fit.options.pull_max_edge_cells;
  plan.pull_last = plan.pulls && level == fit.levels && fit.options.final_correction;
  return plan;
}

// The pull below level L, on the attracted points of the level's last round
// (measured on relaxed or merely subdivided points, it took the surface
// those had shrunk away from for left out); the next attraction puts the
// pulled points back on the isosurface.
void pull_toward_uncovered(FitContext& fit, WrapLevelStatistics& stats) {
  const auto phase = Clock::now();
  const CoveragePullStatistics pulled = fit.pull->apply(fit.mesh, fit.positions, fit.options.pull_reach_cells * fit.cell);
  stats.uncovered_samples = pulled.uncovered_samples;
  stats.pulled_vertices = pulled.pulled_vertices;
  stats.seconds_pull += seconds_since(phase);
}

// The paper's rounds (Sec. 4.2): relaxation, then attraction; droplets
// along rays from their centroid.
void relax_and_attract(FitContext& fit, const LevelPlan& plan, WrapLevelStatistics& stats) {
  fit.scratch.resize(fit.mesh.vertex_count);
  for (int round = 0; round < plan.rounds; ++round) {
    auto phase = Clock::now();
    relax_with(fit.mesh, fit.field, fit.options.relaxation_weight, fit.positions, fit.scratch,
               plan.tangential ? fit.tangent_only.data() : nullptr);
    stats.seconds_relaxation += seconds_since(phase);
    phase = Clock::now();
    stats.last_attraction =
        attract_with(fit.mesh, fit.distance, fit.options.attraction, fit.scratch, fit.positions, fit.face_normals);
    if (!fit.droplets.empty())
      fit_droplets(fit.mesh, fit.droplets, *fit.scalar_grid, fit.box, fit.cell, fit.iso, fit.scratch, fit.positions);
    stats.seconds_attraction += seconds_since(phase);
    if (plan.pulls && !plan.pull_last && round + 1 == plan.rounds) pull_toward_uncovered(fit, stats);
  }
}

// Level L onto the isosurface of the scalar field (correction.h); the
// droplets along rays from their centroid instead.
void correct_onto_isosurface(FitContext& fit, WrapLevelStatistics& stats) {
  const auto phase = Clock::now();
  for (const std::vector<std::uint32_t>& list : fit.droplets.vertices)
    for (const std::uint32_t v : list) fit.scratch[v] = fit.positions[v];
  fit.result.correction =
      correct_with(fit.mesh, *fit.scalar_grid, fit.box, fit.cell, fit.iso, fit.options.correction_max_cells,
                   fit.positions, fit.options.correction_from_nearest_point ? &fit.distance_grid : nullptr,
                   unfolded_sign(fit.orientation), fit.options.surface, &fit.distance_grid);
  if (!fit.droplets.empty())
    fit_droplets(fit.mesh, fit.droplets, *fit.scalar_grid, fit.box, fit.cell, fit.iso, fit.scratch, fit.positions);
  stats.seconds_correction = seconds_since(phase);
}

// The pull on level L, last but for the unfold; the pulled points are
// corrected onto the isosurface or go back.
void pull_and_settle(FitContext& fit, WrapLevelStatistics& stats) {
  const auto phase = Clock::now();
  std::vector<PulledPoint> pulled_points;
  const CoveragePullStatistics pulled =
      fit.pull->apply(fit.mesh, fit.positions, fit.options.final_pull_reach_cells * fit.cell, &pulled_points);
  stats.uncovered_samples = pulled.uncovered_samples;
  stats.pulled_vertices = pulled.pulled_vertices;
  stats.pulled_back = settle_pulled_points(fit.mesh, *fit.scalar_grid, fit.box, fit.cell, fit.iso, fit.orientation,
                                           fit.options.correction_max_cells,
                                           fit.options.correction_from_nearest_point ? &fit.distance_grid : nullptr,
                                           pulled_points, fit.positions);
  stats.seconds_pull += seconds_since(phase);
}

// The unfold on level L, unless more than unfold_max_folded_fraction of the
// faces fold: judged by untangle()'s count when it ran (the pull changes few
// faces), else by a count here.
void unfold_unless_too_folded(FitContext& fit, WrapLevelStatistics& stats) {
  ShrinkWrapResult& result = fit.result;
  if (fit.options.untangle_rounds > 0) {
    result.folded_faces = result.untangle.folded_after;
  } else {
    HugePageVector<std::uint8_t> folded;
    result.folded_faces = find_folded_faces(fit.mesh, *fit.scalar_grid, fit.orientation, fit.positions, folded);
  }
  const bool too_folded =
      double(result.folded_faces) > fit.options.unfold_max_folded_fraction * double(fit.mesh.face_count());
  if (fit.options.unfold_rounds > 0 && too_folded) {
    result.unfold.folded_before = result.unfold.folded_after = result.folded_faces;
    result.unfold.skipped = true;
  } else if (fit.options.unfold_rounds > 0) {
    const auto phase = Clock::now();
    result.unfold = unfold_with(fit.mesh, *fit.scalar_grid, fit.box, fit.cell, fit.iso, fit.orientation,
                                fit.options.unfold_rounds, fit.options.correction_max_cells, fit.positions);
    result.folded_faces = result.unfold.folded_after;
    stats.seconds_unfold = seconds_since(phase);
  }
}

// Level L after its rounds: the correction, untangle(), the pull, the unfold.
void finish_finest_level(FitContext& fit, const LevelPlan& plan, WrapLevelStatistics& stats) {
  if (fit.options.final_correction) correct_onto_isosurface(fit, stats);
  if (fit.options.untangle_rounds > 0) {
    const auto phase = Clock::now();
    fit.result.untangle = untangle_with(fit.mesh, *fit.scalar_grid, fit.box, fit.cell, fit.iso, fit.orientation,
                                        fit.options.untangle_rounds, fit.options.correction_max_cells, fit.positions,
                                        fit.scratch);
    stats.seconds_untangle = seconds_since(phase);
  }
  if (plan.pull_last) pull_and_settle(fit, stats);
  unfold_unless_too_folded(fit, stats);
}

// Folds on a coarser level, against the distance field, whose gradient the
// vertex normals agree with (hence TowardHigher, iso 0): half the folds left
// on level L are inherited from coarse faces folded over thin sheets and
// filaments, and a subdivided fold is not repaired on level L.
void untangle_coarse_level(FitContext& fit, WrapLevelStatistics& stats) {
  const auto phase = Clock::now();
  untangle_with(fit.mesh, fit.distance_grid, fit.box, fit.cell, 0.0, Orientation::TowardHigher,
                fit.options.coarse_untangle_rounds, fit.options.correction_max_cells, fit.positions, fit.scratch);
  stats.seconds_untangle = seconds_since(phase);
}

}  // namespace
}  // namespace isowave::wrap

namespace isowave {

ShrinkWrapResult shrink_wrap(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                             const SignedDistanceField& distance, const Volume& field,
                             const ShrinkWrapOptions& options, ProgressSink& progress) {
  using namespace wrap;
  require_valid_inputs(hierarchy, base_positions, distance, field);
  require_valid_options(options);
  progress.begin_stage("shrink-wrap");
  FitContext fit(hierarchy, base_positions, distance, field, options);
  double work_done = 0, work_total = 0;
  for (int level = 0; level <= fit.levels; ++level) work_total += double(hierarchy.vertex_count(level));
  for (int level = 0; level <= fit.levels; ++level) {
    const auto start = Clock::now();
    WrapLevelStatistics stats;
    set_up_level(fit, level, stats);
    stats.seconds_setup = seconds_since(start);
    const LevelPlan plan = plan_level(fit, level, stats);
    relax_and_attract(fit, plan, stats);
    if (level == fit.levels && (options.final_correction || options.untangle_rounds > 0))
      finish_finest_level(fit, plan, stats);
    if (level < fit.levels && options.coarse_untangle_rounds > 0) untangle_coarse_level(fit, stats);
    if (options.keep_levels && level < fit.levels)
      fit.result.level_positions.emplace_back(fit.positions.begin(),
                                              fit.positions.begin() + static_cast<std::ptrdiff_t>(fit.mesh.vertex_count));
    stats.seconds = seconds_since(start);
    fit.result.levels.push_back(stats);
    work_done += double(fit.mesh.vertex_count);
    progress.update(work_done / work_total);
  }
  fit.positions.resize(hierarchy.vertex_count(fit.levels));
  progress.end_stage();
  return std::move(fit.result);
}

}  // namespace isowave
