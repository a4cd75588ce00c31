#pragma once
// Levels by error (issue #33, items 3 and 4), for both fits: the fit runs
// level after level until its fine mesh lies within a bound of the extracted
// isosurface (D, core/surface_error.h), and each level tried is reported.
#include <functional>
#include <memory>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/surface_error.h"
#include "isowave/core/vec3.h"
#include "isowave/pipeline/convert.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// Which levels fit_levels_by_error() tries.
struct LevelRule {
  int fixed_levels = 0;          // 1..6: that level alone; 0: by error
  double max_error_cells = 0;    // by error: the bound on D, cells (>= 0)
  double max_fine_vertices = 0;  // by error: never a level whose fine mesh has more vertices (but level 1)
};

// One level's fit, as the fit hands it to fit_levels_by_error().
struct FittedLevel {
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;  // the base refined to the level
  const std::vector<Vec3>* positions = nullptr;           // its fine control points, owned by the fit
  std::size_t folded_faces = 0;                           // fine faces folded against the field gradient
};

// Calls fit(L) for L = rule.fixed_levels, or by error for L = 1, 2, ...
// until the first whose D against `reference` is at most the bound (the
// smallest such L), L = 6, or the last before a fine mesh of more than
// rule.max_fine_vertices. Appends a LevelReport per level tried to `reports`
// and returns the last fit. A fit's previous level is released before it is
// called again. Cost per level: the fit, D (about linear in the fine faces
// plus the reference's samples) and a pass over the fine faces.
FittedLevel fit_levels_by_error(const PolygonMesh& base, const LevelRule& rule, const SurfaceErrorReference& reference,
                                double cell_size, const std::function<FittedLevel(int levels)>& fit,
                                std::vector<LevelReport>& reports);

}  // namespace isowave
