#include "isowave/fit/fit_quality.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "isowave/core/error.h"
#include "isowave/fit/trilinear.h"
#include "fitted_field.h"

namespace isowave {
namespace {

template <class Body>
void for_each_index(std::size_t n, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) body(i);
  });
}

// Root mean square and maximum of finite values (in order, so deterministic).
void rms_and_max(const std::vector<double>& values, double scale, double& rms, double& max) {
  double sum = 0;
  max = 0;
  for (double v : values) {
    sum += v * v;
    max = std::max(max, v);
  }
  rms = values.empty() ? 0.0 : std::sqrt(sum / double(values.size())) * scale;
  max *= scale;
}

// First-order distance |f(p) - iso| / |grad f(p)| of p to the isosurface of
// the trilinear field, world units; -1 where the gradient is zero or the
// value not finite.
double first_order_distance(const TrilinearGrid& grid, const Vec3& p, double iso) {
  const TrilinearSample s = grid.sample(p);
  // A point where the field equals iso is on the isosurface whatever the
  // gradient: the correction leaves points on plateaus of samples equal to
  // the isovalue.
  if (s.value == iso) return 0.0;
  const double g = norm(s.gradient);
  return g > 0 && std::isfinite(s.value) ? std::abs(s.value - iso) / g : -1.0;
}

}  // namespace

double percentile(std::vector<double>& values, double fraction) {
  if (values.empty()) return 0.0;
  const double clamped = std::clamp(fraction, 0.0, 1.0);
  const std::size_t rank = std::min(values.size() - 1, static_cast<std::size_t>(std::ceil(clamped * double(values.size()))) -
                                                           (clamped > 0 ? 1 : 0));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(rank), values.end());
  return values[rank];
}

namespace {

// isosurface_distance() on a field already set up (the report's fold
// count reads the same one).
IsosurfaceDistance isosurface_distance_on(const TrilinearGrid& grid, double cell, const std::vector<Vec3>& points,
                                          std::size_t count, double iso, double far_cells) {
  std::vector<double> first_order(count);
  for_each_index(count, [&](std::size_t v) { first_order[v] = first_order_distance(grid, points[v], iso); });
  IsosurfaceDistance result;
  std::vector<double> defined;
  defined.reserve(count);
  const double far = far_cells * cell;
  for (double d : first_order) {
    if (!(d >= 0 && std::isfinite(d))) {
      ++result.undefined;
      continue;
    }
    defined.push_back(d);
    result.far += d > far ? 1 : 0;
  }
  rms_and_max(defined, 1.0 / cell, result.rms, result.max);
  return result;
}

}  // namespace

IsosurfaceDistance isosurface_distance(const std::vector<Vec3>& points, std::size_t count, const Volume& field,
                                       double iso, double far_cells) {
  if (points.size() < count) throw Error(ErrorKind::InvalidArgument, "isosurface distance: too few points");
  const detail::FittedField fitted(field, iso);
  return isosurface_distance_on(fitted.grid(), field.cell_size(), points, count, iso, far_cells);
}

SurfaceDeviation extracted_surface_deviation(const PolygonMesh& extracted, const Volume& field, double iso) {
  const detail::FittedField fitted(field, iso);
  const TrilinearGrid& grid = fitted.grid();
  // Fixed blocks of faces, their partial sums added in order: the result
  // does not depend on the thread count.
  constexpr std::size_t kBlock = 4096;
  struct Partial {
    double weighted_squares = 0, weight = 0, max = 0;
  };
  const std::size_t faces = extracted.face_count();
  std::vector<Partial> partials((faces + kBlock - 1) / kBlock);
  constexpr double kBarycentric[7][3] = {{1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.5, 0.0},         {0.0, 0.5, 0.5},
                                         {0.5, 0.0, 0.5},             {2.0 / 3, 1.0 / 6, 1.0 / 6}, {1.0 / 6, 2.0 / 3, 1.0 / 6},
                                         {1.0 / 6, 1.0 / 6, 2.0 / 3}};
  for_each_index(partials.size(), [&](std::size_t block) {
    Partial& partial = partials[block];
    for (std::size_t f = block * kBlock; f < std::min(faces, (block + 1) * kBlock); ++f) {
      const std::uint32_t* face = extracted.face_begin(f);
      for (std::uint32_t k = 1; k + 1 < extracted.face_size(f); ++k) {
        const Vec3& a = extracted.positions[face[0]];
        const Vec3& b = extracted.positions[face[k]];
        const Vec3& c = extracted.positions[face[k + 1]];
        const double area = 0.5 * norm(cross(b - a, c - a));
        for (const auto& w : kBarycentric) {
          const double d = first_order_distance(grid, w[0] * a + w[1] * b + w[2] * c, iso);
          if (!(d >= 0 && std::isfinite(d))) continue;
          partial.weighted_squares += area * d * d;
          partial.weight += area;
          partial.max = std::max(partial.max, d);
        }
      }
    }
  });
  Partial total;
  for (const Partial& partial : partials) {
    total.weighted_squares += partial.weighted_squares;
    total.weight += partial.weight;
    total.max = std::max(total.max, partial.max);
  }
  SurfaceDeviation deviation;
  const double inverse_cell = 1.0 / field.cell_size();
  deviation.rms = total.weight > 0 ? std::sqrt(total.weighted_squares / total.weight) * inverse_cell : 0.0;
  deviation.max = total.max * inverse_cell;
  return deviation;
}

double share_farther_than(const std::vector<Vec3>& reference, std::size_t stride, const std::vector<Vec3>& fitted,
                          std::size_t count, double distance) {
  if (stride == 0 || !(distance > 0) || fitted.size() < count)
    throw Error(ErrorKind::InvalidArgument, "share_farther_than: stride >= 1, distance > 0, count <= fitted points");
  const std::size_t samples = (reference.size() + stride - 1) / stride;
  if (samples == 0) return 0.0;
  if (count == 0) return 1.0;
  // Cubes of side `distance` from the fitted points' lower corner, 21 bits
  // per axis (a key past that range gets no neighbours: it only overstates).
  Vec3 low = fitted[0];
  for (std::size_t i = 1; i < count; ++i)
    low = component_min(low, fitted[i]);
  constexpr std::int64_t kAxis = std::int64_t{1} << 21, kOutside = -2;  // kOutside: no neighbour in range
  const auto cube = [&](const Vec3& p, int axis) {
    const double c = std::floor((p[axis] - low[axis]) / distance);
    return c >= -1 && c < double(kAxis) ? static_cast<std::int64_t>(c) : kOutside;  // false for NaN too
  };
  const auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return static_cast<std::uint64_t>(x) << 42 | static_cast<std::uint64_t>(y) << 21 | static_cast<std::uint64_t>(z);
  };
  const auto inside = [](std::int64_t c) { return c >= 0 && c < kAxis; };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> sorted(count);
  for_each_index(count, [&](std::size_t i) {
    const std::int64_t x = cube(fitted[i], 0), y = cube(fitted[i], 1), z = cube(fitted[i], 2);
    sorted[i] = {inside(x) && inside(y) && inside(z) ? key(x, y, z) : ~std::uint64_t{0}, static_cast<std::uint32_t>(i)};
  });
  tbb::parallel_sort(sorted.begin(), sorted.end());
  const double squared = distance * distance;
  std::vector<std::uint8_t> farther(samples, 1);
  for_each_index(samples, [&](std::size_t s) {
    const Vec3& p = reference[s * stride];
    const std::int64_t x = cube(p, 0), y = cube(p, 1), z = cube(p, 2);
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          if (!inside(x + dx) || !inside(y + dy) || !inside(z + dz)) continue;
          const std::uint64_t k = key(x + dx, y + dy, z + dz);
          auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair<std::uint64_t, std::uint32_t>{k, 0});
          for (; it != sorted.end() && it->first == k; ++it)
            if (squared_norm(fitted[it->second] - p) <= squared) {
              farther[s] = 0;
              return;
            }
        }
  });
  std::size_t total = 0;
  for (std::uint8_t f : farther) total += f;
  return double(total) / double(samples);
}

FitQuality measure_fit_quality(const SubdivisionHierarchy& hierarchy, int level, const std::vector<Vec3>& positions,
                               const PolygonMesh& extracted, const BinnedSurfaceDistance& extracted_distance,
                               const Volume& field, double iso, Orientation orientation) {
  if (level < 0 || level > hierarchy.levels())
    throw Error(ErrorKind::InvalidArgument, "level " + std::to_string(level) + " is not in the hierarchy");
  if (positions.size() < hierarchy.vertex_count(level))
    throw Error(ErrorKind::InvalidArgument, "too few positions for the level");
  const PolygonMesh mesh = hierarchy.control_mesh(level, positions);
  const double inverse_cell = 1.0 / field.cell_size();
  FitQuality q;
  q.level = level;
  q.vertices = mesh.vertex_count();
  q.faces = mesh.face_count();
  for (const Vec3& p : mesh.positions) q.nonfinite_vertices += is_finite(p) ? 0 : 1;
  if (q.nonfinite_vertices) return q;  // nothing else is meaningful

  // Vertices against the field and the extracted surface.
  const detail::FittedField fitted(field, iso);
  const TrilinearGrid& grid = fitted.grid();
  const IsosurfaceDistance on_isosurface =
      isosurface_distance_on(grid, field.cell_size(), mesh.positions, q.vertices, iso, 1.0);
  q.isosurface_rms = on_isosurface.rms;
  q.isosurface_max = on_isosurface.max;
  q.isosurface_undefined = on_isosurface.undefined;
  q.isosurface_far = on_isosurface.far;
  const std::vector<double> to_extracted = extracted_distance.distances(mesh.positions);
  rms_and_max(to_extracted, inverse_cell, q.surface_rms, q.surface_max);
  q.surface_far = static_cast<std::size_t>(std::count_if(to_extracted.begin(), to_extracted.end(), [&](double d) {
    return d * inverse_cell > kSurfaceFarCells;
  }));

  // Coverage of the extracted surface by the fitted one.
  {
    std::vector<double> coverage = BinnedSurfaceDistance(mesh).distances(extracted.positions);
    rms_and_max(coverage, inverse_cell, q.coverage_rms, q.coverage_max);
    q.coverage_p99 = percentile(coverage, 0.99) * inverse_cell;
  }

  // Folds and areas per face.
  std::vector<std::uint8_t> folded(q.faces);
  std::vector<double> area(q.faces);
  const double expected_sign = orientation == Orientation::TowardHigher ? 1.0 : -1.0;
  for_each_index(q.faces, [&](std::size_t f) {
    const std::uint32_t* face = mesh.face_begin(f);
    const std::uint32_t size = mesh.face_size(f);
    Vec3 newell, centroid;
    for (std::uint32_t k = 0; k < size; ++k) {
      newell += cross(mesh.positions[face[k]], mesh.positions[face[k + 1 == size ? 0 : k + 1]]);
      centroid += mesh.positions[face[k]];
    }
    centroid *= 1.0 / double(size);
    area[f] = 0.5 * norm(newell);
    const Vec3 gradient = grid.sample(centroid).gradient;
    folded[f] = !(expected_sign * dot(newell, gradient) > 0) ? 1 : 0;
  });
  for (std::uint8_t t : folded) q.folded_faces += t;
  q.folded_fraction = q.faces ? double(q.folded_faces) / double(q.faces) : 0.0;

  // Patch (base face) of every face.
  const PolygonMesh& base = hierarchy.base();
  std::vector<std::uint32_t> patch(q.faces);
  for (std::size_t b = 0; b < base.face_count(); ++b) {
    const auto [first, last] = hierarchy.descendant_faces(b, level);
    std::fill(patch.begin() + static_cast<std::ptrdiff_t>(first), patch.begin() + static_cast<std::ptrdiff_t>(last),
              static_cast<std::uint32_t>(b));
  }
  std::vector<double> patch_area(base.face_count(), 0.0);
  std::vector<std::uint32_t> patch_faces(base.face_count(), 0);
  for (std::size_t f = 0; f < q.faces; ++f) {
    patch_area[patch[f]] += area[f];
    ++patch_faces[patch[f]];
  }
  std::vector<double> ratio(q.faces);
  double sum = 0, sum_squares = 0;
  for (std::size_t f = 0; f < q.faces; ++f) {
    const double mean = patch_area[patch[f]] / double(patch_faces[patch[f]]);
    ratio[f] = mean > 0 ? area[f] / mean : 1.0;
    sum += ratio[f];
    sum_squares += ratio[f] * ratio[f];
  }
  if (q.faces) {
    const double mean = sum / double(q.faces);
    q.area_ratio_deviation = std::sqrt(std::max(0.0, sum_squares / double(q.faces) - mean * mean));
    q.area_ratio_min = *std::min_element(ratio.begin(), ratio.end());
    q.area_ratio_max = *std::max_element(ratio.begin(), ratio.end());
    q.area_ratio_p1 = percentile(ratio, 0.01);
    q.area_ratio_median = percentile(ratio, 0.5);
    q.area_ratio_p99 = percentile(ratio, 0.99);
  }
  return q;
}

}  // namespace isowave
