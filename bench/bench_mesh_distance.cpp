// Distances between two meshes (CGAL AABB trees): the error measure shared
// by isowave and Draco in bench/draco_rate_distortion.sh, where vertex
// correspondence is lost. Both ways: from the vertices of MESH to the surface
// of REFERENCE (how far off what was decoded lies) and from the vertices of
// REFERENCE to the surface of MESH (how much of the reference it covers; a
// fit that left parts of the surface out shows only here).
//
// usage: bench_mesh_distance MESH REFERENCE [CELL] [--worst N | --surface-error SAMPLES]
// prints: rms max reverse_rms reverse_max   (in percent of CELL, default 1);
// --worst N then lists the N vertices of REFERENCE farthest from MESH (index,
// position, distance in cells): where a fit left the surface out.
// --surface-error SAMPLES instead times the surface error D as convert
// measures it (SurfaceErrorReference: the reference made once, then
// measure(MESH), best of 3) and prints its directions and D in % of CELL.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <stdexcept>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/surface_distance.h"
#include "isowave/core/surface_error.h"

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// D between the meshes with SurfaceErrorReference, timed.
void time_surface_error(const isowave::PolygonMesh& mesh, const isowave::PolygonMesh& reference, double cell,
                        std::size_t samples) {
  auto start = std::chrono::steady_clock::now();
  const isowave::SurfaceErrorReference against(reference, samples);
  std::printf("reference (%zu vertices, %zu samples): %.3f s\n", reference.vertex_count(), samples, seconds_since(start));
  double best = 1e30;
  isowave::SurfaceError error;
  for (int run = 0; run < 3; ++run) {
    start = std::chrono::steady_clock::now();
    error = against.measure(mesh);
    best = std::min(best, seconds_since(start));
  }
  std::printf("measure (%zu vertices): %.3f s best of 3; forward %.4f, backward %.4f, D %.4f %% of a cell\n",
              mesh.vertex_count(), best, 100 * error.forward_rms / cell, 100 * error.backward_rms / cell,
              100 * error.d() / cell);
}

}  // namespace

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  std::size_t worst = 0, samples = 0;
  if (argc >= 5 && std::strcmp(argv[argc - 2], "--worst") == 0) {
    worst = static_cast<std::size_t>(std::atol(argv[argc - 1]));
    argc -= 2;
  } else if (argc >= 5 && std::strcmp(argv[argc - 2], "--surface-error") == 0) {
    samples = static_cast<std::size_t>(std::atol(argv[argc - 1]));
    argc -= 2;
  }
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr, "usage: bench_mesh_distance MESH REFERENCE [CELL] [--worst N | --surface-error SAMPLES]\n");
    return 2;
  }
  try {
    const isowave::PolygonMesh mesh = isowave::read_mesh(argv[1]);
    const isowave::PolygonMesh reference = isowave::read_mesh(argv[2]);
    const double cell = argc > 3 ? std::atof(argv[3]) : 1.0;
    if (!(cell > 0)) throw std::runtime_error("CELL must be a positive number");
    if (samples > 0) {
      time_surface_error(mesh, reference, cell, samples);
      return 0;
    }
    const auto rms_and_max = [cell](const std::vector<double>& d) {
      double sum = 0, max = 0;
      for (double x : d) {
        sum += x * x;
        max = std::max(max, x);
      }
      std::printf("%.4f %.4f", 100 * std::sqrt(sum / static_cast<double>(d.size())) / cell, 100 * max / cell);
    };
    rms_and_max(isowave::SurfaceDistance(reference).distances(mesh.positions));
    std::printf(" ");
    const std::vector<double> reverse = isowave::SurfaceDistance(mesh).distances(reference.positions);
    rms_and_max(reverse);
    std::printf("\n");
    if (worst > 0) {
      std::vector<std::size_t> order(reverse.size());
      std::iota(order.begin(), order.end(), std::size_t{0});
      worst = std::min(worst, order.size());
      std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(worst), order.end(),
                        [&](std::size_t a, std::size_t b) { return reverse[a] > reverse[b]; });
      for (std::size_t k = 0; k < worst; ++k) {
        const isowave::Vec3& p = reference.positions[order[k]];
        std::printf("%zu %.3f %.3f %.3f %.3f\n", order[k], p.x, p.y, p.z, reverse[order[k]] / cell);
      }
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench_mesh_distance: %s\n", error.what());
    return 1;
  }
  return 0;
}
