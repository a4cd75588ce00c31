#include "isowave/fit/surface_fit.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "isowave/core/memory_check.h"
#include "isowave/fit/correction.h"
#include "isowave/fit/fold_repair.h"
#include "isowave/fit/wrap_level_mesh.h"

namespace isowave {

namespace {

// One level's fit, as a method hands it to fit_levels().
struct FittedLevel {
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;  // the base refined to the level
  const std::vector<Vec3>* positions = nullptr;           // its fine control points, owned by the method
  std::size_t folded_faces = 0;                           // fine faces folded against the field gradient
};

// Areas of the faces of `mesh` (vector areas: polygons are not fanned)
// divided by their mean: min, median, max in report.stretch_*; zeros
// when the mean is 0. O(faces).
void measure_stretch(const PolygonMesh& mesh, LevelReport& report) {
  std::vector<double> areas(mesh.face_count());
  double sum = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* v = mesh.face_begin(f);
    const std::uint32_t n = mesh.face_size(f);
    Vec3 area;
    for (std::uint32_t k = 0; k < n; ++k) area += cross(mesh.positions[v[k]], mesh.positions[v[(k + 1) % n]]);
    areas[f] = 0.5 * norm(area);
    sum += areas[f];
  }
  const double mean = areas.empty() ? 0.0 : sum / double(areas.size());
  if (!(mean > 0)) return;
  const auto middle = areas.begin() + static_cast<std::ptrdiff_t>(areas.size() / 2);
  std::nth_element(areas.begin(), middle, areas.end());
  report.stretch_median = *middle / mean;
  report.stretch_min = *std::min_element(areas.begin(), areas.end()) / mean;
  report.stretch_max = *std::max_element(areas.begin(), areas.end()) / mean;
}

// D both ways, the folded share and the stretch of one fitted level.
LevelReport report_level(int levels, const FittedLevel& fitted, const SurfaceErrorReference& reference,
                         double cell_size) {
  const PolygonMesh fine = fitted.hierarchy->control_mesh(levels, *fitted.positions);
  LevelReport report;
  report.levels = levels;
  report.fine_vertices = fine.vertex_count();
  const SurfaceError error = reference.measure(fine);
  report.forward_rms_cells = error.forward_rms / cell_size;
  report.backward_rms_cells = error.backward_rms / cell_size;
  report.folded_share = fine.face_count() ? double(fitted.folded_faces) / double(fine.face_count()) : 0.0;
  measure_stretch(fine, report);
  return report;
}

// Calls fit(L) for the levels of `rule` (surface_fit.h), reports each level
// tried into out.level_reports and takes the last one's counts into `out`.
template <typename LevelFit>
FittedLevel fit_levels(const PolygonMesh& base, const SurfaceFitInput& input, const LevelRule& rule,
                       const LevelFit& fit, SurfaceFit& out) {
  assert(rule.fixed_levels >= 0 && rule.fixed_levels <= 6);
  FittedLevel fitted;
  for (int levels = rule.fixed_levels > 0 ? rule.fixed_levels : 1;; ++levels) {
    const auto start = std::chrono::steady_clock::now();
    fitted = FittedLevel{};
    check_memory(double(fine_vertex_count(base, levels)), kFitBytesPerFineVertex,
                 std::to_string(levels) + " levels of a " + std::to_string(base.vertex_count()) + "-vertex base mesh");
    fitted = fit(levels);
    out.level_reports.push_back(report_level(levels, fitted, *input.reference, input.cell_size));
    out.level_reports.back().seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (rule.fixed_levels > 0 || out.level_reports.back().d_cells() <= rule.max_error_cells || levels == 6 ||
        double(fine_vertex_count(base, levels + 1)) > rule.max_fine_vertices)
      break;
  }
  out.hierarchy = fitted.hierarchy;
  out.levels = fitted.hierarchy->levels();
  out.fine_vertices = fitted.hierarchy->fine_vertex_count();
  // Each parent face of n corners gives n quads.
  out.fine_faces = fitted.hierarchy->step(out.levels).face_vertices.size();
  return fitted;
}

// FinePoints::OnTrilinearIsosurface: the fitted points move along the field
// gradient onto the trilinear isosurface; a point the correction took
// farther than kFinePointMoveCells (its fallbacks: a neighbours' centroid, a
// wide search) goes back onto the extracted surface, where it was, and so
// does every corner of a face the moves fold (take_back_folding_moves). Then
// the corners of the faces still folded move to unfold them (unfold()).
void move_onto_isosurface(const WrapLevelMesh& level, const SurfaceFitInput& input, SurfaceFit& out) {
  std::vector<Vec3>& positions = out.points.positions;
  const std::vector<Vec3> on_surface = positions;
  out.points.correction = correct_to_isosurface(level, *input.field, input.iso, kFinePointMoveCells, positions);
  const double reach = kFinePointMoveCells * input.cell_size;
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!(squared_norm(positions[v] - on_surface[v]) <= reach * reach)) positions[v] = on_surface[v];
  take_back_folding_moves(level, *input.field, input.orientation, on_surface, positions);
  out.points.unfold =
      unfold(level, *input.field, input.iso, input.orientation, kFineUnfoldRounds, kFinePointMoveCells, positions);
  out.points.folded_faces = out.points.unfold.folded_after;
}

// The parametrization-based fit (parametrized_fit.h) of `base`; its points
// then move onto the trilinear isosurface (FinePoints).
void fit_parametrized(const PolygonMesh& base, const SurfaceFitInput& input, const SurfaceFitOptions& options,
                      SurfaceFit& out, ProgressSink& progress) {
  assert(input.map);
  // One connectivity of level L for the fold counts and the correction.
  std::optional<WrapLevelMesh> level;
  const auto fit_level = [&](int levels) {
    level.reset();
    out.points = ShrinkWrapResult{};
    auto hierarchy = std::make_shared<const SubdivisionHierarchy>(base, levels);
    ParametrizedFitResult fit = parametrized_fit(*hierarchy, base.positions, *input.isosurface, *input.map, progress);
    out.points.positions = std::move(fit.positions);
    out.parametrization = fit.statistics;
    level.emplace(make_wrap_level_mesh(*hierarchy, levels, out.points.positions, *input.field, input.iso));
    out.points.folded_faces = count_folded_faces(*level, out.points.positions, *input.field, input.orientation);
    return FittedLevel{std::move(hierarchy), &out.points.positions, out.points.folded_faces};
  };
  fit_levels(base, input, options.levels, fit_level, out);
  if (options.fine_points == FinePoints::OnTrilinearIsosurface) move_onto_isosurface(*level, input, out);
}

// The shrink-wrap (Sec. 4.2; shrink_wrap.h) of `base`.
void fit_shrink_wrap(const PolygonMesh& base, const SurfaceFitInput& input, const SurfaceFitOptions& options,
                     SurfaceFit& out, ProgressSink& progress) {
  assert(input.distance);
  ShrinkWrapOptions wrap = options.shrink_wrap;
  wrap.surface = input.isosurface;
  const auto fit_level = [&](int levels) {
    out.points = ShrinkWrapResult{};
    auto hierarchy = std::make_shared<const SubdivisionHierarchy>(base, levels);
    out.points = shrink_wrap(*hierarchy, base.positions, *input.distance, *input.field, wrap, progress);
    return FittedLevel{std::move(hierarchy), &out.points.positions, out.points.folded_faces};
  };
  fit_levels(base, input, options.levels, fit_level, out);
}

// The normal fit (normal_fit.h) of `base`, its coefficients along the
// input's directions; each level tried continues the previous one's entries.
void fit_normal(const PolygonMesh& base, const SurfaceFitInput& input, const SurfaceFitOptions& options,
                SurfaceFit& out, ProgressSink& progress) {
  assert(input.directions);
  NormalFitOptions normal = options.normal;
  normal.surface = input.isosurface;
  normal.orientation = input.orientation;
  normal.coverage_pull = options.shrink_wrap.coverage_pull;
  NormalFitResult previous;
  const auto fit_level = [&](int levels) {
    out.points = ShrinkWrapResult{};
    auto hierarchy = std::make_shared<const SubdivisionHierarchy>(base, levels);
    normal.start = previous.levels.empty() ? nullptr : &previous;
    previous = normal_fit(*hierarchy, base.positions, *input.field, input.iso, input.directions(*hierarchy), normal,
                          progress);
    out.points.positions = std::move(previous.positions);
    out.normal_levels = previous.levels;
    out.non_normal_coefficients = previous.non_normal_count();
    out.frame_base = previous.frame_base;
    const WrapLevelMesh level = make_wrap_level_mesh(*hierarchy, levels, out.points.positions, *input.field, input.iso);
    out.points.folded_faces = count_folded_faces(level, out.points.positions, *input.field, input.orientation);
    return FittedLevel{std::move(hierarchy), &out.points.positions, out.points.folded_faces};
  };
  fit_levels(base, input, options.levels, fit_level, out);
}

// The fitted fine control points against the isosurface (first order), and
// the share of the isosurface no fine point comes near.
void check_fit(const SurfaceFitInput& input, SurfaceFit& out) {
  out.isosurface = isosurface_distance(out.points.positions, out.fine_vertices, *input.field, input.iso, 1.0);
  const PolygonMesh& surface = *input.isosurface;
  const std::size_t stride = std::max<std::size_t>(1, surface.vertex_count() / 100000);
  out.uncovered_share = share_farther_than(surface.positions, stride, out.points.positions, out.fine_vertices,
                                           kUncoveredCells * input.cell_size);
}

}  // namespace

SurfaceFit fit_surface(const PolygonMesh& base, const SurfaceFitInput& input, const SurfaceFitOptions& options,
                       ProgressSink& progress) {
  assert(input.field && input.isosurface && input.reference && input.cell_size > 0);
  SurfaceFit out;
  switch (options.method) {
    case FitMethod::ShrinkWrap: fit_shrink_wrap(base, input, options, out, progress); break;
    case FitMethod::Parametrization: fit_parametrized(base, input, options, out, progress); break;
    case FitMethod::Normal: fit_normal(base, input, options, out, progress); break;
  }
  check_fit(input, out);
  return out;
}

}  // namespace isowave
