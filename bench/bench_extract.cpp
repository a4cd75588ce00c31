// Isosurface extraction speed and memory against OpenVDB, measured in one run
// on the same loaded grid (issue 3: "Speed and memory").
//
//   bench_extract [VOLUME] [--iso V] [--repeat R] [--min-component-vertices N]
//
// VOLUME defaults to ../shared/data/volumes/miranda_256x256x256.nrrd at iso
// 1.5 (any read_volume() input works, e.g. builtin:mixing:256 --iso 0). The
// phases run in this order, each with its own peak resident memory (VmHWM
// is reset between phases through /proc/self/clear_refs), so OpenVDB's
// allocations never count against isowave's:
//   1. load the volume;
//   2. isowave contour_volume() (best of R runs), peak memory;
//   3. with --min-component-vertices N: the full extract_isosurface() with the
//      clean-up and its topology report;
//   4. OpenVDB tools::copyFromDense + tools::volumeToMesh (adaptivity 0) on the
//      same values (best of R runs).
// Prints the time ratio isowave / OpenVDB (target <= 1.0) and the peak
// against the target volume bytes + 2 x output mesh bytes + 64 MB.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/error.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kMiB = 1024.0 * 1024.0;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Peak resident set size of this process in bytes (VmHWM), or 0 if unknown.
double peak_rss_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atof(line.c_str() + 6) * 1024.0;
  return 0;
}
double current_rss_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atof(line.c_str() + 6) * 1024.0;
  return 0;
}
// Resets VmHWM to the current RSS (Linux >= 4.0); false if not possible.
bool reset_peak_rss() {
  std::FILE* file = std::fopen("/proc/self/clear_refs", "w");
  if (!file) return false;
  const bool ok = std::fputs("5", file) >= 0;
  return std::fclose(file) == 0 && ok;
}

double mesh_bytes(const isowave::PolygonMesh& mesh) {
  return static_cast<double>(mesh.positions.size() * sizeof(isowave::Vec3) +
                             mesh.face_vertices.size() * sizeof(std::uint32_t) +
                             mesh.face_offsets.size() * sizeof(std::uint32_t) + mesh.sharp.size());
}

// Records how long each stage of extract_isosurface() takes.
class StageTimer : public isowave::ProgressSink {
 public:
  void begin_stage(std::string_view name) override {
    name_ = name;
    start_ = Clock::now();
  }
  void end_stage() override {
    text_ += (text_.empty() ? "" : ", ") + name_ + " " + std::to_string(seconds_since(start_)).substr(0, 5) + " s";
  }
  const std::string& text() const { return text_; }

 private:
  std::string name_, text_;
  Clock::time_point start_;
};


struct BenchOptions {
  std::string path = std::string(ISOWAVE_SHARED_DATA_DIR) + "/volumes/miranda_256x256x256.nrrd";
  double iso = 1.5;
  int repeat = 3;                          // >= 1
  std::size_t min_component_vertices = 0;  // 0: no clean-up phase
};

// Exits with 2 and the usage on an unknown option.
BenchOptions parse_options(int argc, char** argv) {
  BenchOptions o;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--iso" && a + 1 < argc)
      o.iso = std::atof(argv[++a]);
    else if (arg == "--repeat" && a + 1 < argc)
      o.repeat = std::max(1, std::atoi(argv[++a]));
    else if (arg == "--min-component-vertices" && a + 1 < argc)
      o.min_component_vertices = std::strtoull(argv[++a], nullptr, 10);
    else if (!arg.empty() && arg[0] != '-')
      o.path = arg;
    else {
      std::fprintf(stderr, "usage: bench_extract [VOLUME] [--iso V] [--repeat R] [--min-component-vertices N]\n");
      std::exit(2);
    }
  }
  return o;
}

// Peak resident memory of each phase: VmHWM reset before it where the kernel
// allows, else the whole run so far.
struct PeakMemory {
  bool can_reset = reset_peak_rss();
  double baseline = current_rss_bytes();  // before the load, bytes
  // Starts a phase; returns the resident bytes at its start.
  double begin_phase() const {
    if (can_reset) reset_peak_rss();
    return current_rss_bytes();
  }
};

// 1. Load.
isowave::Volume load(const BenchOptions& o, const PeakMemory& memory) {
  const auto start = Clock::now();
  isowave::Volume volume = isowave::read_volume(o.path);
  const double load_seconds = seconds_since(start);
  const double volume_bytes = static_cast<double>(volume.values.size() * sizeof(float));
  std::printf("volume      %s: %zu x %zu x %zu (%s), %.1f MiB as float\n", o.path.c_str(), volume.dims[0],
              volume.dims[1], volume.dims[2], isowave::to_string(volume.source_type), volume_bytes / kMiB);
  std::printf("load        %.3f s, peak RSS %.1f MiB\n", load_seconds, (peak_rss_bytes() - memory.baseline) / kMiB);
  return volume;
}

// 2. isowave contouring, best of --repeat runs; returns its time in s.
double time_contour(const isowave::Volume& volume, const BenchOptions& o, const PeakMemory& memory) {
  if (memory.can_reset) reset_peak_rss();
  double best = 1e30;
  std::size_t vertices = 0, triangles = 0;
  double output_bytes = 0;
  for (int r = 0; r < o.repeat; ++r) {
    const auto start = Clock::now();
    isowave::PolygonMesh mesh = isowave::contour_volume(volume, o.iso);
    best = std::min(best, seconds_since(start));
    vertices = mesh.vertex_count();
    triangles = mesh.face_count();
    output_bytes = mesh_bytes(mesh);
  }
  const double peak = peak_rss_bytes() - memory.baseline;
  const double volume_bytes = static_cast<double>(volume.values.size() * sizeof(float));
  const double target = volume_bytes + 2 * output_bytes + 64 * kMiB;
  std::printf("isowave     contour at iso %g: %zu vertices, %zu triangles, %.3f s (best of %d)\n", o.iso, vertices,
              triangles, best, o.repeat);
  std::printf("isowave     peak RSS %.1f MiB (%s), target volume %.1f + 2 x mesh %.1f + 64 = %.1f MiB: %s\n",
              peak / kMiB, memory.can_reset ? "load + contour" : "whole run so far", volume_bytes / kMiB,
              output_bytes / kMiB, target / kMiB, peak <= target ? "met" : "MISSED");
  return best;
}

// 3. The full extraction with the clean-up and the report.
void time_cleanup(const isowave::Volume& volume, const BenchOptions& o, const PeakMemory& memory) {
  const double before = memory.begin_phase();
  isowave::IsosurfaceOptions options;
  options.iso = o.iso;
  options.min_component_vertices = o.min_component_vertices;
  StageTimer stages;
  const auto start = Clock::now();
  const isowave::Isosurface result = isowave::extract_isosurface(volume, options, stages);
  const double seconds = seconds_since(start);
  const isowave::IsosurfaceReport& report = result.report;
  std::printf(
      "clean-up    --min-component-vertices %zu: %.3f s (contour + clean-up + two topology reports), "
      "peak RSS above the loaded volume %.1f MiB\n",
      o.min_component_vertices, seconds, (peak_rss_bytes() - before) / kMiB);
  std::printf("            stages: %s\n", stages.text().c_str());
  std::printf("            before: %zu vertices, %zu components, genus %lld, %zu boundary loops, area %.6g\n",
              report.before.vertices, report.before.components, report.before.genus, report.before.boundary_loops,
              report.before.area);
  std::printf("            dropped %zu components, %zu vertices, %zu triangles, area %.6g\n",
              report.dropped_components, report.dropped_vertices, report.dropped_triangles, report.dropped_area);
  std::printf("            after:  %zu vertices, %zu components, genus %lld, %zu boundary loops, area %.6g\n",
              report.after.vertices, report.after.components, report.after.genus, report.after.boundary_loops,
              report.after.area);
}

// 4. OpenVDB on the same values, best of --repeat runs; returns its time in s.
double time_openvdb(const isowave::Volume& volume, const BenchOptions& o, const PeakMemory& memory) {
  openvdb::initialize();
  const double before = memory.begin_phase();
  const openvdb::CoordBBox box(openvdb::Coord(0, 0, 0), openvdb::Coord(static_cast<int>(volume.dims[0]) - 1,
                                                                       static_cast<int>(volume.dims[1]) - 1,
                                                                       static_cast<int>(volume.dims[2]) - 1));
  double best = 1e30, copy_seconds = 0;
  std::size_t points_count = 0, polygons = 0;
  for (int r = 0; r < o.repeat; ++r) {
    const auto start = Clock::now();
    openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, const_cast<float*>(volume.values.data()));
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    openvdb::tools::copyFromDense(dense, *grid, 0.0f);
    const double copied = seconds_since(start);
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> tris;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*grid, points, tris, quads, o.iso, 0.0);
    const double seconds = seconds_since(start);
    if (seconds < best) {
      best = seconds;
      copy_seconds = copied;
    }
    points_count = points.size();
    polygons = tris.size() + quads.size();
  }
  std::printf(
      "openvdb     copyFromDense %.3f s + volumeToMesh %.3f s = %.3f s (best of %d): %zu points, %zu "
      "polygons, peak RSS above the loaded volume %.1f MiB\n",
      copy_seconds, best - copy_seconds, best, o.repeat, points_count, polygons, (peak_rss_bytes() - before) / kMiB);
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  const BenchOptions options = parse_options(argc, argv);
  if (options.path.rfind("builtin:", 0) != 0 && !std::ifstream(options.path)) {
    std::printf("SKIP: %s not found (../shared/data absent)\n", options.path.c_str());
    return 0;
  }
  try {
    const PeakMemory memory;
    const isowave::Volume volume = load(options, memory);
    const double isowave_seconds = time_contour(volume, options, memory);
    if (options.min_component_vertices > 0) time_cleanup(volume, options, memory);
    const double openvdb_seconds = time_openvdb(volume, options, memory);
    std::printf("ratio       isowave / OpenVDB = %.3f (target <= 1.0)\n", isowave_seconds / openvdb_seconds);
  } catch (const isowave::Error& error) {
    std::fprintf(stderr, "bench_extract: %s\n", error.what());
    return 1;
  }
  return 0;
}
