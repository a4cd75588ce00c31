// Wavelet transform speed and memory against OpenSubdiv (issue: foundation and
// transform). Builds a hierarchy of about 1.2 million fine vertices and times,
// in one run: analysis, synthesis, and OpenSubdiv's Far::PrimvarRefiner
// refining the same base mesh to the same level (double positions). Prints the
// ratios analysis/opensubdiv and synthesis/opensubdiv (target <= 1.5) and the
// hierarchy's bytes per fine vertex (target <= 200).
//
// usage: bench_transform [MESH LEVELS]   (default: a generated triangulated
//        torus at 4 levels, and the shared rocker arm at 3 levels if present)
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh_io.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/wavelet_transform.h"

using namespace isowave;
namespace Far = OpenSubdiv::Far;

namespace {

double median_seconds(int repetitions, const std::function<void()>& setup, const std::function<void()>& work) {
  std::vector<double> times;
  for (int r = 0; r < repetitions; ++r) {
    setup();
    const auto start = std::chrono::steady_clock::now();
    work();
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

PolygonMesh triangulated_torus(int nx, int ny) {
  PolygonMesh mesh;
  const double pi = std::acos(-1.0);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double a = 2 * pi * i / nx, b = 2 * pi * j / ny;
      mesh.positions.push_back({(3 + std::cos(b)) * std::cos(a), (3 + std::cos(b)) * std::sin(a), std::sin(b)});
    }
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>((j % ny) * nx + (i % nx)); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      mesh.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.add_face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return mesh;
}

struct Point {
  Vec3 p;
  void Clear() { p = Vec3{}; }
  void AddWithWeight(const Point& src, double weight) { p += weight * src.p; }
};

double opensubdiv_seconds(const PolygonMesh& base, int levels, int repetitions) {
  std::vector<int> sizes(base.face_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) sizes[f] = static_cast<int>(base.face_size(f));
  std::vector<int> indices(base.face_vertices.begin(), base.face_vertices.end());
  Far::TopologyDescriptor descriptor;
  descriptor.numVertices = static_cast<int>(base.vertex_count());
  descriptor.numFaces = static_cast<int>(base.face_count());
  descriptor.numVertsPerFace = sizes.data();
  descriptor.vertIndicesPerFace = indices.data();
  OpenSubdiv::Sdc::Options options;
  options.SetVtxBoundaryInterpolation(OpenSubdiv::Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(
      Factory::Create(descriptor, Factory::Options(OpenSubdiv::Sdc::SCHEME_CATMARK, options)));
  refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(levels));
  std::vector<Point> points(static_cast<std::size_t>(refiner->GetNumVerticesTotal()));
  Far::PrimvarRefinerReal<double> primvar(*refiner);
  return median_seconds(
      repetitions, [&] { for (std::size_t v = 0; v < base.vertex_count(); ++v) points[v].p = base.positions[v]; },
      [&] {
        Point* source = points.data();
        for (int level = 1; level <= levels; ++level) {
          Point* destination = source + refiner->GetLevel(level - 1).GetNumVertices();
          primvar.Interpolate(level, source, destination);
          source = destination;
        }
      });
}

void run(const std::string& name, const PolygonMesh& base, int levels) {
  const int repetitions = 7;
  const auto build_start = std::chrono::steady_clock::now();
  const SubdivisionHierarchy hierarchy(base, levels);
  const double build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  const std::size_t fine = hierarchy.fine_vertex_count();

  // A smooth fine surface with noise, as fitting would produce.
  std::vector<Vec3> fine_points = subdivide(hierarchy, base.positions);
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 1e-3);
  for (Vec3& p : fine_points) p += Vec3{noise(rng), noise(rng), noise(rng)};

  std::vector<Vec3> data;
  const auto time_transform = [&](int threads, double& analysis, double& synthesis) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    analysis = median_seconds(repetitions, [&] { data = fine_points; }, [&] { analyze(hierarchy, data); });
    std::vector<Vec3> coefficients = fine_points;
    analyze(hierarchy, coefficients);
    synthesis = median_seconds(repetitions, [&] { data = coefficients; }, [&] { synthesize(hierarchy, data); });
  };
  double analysis1, synthesis1, analysis2, synthesis2;
  time_transform(1, analysis1, synthesis1);
  time_transform(2, analysis2, synthesis2);
  const double opensubdiv = opensubdiv_seconds(base, levels, repetitions);

  double error = 0;
  for (std::size_t i = 0; i < fine; ++i) error = std::max(error, norm(data[i] - fine_points[i]));

  std::printf("\n== %s: %zu base vertices, %d levels, %zu fine vertices\n", name.c_str(), base.vertex_count(), levels, fine);
  std::printf("hierarchy build (OpenSubdiv topology + index arrays): %8.1f ms\n", 1e3 * build_seconds);
  std::printf("opensubdiv PrimvarRefiner (1 thread):                 %8.1f ms\n", 1e3 * opensubdiv);
  std::printf("analysis   1 thread %7.1f ms   2 threads %7.1f ms\n", 1e3 * analysis1, 1e3 * analysis2);
  std::printf("synthesis  1 thread %7.1f ms   2 threads %7.1f ms\n", 1e3 * synthesis1, 1e3 * synthesis2);
  std::printf("analysis / opensubdiv  = %.2f (2 threads), %.2f (1 thread)   target <= 1.5\n", analysis2 / opensubdiv,
              analysis1 / opensubdiv);
  std::printf("synthesis / opensubdiv = %.2f (2 threads), %.2f (1 thread)   target <= 1.5\n", synthesis2 / opensubdiv,
              synthesis1 / opensubdiv);
  std::printf("per 1.2 M fine vertices: analysis %.1f ms, synthesis %.1f ms (2 threads)   target <= 100 ms each\n",
              1e3 * analysis2 * 1.2e6 / double(fine), 1e3 * synthesis2 * 1.2e6 / double(fine));
  std::printf("hierarchy memory: %.1f MB = %.1f bytes per fine vertex (target <= 200); coefficients %zu bytes each\n",
              double(hierarchy.memory_bytes()) / 1e6, double(hierarchy.memory_bytes()) / double(fine), sizeof(Vec3));
  std::printf("round trip max error: %.3g\n", error);
}

}  // namespace

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  try {
    if (argc == 3) {
      PolygonMesh mesh = read_mesh(argv[1]);
      remove_unreferenced_vertices(mesh);
      run(argv[1], mesh, std::atoi(argv[2]));
      return 0;
    }
    run("generated triangulated torus 56 x 54", triangulated_torus(56, 54), 4);
    const std::string rocker = std::string(ISOWAVE_SHARED_DATA_DIR) + "/meshes/rocker_arm_genus1.obj";
    if (std::ifstream(rocker)) {
      PolygonMesh mesh = read_mesh(rocker);
      run("shared rocker_arm_genus1.obj", mesh, 3);
    } else {
      std::printf("\n(shared data absent: skipped the rocker arm)\n");
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench_transform: %s\n", error.what());
    return 1;
  }
  return 0;
}
