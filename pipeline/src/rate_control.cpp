#include "rate_control.h"

#include <algorithm>
#include <cmath>

#include "isowave/codec/statistics.h"
#include "isowave/core/error.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave::detail {

double FineSurfaceMeter::d(std::vector<Vec3>& positions) {
  if (mesh_.face_count() == 0) mesh_ = hierarchy_.control_mesh(hierarchy_.levels(), std::move(positions));
  else mesh_.positions = std::move(positions);
  const double d = against_surface_.measure(mesh_).d();
  positions = std::move(mesh_.positions);
  return d;
}

namespace {

// Measures stream prefixes of one file: at plane ends from the encoder's
// values, elsewhere by a decode. The surface of the last one measured is kept.
class PrefixMeter {
 public:
  PrefixMeter(const std::string& file, const IswPlaneValues* planes,
              const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
              FineSurfaceMeter& meter)
      : file_(file), planes_(planes), hierarchy_(hierarchy), meter_(meter) {}

  // D (world units) of the surface decoded from plane end k.
  double at_plane(std::size_t k) {
    planes_->coefficients_at(k, surface_);
    return measure();
  }
  // D (world units) of the surface decoded from the first `stream_bytes`.
  double at_bytes(std::uint64_t stream_bytes) {
    IswDecodeOptions options;
    options.hierarchy = hierarchy_;
    options.max_stream_bytes = stream_bytes;
    options.order = IswOrder::Index;
    IswDecoded decoded = decode_isw(file_, "the stream", options);
    surface_ = std::move(decoded.coefficients);
    return measure();
  }
  std::vector<Vec3> take_surface() { return std::move(surface_); }

 private:
  double measure() {
    synthesize(*hierarchy_, surface_);
    return meter_.d(surface_);
  }

  const std::string& file_;
  const IswPlaneValues* planes_;
  std::shared_ptr<const SubdivisionHierarchy> hierarchy_;
  FineSurfaceMeter& meter_;
  std::vector<Vec3> surface_;
};

// The smallest prefix within (low, high] whose D is within `bound`, given
// that `high`'s is (bisection on bytes; D falls nearly monotonically there).
// The meter keeps the surface of the prefix returned.
IswRatePoint bisect(PrefixMeter& meter, std::uint64_t low, IswRatePoint high, double bound) {
  bool measured_high = false;
  for (int step = 0; step < 8 && high.stream_bytes - low > 16; ++step) {
    const std::uint64_t middle = low + (high.stream_bytes - low) / 2;
    const double e = meter.at_bytes(middle);
    measured_high = e <= bound;
    if (measured_high) high = {middle, e};
    else low = middle;
  }
  if (!measured_high) meter.at_bytes(high.stream_bytes);
  return high;
}

}  // namespace

RatePlan plan_rate(const std::string& file, const IswPlaneValues& planes,
                   const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, FineSurfaceMeter& surface_meter,
                   const RateTarget& target, std::size_t extracted_vertices, double cell_size) {
  PrefixMeter meter(file, &planes, hierarchy, surface_meter);
  RatePlan plan;
  // The last kRateTablePlanes plane boundaries, coarse to fine: the whole
  // stream's surface is the meter's at the end.
  const std::vector<std::uint64_t>& ends = planes.plane_ends();
  const std::size_t first = ends.size() > kRateTablePlanes ? ends.size() - kRateTablePlanes : 0;
  for (std::size_t k = first; k < ends.size(); ++k) plan.table.push_back({ends[k], meter.at_plane(k)});
  const std::uint64_t whole = plan.table.empty() ? 0 : plan.table.back().stream_bytes;
  plan.error = plan.table.empty() ? meter.at_bytes(0) : plan.table.back().error;
  if (const std::uint64_t bytes = byte_limit(target, extracted_vertices); bytes > 0) {
    const std::size_t rows = plan.table.size() + 1;
    const std::uint64_t within = stream_bytes_within(file, bytes, rows);
    if (within < whole) {
      plan.stream_bytes = within;
      plan.error = meter.at_bytes(within);
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
  plan.surface = meter.take_surface();
  return plan;
}

std::uint64_t byte_limit(const RateTarget& target, std::size_t extracted_vertices) {
  if (target.bits_per_vertex > 0)
    return std::max<std::uint64_t>(1, static_cast<std::uint64_t>(target.bits_per_vertex * double(extracted_vertices) / 8));
  return target.max_bytes;
}

void move_cut(RatePlan& plan, std::uint64_t stream_bytes, const std::string& file,
              const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, FineSurfaceMeter& surface_meter) {
  PrefixMeter meter(file, nullptr, hierarchy, surface_meter);
  plan.stream_bytes = stream_bytes;
  plan.error = meter.at_bytes(stream_bytes);
  plan.surface = meter.take_surface();
  while (!plan.table.empty() && plan.table.back().stream_bytes >= stream_bytes) plan.table.pop_back();
  plan.table.push_back({stream_bytes, plan.error});
}

}  // namespace isowave::detail
