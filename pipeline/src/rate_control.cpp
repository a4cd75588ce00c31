#include "rate_control.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "isowave/codec/statistics.h"
#include "isowave/core/error.h"

namespace isowave::detail {

namespace {

// Decodes and measures stream prefixes of one file.
class PrefixMeter {
 public:
  PrefixMeter(const std::string& file, const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
              const SurfaceErrorReference& against_surface)
      : file_(file), hierarchy_(hierarchy), against_surface_(against_surface) {}

  // D (world units) of the surface decoded from the first `stream_bytes`.
  double error(std::uint64_t stream_bytes) {
    IswDecodeOptions options;
    options.hierarchy = hierarchy_;
    options.max_stream_bytes = stream_bytes;
    IswDecoded decoded = decode_isw(file_, "the stream", options);
    const int levels = decoded.levels;
    const PolygonMesh mesh = hierarchy_->control_mesh(levels, take_reconstruction(decoded, SIZE_MAX));
    return against_surface_.measure(mesh).d();
  }

 private:
  const std::string& file_;
  std::shared_ptr<const SubdivisionHierarchy> hierarchy_;
  const SurfaceErrorReference& against_surface_;
};

// The smallest prefix within (low, high] whose D is within `bound`, given
// that `high`'s is (bisection on bytes; D falls nearly monotonically there).
IswRatePoint bisect(PrefixMeter& meter, std::uint64_t low, IswRatePoint high, double bound) {
  for (int step = 0; step < 8 && high.stream_bytes - low > 16; ++step) {
    const std::uint64_t middle = low + (high.stream_bytes - low) / 2;
    const double e = meter.error(middle);
    if (e <= bound) high = {middle, e};
    else low = middle;
  }
  return high;
}

}  // namespace

RatePlan plan_rate(const std::string& file, const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
                   const SurfaceErrorReference& against_surface, const RateTarget& target,
                   std::size_t extracted_vertices, double cell_size) {
  PrefixMeter meter(file, hierarchy, against_surface);
  RatePlan plan;
  // The last kRateTablePlanes plane boundaries, measured two at a time.
  std::vector<std::uint64_t> ends = stream_plane_ends(file);
  if (ends.size() > kRateTablePlanes) ends.erase(ends.begin(), ends.end() - kRateTablePlanes);
  plan.table.resize(ends.size());
  tbb::parallel_for(std::size_t{0}, ends.size(), [&](std::size_t k) { plan.table[k] = {ends[k], meter.error(ends[k])}; });
  const std::uint64_t whole = plan.table.empty() ? 0 : plan.table.back().stream_bytes;
  plan.error = plan.table.empty() ? meter.error(0) : plan.table.back().error;
  if (const std::uint64_t bytes = byte_limit(target, extracted_vertices); bytes > 0) {
    const std::size_t rows = plan.table.size() + 1;
    const std::uint64_t within = stream_bytes_within(file, bytes, rows);
    if (within < whole) {
      plan.stream_bytes = within;
      plan.error = meter.error(within);
    }
  } else if (target.max_error_cells > 0) {
    const double bound = target.max_error_cells * cell_size;
    const auto reach = std::find_if(plan.table.begin(), plan.table.end(), [&](const IswRatePoint& p) { return p.error <= bound; });
    if (reach == plan.table.end()) {
      plan.target_missed = true;
    } else {
      const std::uint64_t low = reach == plan.table.begin() ? 0 : (reach - 1)->stream_bytes;
      const IswRatePoint cut = bisect(meter, low, *reach, bound);
      plan.stream_bytes = cut.stream_bytes;
      plan.error = cut.error;
    }
  }
  if (plan.stream_bytes < whole) {
    plan.table.erase(std::remove_if(plan.table.begin(), plan.table.end(),
                                    [&](const IswRatePoint& p) { return p.stream_bytes >= plan.stream_bytes; }),
                     plan.table.end());
    plan.table.push_back({plan.stream_bytes, plan.error});
  }
  return plan;
}

std::uint64_t byte_limit(const RateTarget& target, std::size_t extracted_vertices) {
  if (target.bits_per_vertex > 0)
    return std::max<std::uint64_t>(1, static_cast<std::uint64_t>(target.bits_per_vertex * double(extracted_vertices) / 8));
  return target.max_bytes;
}

void move_cut(RatePlan& plan, std::uint64_t stream_bytes, const std::string& file,
              const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
              const SurfaceErrorReference& against_surface) {
  PrefixMeter meter(file, hierarchy, against_surface);
  plan.stream_bytes = stream_bytes;
  plan.error = meter.error(stream_bytes);
  while (!plan.table.empty() && plan.table.back().stream_bytes >= stream_bytes) plan.table.pop_back();
  plan.table.push_back({stream_bytes, plan.error});
}

}  // namespace isowave::detail
