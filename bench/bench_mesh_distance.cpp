// Distances between two meshes (CGAL AABB trees): the error measure shared
// by isowave and Draco in bench/draco_rate_distortion.sh, where vertex
// correspondence is lost. Both ways: from the vertices of MESH to the surface
// of REFERENCE (how far off what was decoded lies) and from the vertices of
// REFERENCE to the surface of MESH (how much of the reference it covers; a
// fit that left parts of the surface out shows only here).
//
// usage: bench_mesh_distance MESH REFERENCE [CELL]
// prints: rms max reverse_rms reverse_max   (in percent of CELL, default 1)
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/surface_distance.h"

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_mesh_distance MESH REFERENCE [CELL]\n");
    return 2;
  }
  try {
    const isowave::PolygonMesh mesh = isowave::read_mesh(argv[1]);
    const isowave::PolygonMesh reference = isowave::read_mesh(argv[2]);
    const double cell = argc > 3 ? std::atof(argv[3]) : 1.0;
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
    rms_and_max(isowave::SurfaceDistance(mesh).distances(reference.positions));
    std::printf("\n");
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench_mesh_distance: %s\n", error.what());
    return 1;
  }
  return 0;
}
