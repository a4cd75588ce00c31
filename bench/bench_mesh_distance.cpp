// Distance from the vertices of one mesh to the surface of another (CGAL AABB
// tree): the error measure shared by isowave and Draco in
// bench/draco_rate_distortion.sh, where vertex correspondence is lost.
//
// usage: bench_mesh_distance MESH REFERENCE [CELL]
// prints: rms max   (in percent of CELL, default 1)
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
    const isowave::SurfaceDistance distance(reference);
    const std::vector<double> d = distance.distances(mesh.positions);
    double sum = 0, max = 0;
    for (double x : d) {
      sum += x * x;
      max = std::max(max, x);
    }
    std::printf("%.4f %.4f\n", 100 * std::sqrt(sum / static_cast<double>(d.size())) / cell, 100 * max / cell);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench_mesh_distance: %s\n", error.what());
    return 1;
  }
  return 0;
}
