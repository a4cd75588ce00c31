#include "levels_by_error.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cstdint>

#include "isowave/pipeline/prepare.h"

namespace isowave {
namespace {

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

}  // namespace

FittedLevel fit_levels_by_error(const PolygonMesh& base, const LevelRule& rule, const SurfaceErrorReference& reference,
                                double cell_size, const std::function<FittedLevel(int levels)>& fit,
                                std::vector<LevelReport>& reports) {
  assert(rule.fixed_levels >= 0 && rule.fixed_levels <= 6);
  FittedLevel fitted;
  for (int levels = rule.fixed_levels > 0 ? rule.fixed_levels : 1;; ++levels) {
    const auto start = std::chrono::steady_clock::now();
    fitted = FittedLevel{};
    fitted = fit(levels);
    reports.push_back(report_level(levels, fitted, reference, cell_size));
    reports.back().seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (rule.fixed_levels > 0 || reports.back().d_cells() <= rule.max_error_cells || levels == 6 ||
        double(fine_vertex_count(base, levels + 1)) > rule.max_fine_vertices)
      return fitted;
  }
}

}  // namespace isowave
