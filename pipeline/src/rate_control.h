#pragma once
// Private: convert's rate control over the embedded .isw 2.0 stream (issue
// #34): D (surface_error.h) of the decoded surface against the extracted
// isosurface at every plane boundary of the whole stream, which becomes the
// file's RDTB, and the cut a target asks for.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/core/surface_error.h"
#include "isowave/pipeline/convert.h"
#include "isowave/transform/hierarchy.h"

namespace isowave::detail {

struct RatePlan {
  std::uint64_t stream_bytes = UINT64_MAX;  // where the plane stream is cut (UINT64_MAX: whole)
  std::vector<IswRatePoint> table;          // D (world units) at the plane boundaries up to the cut, and at the cut
  double error = 0;                         // D at the cut, world units
  bool target_missed = false;               // max_error_cells: even the whole stream lies farther
};

// The plane boundaries measured for the table: the last ones, each halving
// the step (the coarser planes hold few bytes and lie far off).
constexpr std::size_t kRateTablePlanes = 6;

// `file` holds the whole stream (encode_isw, version 2). Targets in
// RateTarget; `extracted_vertices` converts bits per vertex to bytes.
// Errors: Error(InvalidArgument) for a size the headers alone exceed. Cost:
// one decode, synthesis and D per table row (two at a time), and up to
// eight more for max_error_cells (bisection inside the plane that reaches it).
RatePlan plan_rate(const std::string& file, const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
                   const SurfaceErrorReference& against_surface, const RateTarget& target,
                   std::size_t extracted_vertices, double cell_size);

// The target's size limit in bytes (0: none).
std::uint64_t byte_limit(const RateTarget& target, std::size_t extracted_vertices);

// Moves a plan's cut back to `stream_bytes` (below its cut), measuring D
// there: the cut's table row (the last) moves with it.
void move_cut(RatePlan& plan, std::uint64_t stream_bytes, const std::string& file,
              const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
              const SurfaceErrorReference& against_surface);

}  // namespace isowave::detail
