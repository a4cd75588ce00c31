#include "rate_control.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <random>

#include "isowave/codec/statistics.h"
#include "isowave/core/error.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave::detail {

FineSurfaceMeter::FineSurfaceMeter(const SubdivisionHierarchy& hierarchy, const SurfaceErrorReference& against_surface)
    : hierarchy_(hierarchy),
      against_surface_(against_surface),
      estimate_(against_surface.with_first_samples(std::min(kRateEstimateSamples, against_surface.samples()))) {}

namespace {

// Corner positions of fan triangle `corner` of face f.
struct Triangle {
  Vec3 a, b, c;
  double area() const {
    const double area = 0.5 * norm(cross(b - a, c - a));
    return area > 0 && std::isfinite(area) ? area : 0.0;
  }
};
Triangle fan_triangle(const PolygonMesh& mesh, std::uint32_t face, std::uint32_t corner) {
  const std::uint32_t* v = mesh.face_begin(face);
  return {mesh.positions[v[0]], mesh.positions[v[corner]], mesh.positions[v[corner + 1]]};
}

// A uniform double in [0, 1) from the top 53 bits of a 64-bit generator.
double unit(std::mt19937_64& random) { return double(random() >> 11) * 0x1.0p-53; }

}  // namespace

SurfaceError FineSurfaceMeter::exact(std::vector<Vec3>& positions) {
  if (mesh_.face_count() == 0) mesh_ = hierarchy_.control_mesh(hierarchy_.levels(), std::move(positions));
  else mesh_.positions = std::move(positions);
  const SurfaceError error = against_surface_.measure(mesh_);
  positions = std::move(mesh_.positions);
  return error;
}

void FineSurfaceMeter::fix_estimate_samples(std::vector<Vec3>& positions) {
  if (mesh_.face_count() == 0) mesh_ = hierarchy_.control_mesh(hierarchy_.levels(), std::move(positions));
  else mesh_.positions = std::move(positions);
  // Every fan triangle and its cumulative area, in face order.
  std::vector<Location> triangles;
  std::vector<double> cumulative;
  double total = 0;
  for (std::uint32_t f = 0; f < mesh_.face_count(); ++f)
    for (std::uint32_t j = 1; j + 1 < mesh_.face_size(f); ++j) {
      const double area = fan_triangle(mesh_, f, j).area();
      if (area == 0) continue;
      triangles.push_back({f, j, 0, 0, area});
      cumulative.push_back(total += area);
    }
  positions = std::move(mesh_.positions);
  if (triangles.empty()) throw Error(ErrorKind::InvalidArgument, "surface error: a mesh has no area to sample");
  std::mt19937_64 random(0x72617465);  // fixed: the same locations for the same mesh
  locations_.resize(estimate_.samples());
  for (Location& location : locations_) {
    const double pick = total * unit(random);
    const std::size_t t = std::min<std::size_t>(
        triangles.size() - 1, std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
    location = triangles[t];
    location.s = std::sqrt(unit(random));
    location.v = unit(random);
  }
}

double FineSurfaceMeter::forward_estimate() const {
  std::vector<Vec3> points(locations_.size());
  std::vector<double> weights(locations_.size());
  for (std::size_t i = 0; i < locations_.size(); ++i) {
    const Location& l = locations_[i];
    const Triangle t = fan_triangle(mesh_, l.face, l.corner);
    points[i] = (1 - l.s) * t.a + (l.s * (1 - l.v)) * t.b + (l.s * l.v) * t.c;
    weights[i] = t.area() / l.area;
  }
  const std::vector<double> distances = estimate_.distances_to_reference(points);
  double sum = 0, weight = 0;
  for (std::size_t i = 0; i < distances.size(); ++i) {
    sum += weights[i] * distances[i] * distances[i];
    weight += weights[i];
  }
  return weight > 0 ? std::sqrt(sum / weight) : 0.0;
}

SurfaceError FineSurfaceMeter::estimate(std::vector<Vec3>& positions) {
  assert(!locations_.empty());
  mesh_.positions = std::move(positions);
  SurfaceError error;
  error.forward_rms = forward_estimate();
  estimate_.backward(mesh_, error.backward_rms, error.backward_max);
  positions = std::move(mesh_.positions);
  return error;
}

double corrected_d(const SurfaceError& estimate, const SurfaceError& last_estimate, const SurfaceError& last_exact) {
  const auto direction = [](double rms, double last_rms, double last_exact_rms) {
    return std::sqrt(std::max(0.0, rms * rms + last_exact_rms * last_exact_rms - last_rms * last_rms));
  };
  return std::max(direction(estimate.forward_rms, last_estimate.forward_rms, last_exact.forward_rms),
                  direction(estimate.backward_rms, last_estimate.backward_rms, last_exact.backward_rms));
}

namespace {

enum class Samples { All, Estimate };

// Measures stream prefixes of one file: at plane ends from the encoder's
// values, elsewhere by a decode. Holds the surface of the prefix loaded last.
class PrefixMeter {
 public:
  PrefixMeter(const std::string& file, const IswPlaneValues* planes,
              const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, FineSurfaceMeter& meter)
      : file_(file), planes_(planes), hierarchy_(hierarchy), meter_(meter) {}

  // The surface decoded from plane end k.
  void load_plane(std::size_t k) {
    planes_->coefficients_at(k, surface_);
    synthesize(*hierarchy_, surface_);
  }
  // The surface decoded from the first `stream_bytes`.
  void load_bytes(std::uint64_t stream_bytes) {
    IswDecodeOptions options;
    options.hierarchy = hierarchy_;
    options.max_stream_bytes = stream_bytes;
    options.order = IswOrder::Index;
    IswDecoded decoded = decode_isw(file_, "the stream", options);
    surface_ = std::move(decoded.coefficients);
    synthesize(*hierarchy_, surface_);
  }
  // D's directions (world units) of the surface loaded last.
  SurfaceError measure(Samples samples) {
    return samples == Samples::All ? meter_.exact(surface_) : meter_.estimate(surface_);
  }
  double exact_d_at_bytes(std::uint64_t stream_bytes) {
    load_bytes(stream_bytes);
    return measure(Samples::All).d();
  }
  // The estimate's samples drawn on the surface loaded last.
  void fix_estimate_samples() { meter_.fix_estimate_samples(surface_); }
  std::vector<Vec3> take_surface() { return std::move(surface_); }

 private:
  const std::string& file_;
  const IswPlaneValues* planes_;
  std::shared_ptr<const SubdivisionHierarchy> hierarchy_;
  FineSurfaceMeter& meter_;
  std::vector<Vec3> surface_;
};

// A prefix the table measures: no packet (plane -1), or a plane's end.
struct TableRow {
  std::uint64_t stream_bytes = 0;
  int plane = -1;
};

// Row 0 and one row per distinct plane end (of plane ends that coincide,
// the last: they decode alike), ascending.
std::vector<TableRow> table_rows(const std::vector<std::uint64_t>& ends) {
  std::vector<TableRow> rows{{0, -1}};
  for (std::size_t k = 0; k < ends.size(); ++k) {
    if (ends[k] == rows.back().stream_bytes) rows.pop_back();
    rows.push_back({ends[k], static_cast<int>(k)});
  }
  return rows;
}

void load(PrefixMeter& meter, const TableRow& row) {
  if (row.plane < 0) meter.load_bytes(row.stream_bytes);
  else meter.load_plane(static_cast<std::size_t>(row.plane));
}

// D at every row: the last exact, the others estimated and corrected by the
// last row's exact measure (corrected_d). The estimate's samples are drawn
// on the last row's surface; the meter ends on it.
std::vector<IswRatePoint> measure_table(PrefixMeter& meter, const std::vector<TableRow>& rows) {
  load(meter, rows.back());
  const SurfaceError last_exact = meter.measure(Samples::All);
  std::vector<IswRatePoint> table;
  if (rows.size() > 1) {
    meter.fix_estimate_samples();
    const SurfaceError last_estimate = meter.measure(Samples::Estimate);
    for (std::size_t r = 0; r + 1 < rows.size(); ++r) {
      load(meter, rows[r]);
      table.push_back({rows[r].stream_bytes, corrected_d(meter.measure(Samples::Estimate), last_estimate, last_exact)});
    }
    load(meter, rows.back());
  }
  table.push_back({rows.back().stream_bytes, last_exact.d()});
  return table;
}

// The smallest prefix within (low, high] whose D is within `bound`, given
// that `high`'s (exact) is (bisection on bytes; D falls nearly monotonically
// there). The meter holds the surface of the prefix returned.
IswRatePoint bisect(PrefixMeter& meter, std::uint64_t low, IswRatePoint high, double bound) {
  bool measured_high = false;
  for (int step = 0; step < 8 && high.stream_bytes - low > 16; ++step) {
    const std::uint64_t middle = low + (high.stream_bytes - low) / 2;
    const double e = meter.exact_d_at_bytes(middle);
    measured_high = e <= bound;
    if (measured_high) high = {middle, e};
    else low = middle;
  }
  if (!measured_high) meter.load_bytes(high.stream_bytes);
  return high;
}

// The cut of a maximum error: inside the first row whose exact D is within
// `bound` (rows estimated within it are measured exactly first). The meter
// holds the cut's surface, or the whole stream's when none is.
void cut_to_error(RatePlan& plan, PrefixMeter& meter, const std::vector<TableRow>& rows, double bound) {
  const std::size_t last = plan.table.size() - 1;
  for (std::size_t r = 0; r <= last; ++r) {
    IswRatePoint reach = plan.table[r];
    if (reach.error > bound) continue;
    if (r < last) {
      load(meter, rows[r]);
      reach.error = meter.measure(Samples::All).d();
      if (reach.error > bound) continue;
    }
    const IswRatePoint cut = bisect(meter, r == 0 ? 0 : plan.table[r - 1].stream_bytes, reach, bound);
    plan.stream_bytes = cut.stream_bytes;
    plan.error = cut.error;
    return;
  }
  plan.target_missed = true;
  load(meter, rows.back());
}

}  // namespace

RatePlan plan_rate(const std::string& file, const IswPlaneValues& planes,
                   const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, FineSurfaceMeter& surface_meter,
                   const RateTarget& target, std::size_t extracted_vertices, double cell_size) {
  PrefixMeter meter(file, &planes, hierarchy, surface_meter);
  const std::vector<TableRow> rows = table_rows(planes.plane_ends());
  RatePlan plan;
  plan.table = measure_table(meter, rows);
  plan.error = plan.table.back().error;
  const std::uint64_t whole = plan.table.back().stream_bytes;
  if (const std::uint64_t bytes = byte_limit(target, extracted_vertices); bytes > 0) {
    const std::uint64_t within = stream_bytes_within(file, bytes, plan.table.size() + 1);
    if (within < whole) {
      plan.stream_bytes = within;
      plan.error = meter.exact_d_at_bytes(within);
    }
  } else if (target.max_error_cells > 0) {
    cut_to_error(plan, meter, rows, target.max_error_cells * cell_size);
  }
  if (plan.stream_bytes < whole) {
    while (!plan.table.empty() && plan.table.back().stream_bytes >= plan.stream_bytes) plan.table.pop_back();
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
  plan.error = meter.exact_d_at_bytes(stream_bytes);
  plan.surface = meter.take_surface();
  while (!plan.table.empty() && plan.table.back().stream_bytes >= stream_bytes) plan.table.pop_back();
  plan.table.push_back({stream_bytes, plan.error});
}

}  // namespace isowave::detail
