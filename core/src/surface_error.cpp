#include "isowave/core/surface_error.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <tbb/parallel_for.h>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"
#include "isowave/core/point_set_distance.h"

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

// Sample i in fan triangle j of `face`: uniform in the triangle, the square
// root of one coordinate undoing the crowding towards the first corner
// (Osada et al., Shape Distributions, 2002).
Vec3 point_in(const PolygonMesh& mesh, const std::uint32_t* face, std::uint32_t j, std::uint64_t seed, std::size_t i) {
  const double s = std::sqrt(unit_interval(splitmix64(seed, 3 * i + 1)));
  const double v = unit_interval(splitmix64(seed, 3 * i + 2));
  return (1 - s) * mesh.positions[face[0]] + (s * (1 - v)) * mesh.positions[face[j]] + (s * v) * mesh.positions[face[j + 1]];
}

// Fan triangle j (1 <= j < face size - 1) of face f: its area, 0 where it
// is not positive and finite (such a triangle gets no sample).
double fan_area(const PolygonMesh& mesh, const std::uint32_t* face, std::uint32_t j) {
  const Vec3& a = mesh.positions[face[0]];
  const double area = 0.5 * norm(cross(mesh.positions[face[j]] - a, mesh.positions[face[j + 1]] - a));
  return area > 0 && std::isfinite(area) ? area : 0.0;
}

// Faces per block of the cumulative area: blocks are summed in parallel,
// each in face order, so the sums do not depend on the thread count; small,
// so that the blocks no pick falls in are not walked again.
constexpr std::size_t kAreaBlock = 64;

// Samples with the mesh's total area. Sample i takes a uniform pick
// u_i in [0, total) and the fan triangle t whose cumulative area interval
// [A(t-1), A(t)) holds it (triangles in face order). The cumulative areas
// are not stored: the picks are sorted, the blocks' areas summed, and each
// block walks its triangles once past the picks that fall in it. Memory:
// a few words per sample and per block.
struct AreaSamples {
  std::vector<Vec3> samples;
  double area = 0;
};

AreaSamples sample_area(const PolygonMesh& mesh, std::size_t count, std::uint64_t seed) {
  const std::size_t faces = mesh.face_count(), blocks = (faces + kAreaBlock - 1) / kAreaBlock;
  std::vector<double> block_start(blocks + 1, 0.0);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    double sum = 0;
    for (std::size_t f = b * kAreaBlock; f < std::min(faces, (b + 1) * kAreaBlock); ++f)
      for (std::uint32_t j = 1; j + 1 < mesh.face_size(f); ++j) sum += fan_area(mesh, mesh.face_begin(f), j);
    block_start[b + 1] = sum;
  });
  for (std::size_t b = 0; b < blocks; ++b) block_start[b + 1] += block_start[b];
  const double total = block_start[blocks];
  if (!(total > 0) || !std::isfinite(total))
    throw Error(ErrorKind::InvalidArgument, "surface error: a mesh has no area to sample");

  // The picks in increasing order (ties by index), below the total even where it rounds.
  const double below_total = std::nextafter(total, 0.0);
  std::vector<std::pair<double, std::size_t>> picks(count);
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
    picks[i] = {std::min(below_total, total * unit_interval(splitmix64(seed, 3 * i))), i};
  });
  std::sort(picks.begin(), picks.end());

  AreaSamples out{std::vector<Vec3>(count), total};
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const auto by_pick = [](const std::pair<double, std::size_t>& p, double v) { return p.first < v; };
    auto pick = std::lower_bound(picks.begin(), picks.end(), block_start[b], by_pick);
    const auto end = std::lower_bound(pick, picks.end(), block_start[b + 1], by_pick);
    double before = block_start[b];  // the cumulative area before the current triangle
    const std::uint32_t* last_face = nullptr;
    std::uint32_t last_j = 0;
    for (std::size_t f = b * kAreaBlock; f < std::min(faces, (b + 1) * kAreaBlock) && pick != end; ++f) {
      const std::uint32_t* face = mesh.face_begin(f);
      for (std::uint32_t j = 1; j + 1 < mesh.face_size(f) && pick != end; ++j) {
        const double area = fan_area(mesh, face, j);
        if (area == 0) continue;
        last_face = face;
        last_j = j;
        for (; pick != end && pick->first < before + area; ++pick) out.samples[pick->second] = point_in(mesh, face, j, seed, pick->second);
        before += area;
      }
    }
    // Picks the running sum's rounding left past the block's last triangle
    // (a block with picks has a triangle of positive area).
    for (; pick != end; ++pick) out.samples[pick->second] = point_in(mesh, last_face, last_j, seed, pick->second);
  });
  return out;
}

}  // namespace

std::vector<Vec3> area_samples(const PolygonMesh& mesh, std::size_t count, std::uint64_t seed) {
  return sample_area(mesh, count, seed).samples;
}

namespace {

constexpr std::uint64_t kMeshSeed = 0x6d657368, kReferenceSeed = 0x72656665;

// The reference's samples, binned for the backward direction: the first
// search radius is a quarter of their mean spacing over the reference's
// `area`, so that a block of faces visits about one sample
// (docs/MEASUREMENTS.md gives the timings).
PointSetDistance binned_samples(std::vector<Vec3> samples, double area) {
  const double spacing = std::sqrt(area / double(samples.size()));
  return PointSetDistance(std::move(samples), 0.25 * spacing);
}

// RMS and maximum of distances, summed in order.
void rms_and_max(const std::vector<double>& distance, double& rms, double& max) {
  double sum = 0;
  max = 0;
  for (const double d : distance) {
    sum += d * d;
    max = std::max(max, d);
  }
  rms = std::sqrt(sum / double(distance.size()));
}

}  // namespace

SurfaceErrorReference::SurfaceErrorReference(PointSetDistance reference_samples, double area,
                                             std::shared_ptr<const BinnedSurfaceDistance> distance)
    : samples_(reference_samples.points().size()),
      reference_samples_(std::move(reference_samples)),
      area_(area),
      distance_(std::move(distance)) {}

SurfaceErrorReference SurfaceErrorReference::built(const PolygonMesh& reference, std::size_t samples) {
  if (samples == 0) throw Error(ErrorKind::InvalidArgument, "surface error: at least one sample is needed");
  AreaSamples sampled = sample_area(reference, samples, kReferenceSeed);
  return SurfaceErrorReference(binned_samples(std::move(sampled.samples), sampled.area), sampled.area,
                               std::make_shared<const BinnedSurfaceDistance>(reference));
}

SurfaceErrorReference::SurfaceErrorReference(const PolygonMesh& reference, std::size_t samples)
    : SurfaceErrorReference(built(reference, samples)) {}

SurfaceErrorReference SurfaceErrorReference::with_first_samples(std::size_t fewer) const {
  if (fewer == 0 || fewer > samples_)
    throw Error(ErrorKind::InvalidArgument, "surface error: between 1 and " + std::to_string(samples_) +
                                                " samples of this reference can be kept, not " + std::to_string(fewer));
  const std::vector<Vec3>& all = reference_samples_.points();
  std::vector<Vec3> first(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(fewer));
  return SurfaceErrorReference(binned_samples(std::move(first), area_), area_, distance_);
}

SurfaceError SurfaceErrorReference::measure(const PolygonMesh& mesh) const {
  SurfaceError error;
  rms_and_max(distances_to_reference(area_samples(mesh, samples_, kMeshSeed)), error.forward_rms, error.forward_max);
  backward(mesh, error.backward_rms, error.backward_max);
  return error;
}

std::vector<double> SurfaceErrorReference::distances_to_reference(const std::vector<Vec3>& points) const {
  return distance_->distances(points);
}

void SurfaceErrorReference::backward(const PolygonMesh& mesh, double& rms, double& max) const {
  rms_and_max(reference_samples_.distances(mesh), rms, max);
}

SurfaceError surface_error(const PolygonMesh& mesh, const PolygonMesh& reference, std::size_t samples) {
  return SurfaceErrorReference(reference, samples).measure(mesh);
}

}  // namespace isowave
