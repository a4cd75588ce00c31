// Signed-distance field and shrink-wrap speed and quality (issue 5), with
// OpenVDB's tools::meshToLevelSet (half width 3) on the extracted mesh timed in
// the same run as the peer for the distance field.
//
// Default: the miranda isosurface (iso 1.5, min_component_vertices 50), its
// base mesh simplified as far as topology allows, L = 3, 2 threads, distance
// band 3 cells. Targets: distance field <= 1.5 s and <= 1.0x OpenVDB;
// shrink-wrap <= 5 s (no peer named; its time against OpenVDB's in the same
// run is printed too, as the host's speed drifts). Prints the quality report
// per level and peak memory.
//
// usage: bench_fit [INPUT ISO] [--min-component N] [--base-vertices N]
//                  [--levels L] [--threads T] [--band K] [--no-quality]
//                  [--distance-only] [--iterations N] [--final-iterations N]
//                  [--reach R] [--min-reach C] [--weight W] [--no-correction] [--no-coverage-pull]
//                  [--pull-max-edge C] [--rmse-spread]
//                  [--correction-cells C] [--untangle N] [--coarse-untangle N] [--unfold N]
//                  [--unfold-limit FRACTION] [--base FILE]
//                  [--write-base FILE] [--no-peer] [--repeat N] [--final-quality] [--rmse]
//                  [--droplet-vertices N] [--no-nearest-correction]
//   INPUT is a volume file or builtin:NAME[:N]; --base-vertices 0 simplifies
//   as far as the rules allow (default). --base reads the base mesh instead of
//   simplifying (e.g. one saved with --write-base: repeatable runs while the
//   simplifier changes); --no-peer skips OpenVDB and the whole-grid distance;
//   --repeat times the distance field and the shrink-wrap N times (noisy
//   shared machines); --final-quality measures level L only; --rmse runs the
//   wavelet analysis of the fit and prints the paper's Table 1 RMSE rows
//   (unquantized coefficients, importance-weighted truncation), --rmse-spread
//   also each row's error quantiles and the share of its largest 1%;
//   --pull-max-edge sets the coverage pull's edge limit (0.5: level L only).
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/global_control.h>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/error.h"
#include "isowave/codec/importance.h"
#include "isowave/core/mesh_io.h"
#include "isowave/fit/fit_quality.h"
#include "isowave/fit/shrink_wrap.h"
#include "isowave/core/binned_surface_distance.h"
#include "isowave/fit/trilinear.h"
#include "isowave/pipeline/prepare.h"
#include "isowave/simplify/simplify.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/wavelet_transform.h"

using namespace isowave;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// User + system time of the process: less sensitive than wall time to other
// work on a shared machine.
double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) + 1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

double peak_megabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

void print_quality(const FitQuality& q) {
  std::printf(
      "  level %d: %zu vertices, %zu faces | isosurface rms %.4f max %.3f cell (%zu over 1) | to extracted rms %.4f "
      "max %.3f cell (%zu over 0.5) | coverage rms %.3f p99 %.3f max %.3f cell | folded %zu (%.4f%%) | area/patch "
      "mean p1 %.2f median %.2f p99 %.2f (sd %.2f)%s\n",
      q.level, q.vertices, q.faces, q.isosurface_rms, q.isosurface_max, q.isosurface_far, q.surface_rms, q.surface_max,
      q.surface_far, q.coverage_rms, q.coverage_p99, q.coverage_max, q.folded_faces, 100 * q.folded_fraction,
      q.area_ratio_p1, q.area_ratio_median, q.area_ratio_p99, q.area_ratio_deviation,
      q.nonfinite_vertices ? " NON-FINITE" : "");
}


// What the command line asks for; the shrink-wrap's own options are parsed
// straight into `wrap` (keep_levels and surface are set when it runs).
struct BenchOptions {
  std::string input = std::string(ISOWAVE_SHARED_DATA_DIR) + "/volumes/miranda_256x256x256.nrrd";
  double iso = 1.5;
  std::size_t min_component = 50;
  std::size_t base_vertices = 0;  // 0: as far as the simplifier's rules allow
  int levels = 3;
  int threads = 2;
  double band = 3;  // distance band, cells
  bool quality = true;
  bool sdf_only = false;
  bool peer = true;
  bool final_quality_only = false;
  bool rmse = false;
  bool rmse_spread = false;
  std::string base_input, base_output;
  int repeat = 1;  // >= 1
  ShrinkWrapOptions wrap;
};

// Exits with 2 on a missing value or a wrong number of positional arguments.
BenchOptions parse_options(int argc, char** argv) {
  BenchOptions o;
  ShrinkWrapOptions& w = o.wrap;
  std::vector<std::string> positional;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    const auto next = [&]() -> std::string {
      if (a + 1 >= argc) {
        std::fprintf(stderr, "missing value for %s\n", arg.c_str());
        std::exit(2);
      }
      return argv[++a];
    };
    if (arg == "--min-component") o.min_component = std::stoul(next());
    else if (arg == "--base-vertices") o.base_vertices = std::stoul(next());
    else if (arg == "--levels") o.levels = std::stoi(next());
    else if (arg == "--threads") o.threads = std::stoi(next());
    else if (arg == "--band") o.band = std::stod(next());
    else if (arg == "--no-quality") o.quality = false;
    else if (arg == "--distance-only") o.sdf_only = true;
    else if (arg == "--no-correction") w.final_correction = false;
    else if (arg == "--no-coverage-pull") w.coverage_pull = false;
    else if (arg == "--pull-max-edge") w.pull_max_edge_cells = std::stod(next());
    else if (arg == "--weight") w.relaxation_weight = std::stod(next());
    else if (arg == "--correction-cells") w.correction_max_cells = std::stod(next());
    else if (arg == "--untangle") w.untangle_rounds = std::stoi(next());
    else if (arg == "--coarse-untangle") w.coarse_untangle_rounds = std::stoi(next());
    else if (arg == "--unfold") w.unfold_rounds = std::stoi(next());
    else if (arg == "--unfold-limit") w.unfold_max_folded_fraction = std::stod(next());
    else if (arg == "--droplet-vertices") w.droplet_vertices = std::stoul(next());
    else if (arg == "--no-nearest-correction") w.correction_from_nearest_point = false;
    else if (arg == "--reach") w.attraction.reach_edges = std::stod(next());
    else if (arg == "--min-reach") w.attraction.min_reach_cells = std::stod(next());
    else if (arg == "--iterations") w.iterations = std::stoi(next());
    else if (arg == "--final-iterations") w.final_level_iterations = std::stoi(next());
    else if (arg == "--base") o.base_input = next();
    else if (arg == "--write-base") o.base_output = next();
    else if (arg == "--no-peer") o.peer = false;
    else if (arg == "--repeat") o.repeat = std::max(1, std::stoi(next()));
    else if (arg == "--final-quality") o.final_quality_only = true;
    else if (arg == "--rmse") o.rmse = true;
    else if (arg == "--rmse-spread") o.rmse = o.rmse_spread = true;
    else positional.push_back(arg);
  }
  if (positional.size() == 2) {
    o.input = positional[0];
    o.iso = std::stod(positional[1]);
  } else if (!positional.empty()) {
    std::fprintf(stderr, "usage: bench_fit [INPUT ISO] [options]\n");
    std::exit(2);
  }
  return o;
}

PrepareOptions prepare_options_for(const BenchOptions& o) {
  PrepareOptions p;
  p.extract.iso = o.iso;
  p.extract.min_component_vertices = o.min_component;
  p.distance_band_cells = o.band;
  return p;
}

// Reads the volume and extracts its isosurface (no distance field yet).
PreparedSurface load_and_extract(const BenchOptions& o, const PrepareOptions& prepare_options) {
  auto start = std::chrono::steady_clock::now();
  Volume loaded = load_volume(o.input, {});
  std::printf("%s: %zux%zux%zu, read in %.2f s, %d threads\n", o.input.c_str(), loaded.dims[0], loaded.dims[1],
              loaded.dims[2], seconds_since(start), o.threads);
  start = std::chrono::steady_clock::now();
  PreparedSurface prepared = extract_surface(std::move(loaded), prepare_options, o.input);
  const PolygonMesh& extracted = prepared.isosurface.mesh;
  std::printf("extracted: %zu vertices, %zu triangles, genus %lld, %zu components in %.2f s\n",
              extracted.vertex_count(), extracted.face_count(), prepared.isosurface.report.after.genus,
              prepared.isosurface.report.after.components, seconds_since(start));
  return prepared;
}

struct DistanceTimes {
  double band = 0;   // best of the runs, s
  double whole = 0;  // whole grid, s; 0 without the peer
};

// Our distance field: the narrow band the fit uses (--band, default 3 cells,
// OpenVDB's half width), left in prepared.distance, and with the peer, for
// reference, the whole grid.
DistanceTimes time_distance_field(PreparedSurface& prepared, const PrepareOptions& prepare_options,
                                  const BenchOptions& o) {
  DistanceTimes times;
  for (int run = 0; run < o.repeat; ++run) {
    const double cpu_start = cpu_seconds();
    const auto start = std::chrono::steady_clock::now();
    prepared.distance = surface_distance_field(prepared, prepare_options);
    const double seconds = seconds_since(start);
    if (o.repeat > 1) std::printf("  distance run %d: %.3f s (cpu %.3f s)\n", run + 1, seconds, cpu_seconds() - cpu_start);
    times.band = run == 0 ? seconds : std::min(times.band, seconds);
  }
  const SignedDistanceStatistics& ds = prepared.distance.statistics;
  std::printf("signed distance (band %g cells): %.3f s%s (seeding %.3f, propagation %.3f, finishing %.3f) | %zu nodes, "
              "%zu seeds, %zu pops, %zu updates, peak queue %zu, working set %.1f MB; %zu nodes on dropped "
              "components, %zu flipped\n",
              o.band, times.band, o.repeat > 1 ? " best" : "", ds.seconds_seeding, ds.seconds_propagation,
              ds.seconds_finishing, ds.nodes, ds.seed_nodes, ds.queue_pops, ds.updates, ds.peak_queue,
              double(ds.peak_bytes) / 1e6, ds.unseeded_crossing_nodes, ds.flipped_nodes);
  if (o.peer) {
    PrepareOptions whole_options = prepare_options;
    whole_options.distance_band_cells = 0;
    const auto start = std::chrono::steady_clock::now();
    const SignedDistanceField whole = surface_distance_field(prepared, whole_options);
    times.whole = seconds_since(start);
    std::printf("signed distance (whole grid): %.3f s | %zu pops, %zu updates, working set %.1f MB\n", times.whole,
                whole.statistics.queue_pops, whole.statistics.updates, double(whole.statistics.peak_bytes) / 1e6);
  }
  return times;
}

// The peer: OpenVDB's mesh-to-level-set on the extracted triangles; returns
// its time in s.
double time_openvdb(const PolygonMesh& extracted, const Volume& volume, const BenchOptions& o,
                    const DistanceTimes& distance) {
  openvdb::initialize();
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  points.reserve(extracted.vertex_count());
  for (const Vec3& p : extracted.positions) points.emplace_back(float(p.x), float(p.y), float(p.z));
  triangles.reserve(extracted.face_count());
  for (std::size_t f = 0; f < extracted.face_count(); ++f) {
    const std::uint32_t* t = extracted.face_begin(f);
    triangles.emplace_back(t[0], t[1], t[2]);
  }
  const openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(volume.cell_size());
  const auto start = std::chrono::steady_clock::now();
  const openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, 3.0f);
  const double peer_seconds = seconds_since(start);
  std::printf("OpenVDB meshToLevelSet (half width 3): %.3f s, %zu active voxels\n", peer_seconds,
              std::size_t(grid->activeVoxelCount()));
  std::printf("ratio signed distance / OpenVDB: band %g %.3fx (target <= 1.0x), whole grid %.3fx\n", o.band,
              distance.band / peer_seconds, distance.whole / peer_seconds);
  return peer_seconds;
}

// The base mesh: read from --base or simplified; written to --write-base.
PolygonMesh make_base(const PolygonMesh& extracted, const BenchOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  PolygonMesh base;
  if (!o.base_input.empty()) {
    base = read_mesh(o.base_input);
    std::printf("base mesh: %zu vertices, %zu faces read from %s\n", base.vertex_count(), base.face_count(),
                o.base_input.c_str());
  } else {
    simplify::SimplifyOptions simplify_options;
    simplify_options.target_vertices = o.base_vertices;
    simplify_options.compute_distance = false;
    base = simplify::simplify(extracted, simplify_options).base;
    std::printf("base mesh: %zu vertices, %zu faces in %.2f s\n", base.vertex_count(), base.face_count(),
                seconds_since(start));
  }
  if (!o.base_output.empty()) write_mesh(o.base_output, base);
  return base;
}

// Shrink-wraps --repeat times; returns the last fit and the best time in s.
std::pair<ShrinkWrapResult, double> time_shrink_wrap(const SubdivisionHierarchy& hierarchy, const PolygonMesh& base,
                                                     const PreparedSurface& prepared, const BenchOptions& o) {
  ShrinkWrapOptions wrap_options = o.wrap;
  wrap_options.keep_levels = o.quality && !o.final_quality_only;
  wrap_options.surface = &prepared.isosurface.mesh;
  ShrinkWrapResult wrapped;
  double wrap_seconds = 0;
  for (int run = 0; run < o.repeat; ++run) {
    const double cpu_start = cpu_seconds();
    const auto start = std::chrono::steady_clock::now();
    wrapped = shrink_wrap(hierarchy, base.positions, prepared.distance, prepared.field, wrap_options);
    const double seconds = seconds_since(start);
    std::printf("  shrink-wrap run %d: %.3f s (cpu %.3f s)\n", run + 1, seconds, cpu_seconds() - cpu_start);
    wrap_seconds = run == 0 ? seconds : std::min(wrap_seconds, seconds);
  }
  return {std::move(wrapped), wrap_seconds};
}

// The shrink-wrap's time against its target and the peer.
void print_wrap_times(const SubdivisionHierarchy& hierarchy, double hierarchy_seconds, double wrap_seconds,
                      double peer_seconds, int repeat) {
  std::printf("hierarchy %.3f s; shrink-wrap to %zu fine vertices: %.3f s%s (target <= 5 s)\n", hierarchy_seconds,
              hierarchy.fine_vertex_count(), wrap_seconds, repeat > 1 ? " best" : "");
  // The host's speed drifts between days: the shrink-wrap against the peer of
  // the same run.
  if (peer_seconds > 0)
    std::printf("  shrink-wrap / OpenVDB meshToLevelSet in this run: %.3fx\n", wrap_seconds / peer_seconds);
  // The issue sets 5 s for miranda, 3 levels, from a base of about 45,000
  // vertices, which this extraction's surface cannot be simplified to: per
  // fine vertex, with this base's ratio of fine to base vertices.
  const double fine_per_base = double(hierarchy.fine_vertex_count()) / double(hierarchy.vertex_count(0));
  if (hierarchy.levels() == 3)
    std::printf("  per fine vertex: %.3f us; the target's 5 s for a 45,000-vertex base (%.2f M fine vertices at "
                "this base's ratio) is %.3f us\n",
                1e6 * wrap_seconds / double(hierarchy.fine_vertex_count()), 45000 * fine_per_base / 1e6,
                1e6 * 5.0 / (45000 * fine_per_base));
}

// Per-level, correction, untangle and unfold statistics, and a hash of the fit.
void print_wrap_statistics(const ShrinkWrapResult& wrapped) {
  for (const WrapLevelStatistics& s : wrapped.levels)
    std::printf("  level %d: %zu vertices (%zu on the box, %zu fixed) %.3f s (setup %.3f, relax %.3f, attract %.3f, "
                "correct %.3f, untangle %.3f, pull %.3f, unfold %.3f); mean edge %.2f cell; pulled %zu toward %zu "
                "uncovered isosurface vertices (%zu back); last attraction: %zu attracted "
                "(mean %.3f, max %.2f cell), %zu out of reach, %zu without direction\n",
                s.level, s.vertices, s.boundary_vertices, s.fixed_vertices, s.seconds, s.seconds_setup,
                s.seconds_relaxation, s.seconds_attraction, s.seconds_correction, s.seconds_untangle, s.seconds_pull,
                s.seconds_unfold, s.mean_edge_cells, s.pulled_vertices, s.uncovered_samples, s.pulled_back,
                s.last_attraction.attracted, s.last_attraction.mean_move_cells, s.last_attraction.max_move_cells,
                s.last_attraction.out_of_reach, s.last_attraction.no_direction);
  const auto& c = wrapped.correction;
  std::printf("  correction: %zu corrected (mean %.4f, max %.3f cell; %zu from the nearest point, %zu along a box "
              "face, %zu from their neighbours, %zu by the wide search, %zu from the extracted surface), %zu "
              "failed\n",
              c.corrected, c.mean_move_cells, c.max_move_cells, c.from_nearest_point, c.along_box_face,
              c.from_neighbours, c.from_wide_search, c.from_extracted_surface, c.failed);
  std::printf("  untangle: %zu folded faces before, %zu after %d rounds\n", wrapped.untangle.folded_before,
              wrapped.untangle.folded_after, wrapped.untangle.rounds);
  std::printf("  unfold: %zu folded faces before, %zu after %d rounds (%zu moves)%s\n", wrapped.unfold.folded_before,
              wrapped.unfold.folded_after, wrapped.unfold.rounds, wrapped.unfold.moved,
              wrapped.unfold.skipped ? ", skipped: over the limit" : "");
  // FNV-1a over the fitted positions' bytes: equal hashes mean bit-identical fits.
  std::uint64_t hash = 1469598103934665603ull;
  const auto* bytes = reinterpret_cast<const unsigned char*>(wrapped.positions.data());
  for (std::size_t i = 0; i < wrapped.positions.size() * sizeof(Vec3); ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
  std::printf("  positions hash %016llx\n", static_cast<unsigned long long>(hash));
}

// The extracted triangles' distance to the isosurface and the fit's quality
// per level (level L only with --final-quality).
void print_quality_rows(const SubdivisionHierarchy& hierarchy, const ShrinkWrapResult& wrapped,
                        const PreparedSurface& prepared, const BenchOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const PolygonMesh& extracted = prepared.isosurface.mesh;
  const Volume& volume = prepared.field;
  const BinnedSurfaceDistance reference(extracted);
  const SurfaceDeviation deviation = extracted_surface_deviation(extracted, volume, o.iso);
  std::printf("extracted triangles off the isosurface: rms %.4f max %.3f cell (area-weighted)\n", deviation.rms,
              deviation.max);
  for (int level = o.final_quality_only ? o.levels : 0; level <= o.levels; ++level)
    print_quality(measure_fit_quality(hierarchy, level,
                                      level < o.levels ? wrapped.level_positions[std::size_t(level)] : wrapped.positions,
                                      extracted, reference, volume, o.iso, Orientation::TowardLower));
  std::printf("quality measured in %.1f s\n", seconds_since(start));
}

// How the squared error of `kept` is spread over the fine points: a few
// outliers (folds, points off the surface) or the whole surface.
void print_error_spread(const std::vector<Vec3>& kept, const std::vector<Vec3>& fitted, std::size_t fine_vertices,
                        double cell) {
  std::vector<double> squared(fine_vertices);
  for (std::size_t i = 0; i < squared.size(); ++i) squared[i] = squared_norm(kept[i] - fitted[i]);
  std::sort(squared.begin(), squared.end());
  const double total = std::accumulate(squared.begin(), squared.end(), 0.0);
  const auto share_of_largest = [&](double fraction) {
    const auto first = squared.begin() + std::ptrdiff_t(double(squared.size()) * (1 - fraction));
    return total > 0 ? 100 * std::accumulate(first, squared.end(), 0.0) / total : 0.0;
  };
  const auto quantile = [&](double q) {
    return 100 * std::sqrt(squared[std::min(squared.size() - 1, std::size_t(q * double(squared.size())))]) / cell;
  };
  std::printf(" [p50 %.1f p90 %.1f p99 %.1f; largest 1%% %.0f%% of the squared error]", quantile(0.5), quantile(0.9),
              quantile(0.99), share_of_largest(0.01));
}

// The paper's Table 1 RMSE rows: unquantized coefficients, importance-weighted
// truncation to 20, 10, 5 and 0 percent.
void print_rmse_rows(const SubdivisionHierarchy& hierarchy, const ShrinkWrapResult& wrapped, double cell,
                     bool spread) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<Vec3> coefficients = wrapped.positions;
  analyze(hierarchy, coefficients);
  const std::vector<double> weights = wavelet_norms(hierarchy);
  std::printf("Table 1 (cell %g):", cell);
  for (double percent : {20.0, 10.0, 5.0, 0.0}) {
    std::vector<Vec3> kept = coefficients;
    keep_most_important(hierarchy, kept, weights, coefficients_for_percent(hierarchy, percent));
    synthesize(hierarchy, kept);
    const PointErrors errors = point_errors(kept, wrapped.positions, hierarchy.fine_vertex_count());
    std::printf("  %g%% %.2f", percent, 100 * errors.rms / cell);
    if (spread) print_error_spread(kept, wrapped.positions, hierarchy.fine_vertex_count(), cell);
  }
  std::printf("  (%% of a cell, %.1f s)\n", seconds_since(start));
}

void run(const BenchOptions& o) {
  const PrepareOptions prepare_options = prepare_options_for(o);
  PreparedSurface prepared = load_and_extract(o, prepare_options);
  const DistanceTimes distance = time_distance_field(prepared, prepare_options, o);
  const double peer_seconds = o.peer ? time_openvdb(prepared.isosurface.mesh, prepared.field, o, distance) : 0;
  if (o.sdf_only) return;

  const PolygonMesh base = make_base(prepared.isosurface.mesh, o);
  const auto start = std::chrono::steady_clock::now();
  const SubdivisionHierarchy hierarchy(base, o.levels);
  const double hierarchy_seconds = seconds_since(start);
  const auto [wrapped, wrap_seconds] = time_shrink_wrap(hierarchy, base, prepared, o);
  print_wrap_times(hierarchy, hierarchy_seconds, wrap_seconds, peer_seconds, o.repeat);
  print_wrap_statistics(wrapped);
  std::printf("peak memory so far: %.0f MB\n", peak_megabytes());

  if (o.quality) print_quality_rows(hierarchy, wrapped, prepared, o);
  if (o.rmse) print_rmse_rows(hierarchy, wrapped, prepared.field.cell_size(), o.rmse_spread);
  std::printf("peak memory: %.0f MB\n", peak_megabytes());
}

}  // namespace

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  const BenchOptions options = parse_options(argc, argv);
  tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism,
                                   static_cast<std::size_t>(options.threads));
  try {
    run(options);
  } catch (const Error& error) {
    std::fprintf(stderr, "bench_fit: %s\n", error.what());
    return 1;
  }
  return 0;
}
