#include "isowave/core/surface_error.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"

namespace isowave {

namespace {

// The n-th output of a SplitMix64 generator started at `seed` (Steele, Lea,
// Flood 2014): a counter-based stream, so any sample is computed on its own.
std::uint64_t splitmix64(std::uint64_t seed, std::uint64_t n) {
  std::uint64_t z = seed + (n + 1) * 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// A uniform double in [0, 1) from the top 53 bits.
double unit_interval(std::uint64_t bits) { return double(bits >> 11) * 0x1.0p-53; }

// The mesh's fan triangles of positive finite area and their cumulative
// areas: triangle t is picked by a uniform u in [0, total) where
// cumulative[t - 1] <= u < cumulative[t].
struct AreaTable {
  std::vector<std::uint32_t> corners;  // 3 vertex indices per triangle
  std::vector<double> cumulative;      // one per triangle, increasing
};

AreaTable area_table(const PolygonMesh& mesh) {
  AreaTable table;
  double total = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    for (std::uint32_t j = 1; j + 1 < mesh.face_size(f); ++j) {
      const Vec3& a = mesh.positions[face[0]];
      const double area = 0.5 * norm(cross(mesh.positions[face[j]] - a, mesh.positions[face[j + 1]] - a));
      if (!(area > 0) || !std::isfinite(area)) continue;
      total += area;
      table.corners.insert(table.corners.end(), {face[0], face[j], face[j + 1]});
      table.cumulative.push_back(total);
    }
  }
  if (table.cumulative.empty() || !std::isfinite(total))
    throw Error(ErrorKind::InvalidArgument, "surface error: a mesh has no area to sample");
  return table;
}

}  // namespace

std::vector<Vec3> area_samples(const PolygonMesh& mesh, std::size_t count, std::uint64_t seed) {
  const AreaTable table = area_table(mesh);
  const double total = table.cumulative.back();
  std::vector<Vec3> samples(count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const double pick = total * unit_interval(splitmix64(seed, 3 * i));
      const std::size_t t = std::min<std::size_t>(
          std::upper_bound(table.cumulative.begin(), table.cumulative.end(), pick) - table.cumulative.begin(),
          table.cumulative.size() - 1);
      // Uniform in the triangle: the square root of one coordinate undoes
      // the crowding towards corner a (Osada et al., Shape Distributions, 2002).
      const double s = std::sqrt(unit_interval(splitmix64(seed, 3 * i + 1)));
      const double v = unit_interval(splitmix64(seed, 3 * i + 2));
      const std::uint32_t* c = &table.corners[3 * t];
      samples[i] = (1 - s) * mesh.positions[c[0]] + (s * (1 - v)) * mesh.positions[c[1]] + (s * v) * mesh.positions[c[2]];
    }
  });
  return samples;
}

namespace {

constexpr std::uint64_t kMeshSeed = 0x6d657368, kReferenceSeed = 0x72656665;

// RMS and maximum distance from `samples` to the surface `target` measures,
// summed in sample order (the same result for any thread count).
void distances_to(const BinnedSurfaceDistance& target, const std::vector<Vec3>& samples, double& rms, double& max) {
  const std::vector<double> distance = target.distances(samples);
  double sum = 0;
  max = 0;
  for (const double d : distance) {
    sum += d * d;
    max = std::max(max, d);
  }
  rms = std::sqrt(sum / double(distance.size()));
}

}  // namespace

SurfaceErrorReference::SurfaceErrorReference(const PolygonMesh& reference, std::size_t samples)
    : samples_(samples == 0 ? throw Error(ErrorKind::InvalidArgument, "surface error: at least one sample is needed")
                            : samples),
      reference_samples_(area_samples(reference, samples, kReferenceSeed)),
      distance_(reference) {}

SurfaceError SurfaceErrorReference::measure(const PolygonMesh& mesh) const {
  SurfaceError error;
  distances_to(distance_, area_samples(mesh, samples_, kMeshSeed), error.forward_rms, error.forward_max);
  distances_to(BinnedSurfaceDistance(mesh), reference_samples_, error.backward_rms, error.backward_max);
  return error;
}

SurfaceError surface_error(const PolygonMesh& mesh, const PolygonMesh& reference, std::size_t samples) {
  return SurfaceErrorReference(reference, samples).measure(mesh);
}

}  // namespace isowave
