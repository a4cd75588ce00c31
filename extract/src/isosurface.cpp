// Extraction driver and clean-ups: Gaussian pre-filter, small-component
// removal, statistics (contouring itself is in contour.cpp).
#include "isowave/extract/isosurface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/core/surface_error.h"

namespace isowave {
namespace {

// Convolves `rows` rows of nx contiguous samples, row m starting at
// data + base + m * stride, along the row index (the y or z axis) in place.
// `scratch` holds rows * nx floats.
void convolve_rows(float* data, std::size_t base, std::size_t stride, std::size_t rows, std::size_t nx,
                   const std::vector<float>& weights, std::vector<float>& scratch) {
  scratch.resize(rows * nx);
  for (std::size_t m = 0; m < rows; ++m) std::copy_n(data + base + m * stride, nx, scratch.data() + m * nx);
  const long radius = static_cast<long>(weights.size()) - 1;
  const long last = static_cast<long>(rows) - 1;
  std::vector<float> sum(nx), weight(nx);
  for (long m = 0; m <= last; ++m) {
    std::fill(sum.begin(), sum.end(), 0.0f);
    std::fill(weight.begin(), weight.end(), 0.0f);
    for (long d = -radius; d <= radius; ++d) {
      const float w = weights[static_cast<std::size_t>(std::abs(d))];
      const float* row = scratch.data() + static_cast<std::size_t>(std::clamp(m + d, 0L, last)) * nx;
      for (std::size_t i = 0; i < nx; ++i) {
        const bool finite = std::isfinite(row[i]);
        sum[i] += finite ? w * row[i] : 0.0f;
        weight[i] += finite ? w : 0.0f;
      }
    }
    float* out = data + base + static_cast<std::size_t>(m) * stride;
    for (std::size_t i = 0; i < nx; ++i)
      out[i] = weight[i] > 0 ? sum[i] / weight[i] : std::numeric_limits<float>::quiet_NaN();
  }
}

// Convolves one contiguous row (the x axis) in place.
void convolve_row(float* row, std::size_t nx, const std::vector<float>& weights, std::vector<float>& scratch) {
  scratch.assign(row, row + nx);
  const long radius = static_cast<long>(weights.size()) - 1;
  const long last = static_cast<long>(nx) - 1;
  for (long i = 0; i <= last; ++i) {
    float sum = 0, weight = 0;
    for (long d = -radius; d <= radius; ++d) {
      const float v = scratch[static_cast<std::size_t>(std::clamp(i + d, 0L, last))];
      if (!std::isfinite(v)) continue;
      const float w = weights[static_cast<std::size_t>(std::abs(d))];
      sum += w * v;
      weight += w;
    }
    row[i] = weight > 0 ? sum / weight : std::numeric_limits<float>::quiet_NaN();
  }
}

std::vector<std::size_t> size_histogram(const std::vector<std::size_t>& sizes) {
  std::vector<std::size_t> histogram;
  for (std::size_t size : sizes) {
    std::size_t bucket = 0;
    for (std::size_t s = size; s >= 10; s /= 10) ++bucket;
    if (histogram.size() <= bucket) histogram.resize(bucket + 1, 0);
    ++histogram[bucket];
  }
  return histogram;
}

double face_area(const PolygonMesh& mesh, std::size_t f) {
  const std::uint32_t* face = mesh.face_begin(f);
  const Vec3& a = mesh.positions[face[0]];
  double area = 0;
  for (std::uint32_t i = 1; i + 1 < mesh.face_size(f); ++i)
    area += 0.5 * norm(cross(mesh.positions[face[i]] - a, mesh.positions[face[i + 1]] - a));
  return area;
}

}  // namespace

Volume gaussian_smoothed(const Volume& volume, double sigma) {
  if (!(sigma > 0) || !std::isfinite(sigma))
    throw Error(ErrorKind::InvalidArgument, "the smoothing sigma must be a positive number of voxels");
  const std::size_t radius = static_cast<std::size_t>(std::ceil(3 * sigma));
  std::vector<float> weights(radius + 1);
  for (std::size_t d = 0; d <= radius; ++d)
    weights[d] = static_cast<float>(std::exp(-0.5 * static_cast<double>(d * d) / (sigma * sigma)));

  Volume out = volume;
  const std::size_t nx = volume.dims[0], ny = volume.dims[1], nz = volume.dims[2], plane = nx * ny;
  float* data = out.values.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ny * nz), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<float> scratch;
    for (std::size_t r = range.begin(); r != range.end(); ++r) convolve_row(data + r * nx, nx, weights, scratch);
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nz), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<float> scratch;
    for (std::size_t k = range.begin(); k != range.end(); ++k)
      convolve_rows(data, k * plane, nx, ny, nx, weights, scratch);
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ny), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<float> scratch;
    for (std::size_t j = range.begin(); j != range.end(); ++j)
      convolve_rows(data, j * nx, plane, nz, nx, weights, scratch);
  });
  out.nonfinite_count = static_cast<std::size_t>(
      std::count_if(out.values.begin(), out.values.end(), [](float v) { return !std::isfinite(v); }));
  return out;
}

namespace {

// Counts and area of every component of a mesh and each face's component:
// one half-edge build serves the statistics before and after the clean-up
// and the clean-up itself, instead of one count each.
struct ComponentTable {
  std::vector<TopologySummary> topology;
  std::vector<double> area;
  std::vector<std::uint32_t> face_component;
};

ComponentTable component_table(const PolygonMesh& mesh) {
  ComponentTable table;
  table.topology = summarize_components(mesh, &table.face_component);
  table.area.assign(table.topology.size(), 0.0);
  for (std::size_t f = 0; f < mesh.face_count(); ++f) table.area[table.face_component[f]] += face_area(mesh, f);
  return table;
}

// The statistics of the components c with keep[c] (all without `keep`).
SurfaceStatistics statistics_of(const ComponentTable& table, const std::vector<std::uint8_t>* keep = nullptr) {
  SurfaceStatistics stats;
  std::vector<std::size_t> sizes;
  for (std::size_t c = 0; c < table.topology.size(); ++c) {
    if (keep && !(*keep)[c]) continue;
    static_cast<TopologySummary&>(stats) += table.topology[c];
    stats.area += table.area[c];
    sizes.push_back(table.topology[c].vertices);
  }
  stats.component_size_histogram = size_histogram(sizes);
  return stats;
}

// Drops the components c without keep[c] (table is the mesh's).
ComponentRemoval drop_components(PolygonMesh& mesh, const ComponentTable& table,
                                 const std::vector<std::uint8_t>& keep) {
  ComponentRemoval removal;
  for (std::size_t c = 0; c < table.topology.size(); ++c)
    if (!keep[c]) {
      ++removal.components;
      removal.faces += table.topology[c].faces;
      removal.area += table.area[c];
    }
  if (removal.components == 0) return removal;

  std::vector<std::uint32_t> kept_offsets{0};
  std::vector<std::uint32_t> kept_vertices;
  kept_offsets.reserve(mesh.face_count() + 1);
  kept_vertices.reserve(mesh.face_vertices.size());
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    if (!keep[table.face_component[f]]) continue;
    kept_vertices.insert(kept_vertices.end(), mesh.face_begin(f), mesh.face_begin(f) + mesh.face_size(f));
    kept_offsets.push_back(static_cast<std::uint32_t>(kept_vertices.size()));
  }
  mesh.face_offsets = std::move(kept_offsets);
  mesh.face_vertices = std::move(kept_vertices);
  removal.vertices = remove_unreferenced_vertices(mesh);
  if (mesh.sharp_count() == 0) mesh.sharp.clear();
  return removal;
}

// remove_small_components() with the mesh's table; keep[c] says which stayed.
ComponentRemoval remove_components(PolygonMesh& mesh, const ComponentTable& table, std::size_t min_vertices,
                                   std::vector<std::uint8_t>& keep) {
  keep.assign(table.topology.size(), 1);
  if (min_vertices <= 1 || mesh.face_count() == 0) return {};
  for (std::size_t c = 0; c < table.topology.size(); ++c) keep[c] = table.topology[c].vertices >= min_vertices;
  return drop_components(mesh, table, keep);
}

}  // namespace

ComponentRemoval remove_small_components(PolygonMesh& mesh, std::size_t min_vertices) {
  if (min_vertices <= 1 || mesh.face_count() == 0) return {};
  std::vector<std::uint8_t> keep;
  return remove_components(mesh, component_table(mesh), min_vertices, keep);
}

ComponentRemoval remove_components_under(PolygonMesh& mesh, double extent) {
  if (!(extent > 0) || mesh.face_count() == 0) return {};
  const ComponentTable table = component_table(mesh);
  const std::size_t count = table.topology.size();
  std::vector<Vec3> low(count, Vec3{1e300, 1e300, 1e300}), high(count, Vec3{-1e300, -1e300, -1e300});
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t c = table.face_component[f];
    for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) {
      const Vec3& p = mesh.positions[mesh.face_begin(f)[k]];
      low[c] = {std::min(low[c].x, p.x), std::min(low[c].y, p.y), std::min(low[c].z, p.z)};
      high[c] = {std::max(high[c].x, p.x), std::max(high[c].y, p.y), std::max(high[c].z, p.z)};
    }
  }
  std::vector<std::uint8_t> keep(count);
  for (std::size_t c = 0; c < count; ++c) {
    const Vec3 size = high[c] - low[c];
    keep[c] = std::max({size.x, size.y, size.z}) >= extent;
  }
  return drop_components(mesh, table, keep);
}

double surface_area(const PolygonMesh& mesh) {
  double area = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) area += face_area(mesh, f);
  return area;
}

SurfaceStatistics surface_statistics(const PolygonMesh& mesh) { return statistics_of(component_table(mesh)); }

namespace {

// extract_isosurface() on `given`; the steps that change the field write to
// *writable (which may be `given` itself) or, when it is null, to a copy.
Isosurface extract(const Volume& given, Volume* writable, const IsosurfaceOptions& options, ProgressSink& progress) {
  if (!std::isfinite(options.iso)) throw Error(ErrorKind::InvalidArgument, "the isovalue must be finite");
  if (!(options.smooth_sigma >= 0) || !std::isfinite(options.smooth_sigma))
    throw Error(ErrorKind::InvalidArgument, "the smoothing sigma must be a non-negative number of voxels");
  if (!(options.topology_tolerance >= 0) || !std::isfinite(options.topology_tolerance))
    throw Error(ErrorKind::InvalidArgument, "the topology tolerance must be a non-negative number of cells");
  Isosurface result;
  IsosurfaceReport& report = result.report;
  report.iso = options.iso;
  report.flipped = options.flip;
  report.nonfinite_samples = given.nonfinite_count;
  report.smooth_sigma = options.smooth_sigma;
  report.min_component_vertices = options.min_component_vertices;
  report.topology_tolerance = options.topology_tolerance;

  progress.begin_stage("contour");
  result.mesh = contour_volume(given, options.iso, options.flip, &report.centroid_vertices);
  progress.end_stage();
  progress.begin_stage("topology");
  ComponentTable table = component_table(result.mesh);
  report.before = statistics_of(table);
  progress.end_stage();

  Volume copy;  // the changed field when the caller's may not change
  const Volume* field = &given;
  bool recontoured = false;
  if (options.smooth_sigma > 0) {
    progress.begin_stage("smooth");
    result.mesh = PolygonMesh();  // free the unsmoothed contour first
    Volume& target = writable ? *writable : copy;
    target = gaussian_smoothed(*field, options.smooth_sigma);
    field = &target;
    result.mesh = contour_volume(*field, options.iso, options.flip, &report.centroid_vertices);
    progress.end_stage();
    recontoured = true;
  }
  if (options.topology_tolerance > 0) {
    progress.begin_stage("topology tolerance");
    if (!writable && field != &copy) copy = given;
    Volume& target = writable ? *writable : copy;
    report.topology = clean_topology(target, options.iso, options.topology_tolerance);
    field = &target;
    if (report.topology.changed()) {
      PolygonMesh cleaned = contour_volume(*field, options.iso, options.flip, &report.centroid_vertices);
      const double area_before = surface_area(result.mesh);
      report.topology_area_change = surface_area(cleaned) - area_before;
      if (cleaned.face_count() > 0 && result.mesh.face_count() > 0)
        report.topology_d = surface_error(cleaned, result.mesh, 100000).d() / field->cell_size();
      result.mesh = std::move(cleaned);
      recontoured = true;
    }
    progress.end_stage();
  }
  if (recontoured) table = component_table(result.mesh);

  std::vector<std::uint8_t> keep;
  bool removed = false;
  if (options.min_component_vertices > 1) {
    progress.begin_stage("components");
    const ComponentRemoval removal = remove_components(result.mesh, table, options.min_component_vertices, keep);
    report.dropped_components = removal.components;
    report.dropped_vertices = removal.vertices;
    report.dropped_triangles = removal.faces;
    report.dropped_area = removal.area;
    removed = removal.components > 0;
    progress.end_stage();
  }
  if (recontoured || removed) report.after = statistics_of(table, removed ? &keep : nullptr);
  else report.after = report.before;
  report.sharp_vertices = result.mesh.sharp_count();
  return result;
}

}  // namespace

Isosurface extract_isosurface(const Volume& volume, const IsosurfaceOptions& options, ProgressSink& progress) {
  return extract(volume, nullptr, options, progress);
}

Isosurface extract_isosurface_in_place(Volume& field, const IsosurfaceOptions& options, ProgressSink& progress) {
  return extract(field, &field, options, progress);
}

}  // namespace isowave
