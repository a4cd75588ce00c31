// Base-mesh construction (paper Sec. 4.1) on the miranda isosurface, timed
// side by side with CGAL's Surface_mesh_simplification::edge_collapse
// (default Lindstrom-Turk cost and placement) stopped at the same vertex count.
//
//   bench_simplify [--volume PATH] [--iso X] [--min-component-vertices N]
//                  [--target-vertices N] [--skip-cgal] [--compare-openmesh]
//                  [--mesh PATH] [--save-mesh PATH] [--skip-distance]
//                  [--no-edge-removal] [--serial] [--eager-stencil] [--batch-factor F]
//                  [--surface-map]
//
// Prints the isowave report, peak memory during simplify() in bytes per input
// vertex (Linux VmHWM, reset before the call), CGAL's time and the ratio.
// --compare-openmesh also times the collapse-evaluation kernel (legality
// topology checks, ring gathering, (4.1)-(4.2)) over every edge, once on the
// corner table used by isowave and once on OpenMesh's TriMesh, single-threaded.
// --mesh reads a triangle mesh instead of extracting one; --save-mesh writes
// the extracted one (to repeat runs without the extraction). --skip-distance
// leaves out the second, untimed simplify() that measures the surface distance.
// --serial turns off the two-thread collapse phase (SimplifyOptions::parallel);
// --eager-stencil re-evaluates whole stencils (SimplifyOptions::lazy_stencil);
// --batch-factor sets SimplifyOptions::batch_error_factor (1: the paper's order).
// --surface-map runs simplify() once more building the MAPS map
// (SurfaceMapping::Build) and prints its time and peak against the plain run
// (issue #33: the map may add at most the simplification's own time).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include <sys/resource.h>
#include <unistd.h>

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/core/peak_memory.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "isowave/simplify/collapse_error.h"
#include "isowave/simplify/collapse_mesh.h"
#include "isowave/simplify/simplify.h"

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// CPU seconds this process has used (all threads, user + system).
double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}
// CPU seconds the hypervisor has taken from this virtual machine (the
// "steal" column of /proc/stat, all CPUs; 0 where the kernel does not say):
// on this machine the main cause of run-to-run spread in wall time.
double steal_seconds() {
  std::ifstream stat("/proc/stat");
  std::string cpu;
  double ticks[8] = {};
  stat >> cpu;
  for (double& t : ticks) stat >> t;
  return cpu == "cpu" ? ticks[7] / double(sysconf(_SC_CLK_TCK)) : 0.0;
}

using Kernel = CGAL::Simple_cartesian<double>;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

SurfaceMesh to_cgal(const isowave::PolygonMesh& mesh) {
  SurfaceMesh result;
  result.reserve(mesh.vertex_count(), mesh.face_vertices.size() / 2 + mesh.vertex_count(), mesh.face_count());
  for (const isowave::Vec3& p : mesh.positions) result.add_vertex(Kernel::Point_3(p.x, p.y, p.z));
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* v = mesh.face_begin(f);
    result.add_face(SurfaceMesh::Vertex_index(v[0]), SurfaceMesh::Vertex_index(v[1]), SurfaceMesh::Vertex_index(v[2]));
  }
  return result;
}

// Stops CGAL's edge_collapse when the mesh has at most `target` vertices.
struct VertexCountStop {
  const SurfaceMesh* mesh;
  std::size_t target;
  template <typename Cost, typename Profile>
  bool operator()(const Cost&, const Profile&, std::size_t, std::size_t) const {
    return mesh->number_of_vertices() <= target;
  }
};

// FNV-1a over the base mesh's coordinates (bit patterns), faces and sharp
// flags: equal fingerprints mean an identical result, which is how a speed-up
// of the simplifier is checked to leave the algorithm unchanged.
std::uint64_t fingerprint(const isowave::PolygonMesh& mesh) {
  std::uint64_t hash = 1469598103934665603ull;
  const auto add = [&](const void* data, std::size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  };
  add(mesh.positions.data(), mesh.positions.size() * sizeof(isowave::Vec3));
  add(mesh.face_vertices.data(), mesh.face_vertices.size() * sizeof(std::uint32_t));
  add(mesh.face_offsets.data(), mesh.face_offsets.size() * sizeof(mesh.face_offsets[0]));
  add(mesh.sharp.data(), mesh.sharp.size() * sizeof(mesh.sharp[0]));
  return hash;
}

// --- Evaluation kernel on OpenMesh, mirroring CollapseMesh::evaluate() ---
struct OmTraits : OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
};
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<OmTraits>;

double openmesh_evaluate_all(const TriMesh& mesh, std::size_t& legal) {
  double sum = 0;
  legal = 0;
  isowave::Vec3 crosses[128];
  for (TriMesh::EdgeHandle e : mesh.edges()) {
    const TriMesh::HalfedgeHandle h = mesh.halfedge_handle(e, 0);
    const TriMesh::VertexHandle vi = mesh.from_vertex_handle(h), vj = mesh.to_vertex_handle(h);
    const bool boundary_edge = mesh.is_boundary(e);
    const bool bi = mesh.is_boundary(vi), bj = mesh.is_boundary(vj);
    if (!boundary_edge && bi && bj) continue;
    const int valence = int(mesh.valence(vi)) + int(mesh.valence(vj)) - (boundary_edge ? 3 : 4);
    if (valence > 8 || valence < ((bi || bj) ? 2 : 3)) continue;
    // Link condition.
    int common = 0;
    for (TriMesh::ConstVertexVertexIter a = mesh.cvv_iter(vi); a.is_valid(); ++a)
      for (TriMesh::ConstVertexVertexIter b = mesh.cvv_iter(vj); b.is_valid(); ++b)
        if (*a == *b) ++common;
    if (common != (boundary_edge ? 1 : 2)) continue;
    const TriMesh::Point& pi = mesh.point(vi);
    const TriMesh::Point& pj = mesh.point(vj);
    const isowave::Vec3 p{(pi[0] + pj[0]) / 2, (pi[1] + pj[1]) / 2, (pi[2] + pj[2]) / 2};
    const TriMesh::FaceHandle f0 = mesh.face_handle(h), f1 = mesh.face_handle(mesh.opposite_halfedge_handle(h));
    std::size_t k = 0;
    bool ok = true;
    for (TriMesh::VertexHandle centre : {vi, vj}) {
      const TriMesh::Point& c = mesh.point(centre);
      for (TriMesh::ConstVertexOHalfedgeIter out = mesh.cvoh_iter(centre); out.is_valid(); ++out) {
        const TriMesh::FaceHandle f = mesh.face_handle(*out);
        if (!f.is_valid() || f == f0 || f == f1) continue;
        const TriMesh::Point& w0 = mesh.point(mesh.to_vertex_handle(*out));
        const TriMesh::Point& w1 = mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(*out)));
        const isowave::Vec3 a{w0[0] - p.x, w0[1] - p.y, w0[2] - p.z}, b{w1[0] - p.x, w1[1] - p.y, w1[2] - p.z};
        const isowave::Vec3 oa{w0[0] - c[0], w0[1] - c[1], w0[2] - c[2]}, ob{w1[0] - c[0], w1[1] - c[1], w1[2] - c[2]};
        const isowave::Vec3 n = isowave::cross(a, b), o = isowave::cross(oa, ob);
        if (isowave::dot(n, o) < 0) ok = false;
        crosses[k++] = n;
      }
    }
    if (!ok || k == 0) continue;
    ++legal;
    sum += isowave::simplify::collapse_error_terms({pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]}, crosses, k).delta_e;
  }
  return sum;
}

void compare_openmesh(const isowave::PolygonMesh& triangles) {
  using namespace isowave::simplify;
  CollapseMesh corner_table(triangles);
  FanCache cache;
  auto start = Clock::now();
  std::size_t legal = 0;
  double sum = 0;
  for (std::uint32_t e = 0; e < corner_table.edge_slots(); ++e) {
    const Evaluation evaluation = corner_table.evaluate(e, cache);
    if (evaluation.legality == Legality::Legal) {
      ++legal;
      sum += evaluation.delta_error;
    }
  }
  const double corner_seconds = seconds(start);
  std::printf("evaluation kernel, corner table: %.3f s for %u edges (%zu legal, checksum %.6g)\n", corner_seconds,
              corner_table.edge_slots(), legal, sum);

  TriMesh mesh;
  for (const isowave::Vec3& p : triangles.positions) mesh.add_vertex(TriMesh::Point(p.x, p.y, p.z));
  for (std::size_t f = 0; f < triangles.face_count(); ++f) {
    const std::uint32_t* v = triangles.face_begin(f);
    mesh.add_face(TriMesh::VertexHandle(int(v[0])), TriMesh::VertexHandle(int(v[1])), TriMesh::VertexHandle(int(v[2])));
  }
  start = Clock::now();
  std::size_t om_legal = 0;
  const double om_sum = openmesh_evaluate_all(mesh, om_legal);
  const double om_seconds = seconds(start);
  std::printf("evaluation kernel, OpenMesh TriMesh: %.3f s (%zu legal, checksum %.6g); OpenMesh / corner table = %.2f\n",
              om_seconds, om_legal, om_sum, om_seconds / corner_seconds);
}

}  // namespace

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  std::string volume_path = std::string(ISOWAVE_SHARED_DATA_DIR) + "/volumes/miranda_256x256x256.nrrd";
  double iso = 1.5;
  std::size_t min_component_vertices = 0, target_vertices = 0;
  bool run_cgal = true, openmesh = false, distance = true, edge_removal = true, parallel = true, lazy_stencil = true,
       surface_map = false;
  double batch_factor = isowave::simplify::SimplifyOptions{}.batch_error_factor;
  std::string mesh_path, save_path;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--volume") volume_path = value();
    else if (arg == "--iso") iso = std::stod(value());
    else if (arg == "--min-component-vertices") min_component_vertices = std::stoul(value());
    else if (arg == "--target-vertices") target_vertices = std::stoul(value());
    else if (arg == "--skip-cgal") run_cgal = false;
    else if (arg == "--skip-distance") distance = false;
    else if (arg == "--no-edge-removal") edge_removal = false;
    else if (arg == "--serial") parallel = false;
    else if (arg == "--eager-stencil") lazy_stencil = false;
    else if (arg == "--batch-factor") batch_factor = std::stod(value());
    else if (arg == "--mesh") mesh_path = value();
    else if (arg == "--save-mesh") save_path = value();
    else if (arg == "--compare-openmesh") openmesh = true;
    else if (arg == "--surface-map") surface_map = true;
    else {
      std::fprintf(stderr, "unknown argument %s\n", arg.c_str());
      return 2;
    }
  }
  try {
    auto start = Clock::now();
    isowave::PolygonMesh triangles;
    if (!mesh_path.empty()) {
      triangles = isowave::read_mesh(mesh_path);
      std::printf("mesh %s: %zu vertices, %zu triangles (%.2f s)\n", mesh_path.c_str(), triangles.vertex_count(),
                  triangles.face_count(), seconds(start));
    } else {
      const isowave::Volume volume = isowave::read_volume(volume_path);
      isowave::IsosurfaceOptions options;
      options.iso = iso;
      options.min_component_vertices = min_component_vertices;
      isowave::Isosurface surface = isowave::extract_isosurface(volume, options);
      triangles = std::move(surface.mesh);
      std::printf("isosurface of %s at %g (min component vertices %zu): %zu vertices, %zu triangles, "
                  "%zu components, genus %lld, %zu boundary loops (%.2f s)\n",
                  volume_path.c_str(), iso, min_component_vertices, triangles.vertex_count(), triangles.face_count(),
                  surface.report.after.components, surface.report.after.genus, surface.report.after.boundary_loops,
                  seconds(start));
    }
    if (!save_path.empty()) {
      isowave::MeshWriteOptions write_options;
      write_options.double_precision = true;
      isowave::write_mesh(save_path, triangles, write_options);
    }
    if (openmesh) compare_openmesh(triangles);

    isowave::simplify::SimplifyOptions options;
    options.target_vertices = target_vertices;
    options.compute_distance = false;  // timed separately below
    options.edge_removal = edge_removal;
    options.parallel = parallel;
    options.lazy_stencil = lazy_stencil;
    options.batch_error_factor = batch_factor;
    isowave::reset_peak_memory();
    const double peak_before = isowave::peak_memory_bytes();
    const double cpu_before = cpu_seconds(), steal_before = steal_seconds();
    start = Clock::now();
    isowave::simplify::SimplifyResult result = isowave::simplify::simplify(triangles, options);
    const double isowave_seconds = seconds(start);
    const double cpu = cpu_seconds() - cpu_before, steal = steal_seconds() - steal_before;
    const double peak = isowave::peak_memory_bytes();
    std::printf("%s", isowave::simplify::format_report(result.report).c_str());
    const double vertices = double(triangles.vertex_count());
    std::printf("isowave simplify: %.3f s; CPU %.2f s; %.2f CPU s stolen by the hypervisor meanwhile; peak memory "
                "%.0f MB = %.0f bytes per input vertex (input mesh included; %.0f MB resident before the call)\n",
                isowave_seconds, cpu, steal, peak / 1e6, peak / vertices, peak_before / 1e6);
    std::printf("base mesh fingerprint: %016llx\n", static_cast<unsigned long long>(fingerprint(result.base)));
    if (surface_map) {
      isowave::simplify::SimplifyOptions mapped = options;
      mapped.surface_map = isowave::simplify::SurfaceMapping::Build;
      isowave::reset_peak_memory();
      start = Clock::now();
      const isowave::simplify::SimplifyResult with_map = isowave::simplify::simplify(triangles, mapped);
      const double map_seconds = seconds(start);
      std::printf("with the surface map: %.3f s (%.2fx the plain run; the map adds %.2fx its time), peak %.0f MB; "
                  "same base mesh: %s\n",
                  map_seconds, map_seconds / isowave_seconds, map_seconds / isowave_seconds - 1.0, isowave::peak_memory_bytes() / 1e6,
                  fingerprint(with_map.base) == fingerprint(result.base) ? "yes" : "NO");
    }
    const isowave::TopologySummary before = isowave::summarize_topology(triangles);
    const isowave::TopologySummary after = isowave::summarize_topology(result.base);
    std::printf("topology preserved: genus %lld -> %lld, components %zu -> %zu, boundary loops %zu -> %zu\n",
                before.genus, after.genus, before.components, after.components, before.boundary_loops,
                after.boundary_loops);

    if (distance) {
    isowave::simplify::SimplifyOptions collapse_only = options;
    collapse_only.edge_removal = false;
    collapse_only.compute_distance = true;
    collapse_only.target_vertices = result.report.vertices_after_collapse;
    const isowave::simplify::SimplifyResult with_distance = isowave::simplify::simplify(triangles, collapse_only);
    std::printf("distance input vertices -> base surface (triangles, before edge removal): max %.4g, rms %.4g "
                "(%.2f s)\n",
                with_distance.report.distance_max, with_distance.report.distance_rms,
                with_distance.report.seconds_distance);
    }

    if (run_cgal) {
      SurfaceMesh mesh = to_cgal(triangles);
      const std::size_t target = result.report.vertices_after_collapse;
      start = Clock::now();
      const int removed =
          CGAL::Surface_mesh_simplification::edge_collapse(mesh, VertexCountStop{&mesh, target});
      const double cgal_seconds = seconds(start);
      std::printf("CGAL edge_collapse (Lindstrom-Turk, stop at %zu vertices): %d edges collapsed, %zu vertices, "
                  "%.3f s\n",
                  target, removed, static_cast<std::size_t>(mesh.number_of_vertices()), cgal_seconds);
      std::printf("ratio CGAL / isowave simplify: %.2f\n", cgal_seconds / isowave_seconds);
    }
  } catch (const isowave::Error& error) {
    std::fprintf(stderr, "bench_simplify: %s\n", error.what());
    return 1;
  }
  return 0;
}
