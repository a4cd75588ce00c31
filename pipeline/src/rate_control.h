#pragma once
// Private: convert's rate control over the embedded .isw 2.0 stream (issue
// #34, #47 item 3): D (surface_error.h) of the decoded surface against the
// extracted isosurface at every prefix the stream's structure marks (the
// base mesh alone, each plane end), which becomes the file's RDTB, and the
// cut a target asks for.
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

// Samples each way of the estimated rows of the rate table.
constexpr std::size_t kRateEstimateSamples = 5000;

// D of fine control point arrays, one at a time, over one fine control mesh
// whose faces are built once (only the positions change between arrays):
// convert's one meter for the rate table and the summary rows.
//
// exact(): D as surface_error.h defines it, with every sample of
// `against_surface`. estimate(): the same two directions from
// kRateEstimateSamples samples each way that every array shares, about a
// quarter of the time: backward, the first of the reference's samples
// (SurfaceErrorReference::with_first_samples); forward, fixed locations
// (fan triangle, barycentric coordinates) drawn area-uniformly on the mesh
// given to fix_estimate_samples(), each weighted by its triangle's area in
// the measured array over its area there (importance sampling of the
// measured mesh's area).
class FineSurfaceMeter {
 public:
  FineSurfaceMeter(const SubdivisionHierarchy& hierarchy, const SurfaceErrorReference& against_surface);
  // D's two directions (world units) of the fine control mesh at
  // `positions` (one per fine control point), which are moved in and handed
  // back unchanged.
  SurfaceError exact(std::vector<Vec3>& positions);
  double d(std::vector<Vec3>& positions) { return exact(positions).d(); }
  // Draws the estimate's forward locations on the mesh at `positions`
  // (handed back unchanged). Error(InvalidArgument) for a mesh without area.
  void fix_estimate_samples(std::vector<Vec3>& positions);
  // Precondition: fix_estimate_samples() was called.
  SurfaceError estimate(std::vector<Vec3>& positions);

 private:
  struct Location {
    std::uint32_t face = 0, corner = 0;  // fan triangle (face corners 0, corner, corner + 1)
    double s = 0, v = 0;                 // 1 - s, s (1 - v), s v at its corners
    double area = 0;                     // of the triangle where the locations were drawn
  };
  double forward_estimate() const;  // RMS over the locations on mesh_

  const SubdivisionHierarchy& hierarchy_;
  const SurfaceErrorReference& against_surface_;
  SurfaceErrorReference estimate_;
  std::vector<Location> locations_;
  PolygonMesh mesh_;
};

// An estimated row's D from the estimates and the exact measure of the last
// row (the whole stream): per direction, the estimate's mean square plus
// what the exact measure differs by at the last row,
// sqrt(max(0, estimate² + last_exact² - last_estimate²)), the larger of the
// two. Every estimate shares its samples, so where a row's surface differs
// little from the last row's, as the fine planes' do, the correction removes
// most of the estimate's sampling error (a control variate); accuracy
// against the exact D in docs/MEASUREMENTS.md.
double corrected_d(const SurfaceError& estimate, const SurfaceError& last_estimate, const SurfaceError& last_exact);

struct RatePlan {
  std::uint64_t stream_bytes = UINT64_MAX;  // where the plane stream is cut (UINT64_MAX: whole)
  // D (world units): at 0 stream bytes (the frame base BPTS sends, every
  // coefficient zero) and at every plane end up to the cut, estimated
  // (corrected_d); at the cut (or the whole stream's end), exact. Strictly
  // ascending in bytes (plane ends that coincide give one row).
  std::vector<IswRatePoint> table;
  double error = 0;                         // D at the cut, world units (exact)
  bool target_missed = false;               // max_error_cells: even the whole stream lies farther
  std::vector<Vec3> surface;                // the fine control points the cut decodes to (synthesized)
};

// `file` holds the whole stream, `planes` what its plane ends decode to
// (encode_isw with IswPlaneValues). Targets in RateTarget;
// `extracted_vertices` converts bits per vertex to bytes; a max_error_cells
// cut is the shortest prefix whose exact D is within it (rows estimated
// within it are measured exactly first). Errors: Error(InvalidArgument) for
// a size the headers alone exceed. Cost: per plane end a synthesis and an
// estimate, a decode of no packets and an estimate for row 0, the exact D
// and an estimate at the end; for a cut between plane ends a decode and
// exact D more (for max_error_cells up to eight, a bisection inside the
// plane that reaches it, and one per row estimated within the bound but
// not within it exactly).
RatePlan plan_rate(const std::string& file, const IswPlaneValues& planes,
                   const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, FineSurfaceMeter& meter,
                   const RateTarget& target, std::size_t extracted_vertices, double cell_size);

// The target's size limit in bytes (0: none).
std::uint64_t byte_limit(const RateTarget& target, std::size_t extracted_vertices);

// Moves a plan's cut back to `stream_bytes` (below its cut), measuring D
// there exactly by a decode: the cut's table row (the last) and surface move with it.
void move_cut(RatePlan& plan, std::uint64_t stream_bytes, const std::string& file,
              const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, FineSurfaceMeter& meter);

}  // namespace isowave::detail
