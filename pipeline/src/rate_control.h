#pragma once
// Private: convert's rate control over the embedded .isw 2.0 stream (issue
// #34): D (surface_error.h) of the decoded surface against the extracted
// isosurface at the last plane boundaries of the whole stream, which becomes
// the file's RDTB, and the cut a target asks for.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/core/mesh.h"
#include "isowave/core/surface_error.h"
#include "isowave/pipeline/convert.h"
#include "isowave/transform/hierarchy.h"

namespace isowave::detail {

// D of fine control point arrays, one at a time, over one fine control mesh
// whose faces are built once (only the positions change between arrays):
// convert's one meter for the rate table and the summary rows.
class FineSurfaceMeter {
 public:
  FineSurfaceMeter(const SubdivisionHierarchy& hierarchy, const SurfaceErrorReference& against_surface)
      : hierarchy_(hierarchy), against_surface_(against_surface) {}
  // D (world units) of the fine control mesh at `positions` (one per fine
  // control point), which are moved in and handed back unchanged.
  double d(std::vector<Vec3>& positions);

 private:
  const SubdivisionHierarchy& hierarchy_;
  const SurfaceErrorReference& against_surface_;
  PolygonMesh mesh_;
};

struct RatePlan {
  std::uint64_t stream_bytes = UINT64_MAX;  // where the plane stream is cut (UINT64_MAX: whole)
  std::vector<IswRatePoint> table;          // D (world units) at the plane boundaries up to the cut, and at the cut
  double error = 0;                         // D at the cut, world units
  bool target_missed = false;               // max_error_cells: even the whole stream lies farther
  std::vector<Vec3> surface;                // the fine control points the cut decodes to (synthesized)
};

// The plane boundaries measured for the table: the last ones, each halving
// the step (the coarser planes hold few bytes and lie far off).
constexpr std::size_t kRateTablePlanes = 4;

// `file` holds the whole stream, `planes` what its plane ends decode to
// (encode_isw with IswPlaneValues). Targets in RateTarget;
// `extracted_vertices` converts bits per vertex to bytes. Errors:
// Error(InvalidArgument) for a size the headers alone exceed. Cost: a
// synthesis and D per table row, one row at a time, and for a cut between
// plane ends a decode more (up to eight for max_error_cells: a bisection
// inside the plane that reaches it).
RatePlan plan_rate(const std::string& file, const IswPlaneValues& planes,
                   const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, FineSurfaceMeter& meter,
                   const RateTarget& target, std::size_t extracted_vertices, double cell_size);

// The target's size limit in bytes (0: none).
std::uint64_t byte_limit(const RateTarget& target, std::size_t extracted_vertices);

// Moves a plan's cut back to `stream_bytes` (below its cut), measuring D
// there by a decode: the cut's table row (the last) and surface move with it.
void move_cut(RatePlan& plan, std::uint64_t stream_bytes, const std::string& file,
              const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, FineSurfaceMeter& meter);

}  // namespace isowave::detail
