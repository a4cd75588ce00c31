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

}  // namespace

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  std::string input = std::string(ISOWAVE_SHARED_DATA_DIR) + "/volumes/miranda_256x256x256.nrrd";
  double iso = 1.5;
  std::size_t min_component = 50, base_vertices = 0;
  int levels = 3, threads = 2;
  double band = 3;
  bool quality = true, sdf_only = false, correction = true, peer = true, final_quality_only = false, rmse = false,
       rmse_spread = false;
  bool coverage_pull = true;
  double pull_max_edge = ShrinkWrapOptions{}.pull_max_edge_cells;
  std::string base_input, base_output;
  int repeat = 1;
  int untangle_rounds = ShrinkWrapOptions().untangle_rounds;
  int coarse_untangle_rounds = ShrinkWrapOptions().coarse_untangle_rounds;
  int unfold_rounds = ShrinkWrapOptions().unfold_rounds;
  double unfold_limit = ShrinkWrapOptions().unfold_max_folded_fraction;
  std::size_t droplet_vertices = ShrinkWrapOptions().droplet_vertices;
  bool nearest_correction = ShrinkWrapOptions().correction_from_nearest_point;
  double weight = 0.5, correction_cells = ShrinkWrapOptions().correction_max_cells;
  double reach = ShrinkWrapOptions().attraction.reach_edges, min_reach = ShrinkWrapOptions().attraction.min_reach_cells;
  int iterations = ShrinkWrapOptions().iterations, final_iterations = ShrinkWrapOptions().final_level_iterations;
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
    if (arg == "--min-component") min_component = std::stoul(next());
    else if (arg == "--base-vertices") base_vertices = std::stoul(next());
    else if (arg == "--levels") levels = std::stoi(next());
    else if (arg == "--threads") threads = std::stoi(next());
    else if (arg == "--band") band = std::stod(next());
    else if (arg == "--no-quality") quality = false;
    else if (arg == "--distance-only") sdf_only = true;
    else if (arg == "--no-correction") correction = false;
    else if (arg == "--no-coverage-pull") coverage_pull = false;
    else if (arg == "--pull-max-edge") pull_max_edge = std::stod(next());
    else if (arg == "--weight") weight = std::stod(next());
    else if (arg == "--correction-cells") correction_cells = std::stod(next());
    else if (arg == "--untangle") untangle_rounds = std::stoi(next());
    else if (arg == "--coarse-untangle") coarse_untangle_rounds = std::stoi(next());
    else if (arg == "--unfold") unfold_rounds = std::stoi(next());
    else if (arg == "--unfold-limit") unfold_limit = std::stod(next());
    else if (arg == "--droplet-vertices") droplet_vertices = std::stoul(next());
    else if (arg == "--no-nearest-correction") nearest_correction = false;
    else if (arg == "--reach") reach = std::stod(next());
    else if (arg == "--min-reach") min_reach = std::stod(next());
    else if (arg == "--iterations") iterations = std::stoi(next());
    else if (arg == "--final-iterations") final_iterations = std::stoi(next());
    else if (arg == "--base") base_input = next();
    else if (arg == "--write-base") base_output = next();
    else if (arg == "--no-peer") peer = false;
    else if (arg == "--repeat") repeat = std::max(1, std::stoi(next()));
    else if (arg == "--final-quality") final_quality_only = true;
    else if (arg == "--rmse") rmse = true;
    else if (arg == "--rmse-spread") rmse = rmse_spread = true;
    else positional.push_back(arg);
  }
  if (positional.size() == 2) {
    input = positional[0];
    iso = std::stod(positional[1]);
  } else if (!positional.empty()) {
    std::fprintf(stderr, "usage: bench_fit [INPUT ISO] [options]\n");
    return 2;
  }
  tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));

  try {
    auto start = std::chrono::steady_clock::now();
    Volume loaded = load_volume(input, {});
    std::printf("%s: %zux%zux%zu, read in %.2f s, %d threads\n", input.c_str(), loaded.dims[0], loaded.dims[1],
                loaded.dims[2], seconds_since(start), threads);

    start = std::chrono::steady_clock::now();
    PrepareOptions prepare_options;
    prepare_options.extract.iso = iso;
    prepare_options.extract.min_component_vertices = min_component;
    prepare_options.distance_band_cells = band;
    PreparedSurface prepared = extract_surface(std::move(loaded), prepare_options, input);
    const Volume& volume = prepared.field;
    const PolygonMesh& extracted = prepared.isosurface.mesh;
    std::printf("extracted: %zu vertices, %zu triangles, genus %lld, %zu components in %.2f s\n",
                extracted.vertex_count(), extracted.face_count(), prepared.isosurface.report.after.genus,
                prepared.isosurface.report.after.components, seconds_since(start));

    // Our distance field: the narrow band the fit uses (--band, default 3
    // cells, OpenVDB's half width) and, for reference, the whole grid.
    double distance_seconds = 0;
    for (int run = 0; run < repeat; ++run) {
      const double cpu_start = cpu_seconds();
      start = std::chrono::steady_clock::now();
      prepared.distance = surface_distance_field(prepared, prepare_options);
      const double seconds = seconds_since(start);
      if (repeat > 1) std::printf("  distance run %d: %.3f s (cpu %.3f s)\n", run + 1, seconds, cpu_seconds() - cpu_start);
      distance_seconds = run == 0 ? seconds : std::min(distance_seconds, seconds);
    }
    const SignedDistanceField& distance = prepared.distance;
    const SignedDistanceStatistics& ds = distance.statistics;
    std::printf("signed distance (band %g cells): %.3f s%s (seeding %.3f, propagation %.3f, finishing %.3f) | %zu nodes, "
                "%zu seeds, %zu pops, %zu updates, peak queue %zu, working set %.1f MB; %zu nodes on dropped "
                "components, %zu flipped\n",
                band, distance_seconds, repeat > 1 ? " best" : "", ds.seconds_seeding, ds.seconds_propagation, ds.seconds_finishing, ds.nodes,
                ds.seed_nodes, ds.queue_pops, ds.updates, ds.peak_queue, double(ds.peak_bytes) / 1e6,
                ds.unseeded_crossing_nodes, ds.flipped_nodes);
    double whole_seconds = 0;
    if (peer) {
      PrepareOptions whole_options = prepare_options;
      whole_options.distance_band_cells = 0;
      start = std::chrono::steady_clock::now();
      const SignedDistanceField whole = surface_distance_field(prepared, whole_options);
      whole_seconds = seconds_since(start);
      std::printf("signed distance (whole grid): %.3f s | %zu pops, %zu updates, working set %.1f MB\n",
                  whole_seconds, whole.statistics.queue_pops, whole.statistics.updates,
                  double(whole.statistics.peak_bytes) / 1e6);
    }

    // Peer: OpenVDB's mesh-to-level-set on the extracted triangles.
    double peer_seconds = 0;
    if (peer) {
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
      start = std::chrono::steady_clock::now();
      const openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*transform, points, triangles, 3.0f);
      peer_seconds = seconds_since(start);
      std::printf("OpenVDB meshToLevelSet (half width 3): %.3f s, %zu active voxels\n", peer_seconds,
                  std::size_t(grid->activeVoxelCount()));
      std::printf("ratio signed distance / OpenVDB: band %g %.3fx (target <= 1.0x), whole grid %.3fx\n", band,
                  distance_seconds / peer_seconds, whole_seconds / peer_seconds);
    }

    if (sdf_only) return 0;
    start = std::chrono::steady_clock::now();
    PolygonMesh base;
    if (!base_input.empty()) {
      base = read_mesh(base_input);
      std::printf("base mesh: %zu vertices, %zu faces read from %s\n", base.vertex_count(), base.face_count(),
                  base_input.c_str());
    } else {
      simplify::SimplifyOptions simplify_options;
      simplify_options.target_vertices = base_vertices;
      simplify_options.compute_distance = false;
      base = simplify::simplify(extracted, simplify_options).base;
      std::printf("base mesh: %zu vertices, %zu faces in %.2f s\n", base.vertex_count(), base.face_count(),
                  seconds_since(start));
    }
    if (!base_output.empty()) write_mesh(base_output, base);

    start = std::chrono::steady_clock::now();
    const SubdivisionHierarchy hierarchy(base, levels);
    const double hierarchy_seconds = seconds_since(start);
    ShrinkWrapOptions wrap_options;
    wrap_options.keep_levels = quality && !final_quality_only;
    wrap_options.attraction.reach_edges = reach;
    wrap_options.attraction.min_reach_cells = min_reach;
    wrap_options.iterations = iterations;
    wrap_options.final_level_iterations = final_iterations;
    wrap_options.final_correction = correction;
    wrap_options.relaxation_weight = weight;
    wrap_options.correction_max_cells = correction_cells;
    wrap_options.untangle_rounds = untangle_rounds;
    wrap_options.coarse_untangle_rounds = coarse_untangle_rounds;
    wrap_options.unfold_rounds = unfold_rounds;
    wrap_options.unfold_max_folded_fraction = unfold_limit;
    wrap_options.droplet_vertices = droplet_vertices;
    wrap_options.correction_from_nearest_point = nearest_correction;
    wrap_options.surface = &extracted;
    wrap_options.coverage_pull = coverage_pull;
    wrap_options.pull_max_edge_cells = pull_max_edge;
    ShrinkWrapResult wrapped;
    double wrap_seconds = 0;
    for (int run = 0; run < repeat; ++run) {
      const double cpu_start = cpu_seconds();
      start = std::chrono::steady_clock::now();
      wrapped = shrink_wrap(hierarchy, base.positions, distance, volume, wrap_options);
      const double seconds = seconds_since(start);
      std::printf("  shrink-wrap run %d: %.3f s (cpu %.3f s)\n", run + 1, seconds, cpu_seconds() - cpu_start);
      wrap_seconds = run == 0 ? seconds : std::min(wrap_seconds, seconds);
    }
    std::printf("hierarchy %.3f s; shrink-wrap to %zu fine vertices: %.3f s%s (target <= 5 s)\n",
                hierarchy_seconds, hierarchy.fine_vertex_count(), wrap_seconds, repeat > 1 ? " best" : "");
    // The host's speed drifts by over 1.5x between days (OpenVDB on miranda
    // 11.2 to 22.8 s): the shrink-wrap against the peer of the same run.
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
    for (const WrapLevelStatistics& s : wrapped.levels)
      std::printf("  level %d: %zu vertices (%zu on the box, %zu fixed) %.3f s (setup %.3f, relax %.3f, attract %.3f, "
                  "correct %.3f, untangle %.3f, pull %.3f, unfold %.3f); mean edge %.2f cell; pulled %zu toward %zu "
                  "uncovered isosurface vertices (%zu back); last attraction: %zu attracted "
                  "(mean %.3f, max %.2f cell), %zu out of reach, %zu without direction\n",
                  s.level, s.vertices, s.boundary_vertices, s.fixed_vertices, s.seconds, s.seconds_setup,
                  s.seconds_relaxation, s.seconds_attraction, s.seconds_correction, s.seconds_untangle, s.seconds_pull,
                  s.seconds_unfold, s.mean_edge_cells, s.pulled_vertices, s.uncovered_samples, s.pulled_back,
                  s.last_attraction.attracted,
                  s.last_attraction.mean_move_cells, s.last_attraction.max_move_cells, s.last_attraction.out_of_reach,
                  s.last_attraction.no_direction);
    std::printf("  correction: %zu corrected (mean %.4f, max %.3f cell; %zu from the nearest point, %zu along a box "
                "face, %zu from their neighbours, %zu by the wide search, %zu from the extracted surface), %zu "
                "failed\n",
                wrapped.correction.corrected, wrapped.correction.mean_move_cells, wrapped.correction.max_move_cells,
                wrapped.correction.from_nearest_point, wrapped.correction.along_box_face,
                wrapped.correction.from_neighbours, wrapped.correction.from_wide_search,
                wrapped.correction.from_extracted_surface, wrapped.correction.failed);
    std::printf("  untangle: %zu folded faces before, %zu after %d rounds\n", wrapped.untangle.folded_before,
                wrapped.untangle.folded_after, wrapped.untangle.rounds);
    std::printf("  unfold: %zu folded faces before, %zu after %d rounds (%zu moves)%s\n",
                wrapped.unfold.folded_before, wrapped.unfold.folded_after, wrapped.unfold.rounds, wrapped.unfold.moved,
                wrapped.unfold.skipped ? ", skipped: over the limit" : "");
    {
      // FNV-1a over the fitted positions' bytes: equal hashes mean bit-identical fits.
      std::uint64_t hash = 1469598103934665603ull;
      const auto* bytes = reinterpret_cast<const unsigned char*>(wrapped.positions.data());
      for (std::size_t i = 0; i < wrapped.positions.size() * sizeof(Vec3); ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
      std::printf("  positions hash %016llx\n", static_cast<unsigned long long>(hash));
    }
    std::printf("peak memory so far: %.0f MB\n", peak_megabytes());

    if (quality) {
      start = std::chrono::steady_clock::now();
      const BinnedSurfaceDistance reference(extracted);
      const SurfaceDeviation deviation = extracted_surface_deviation(extracted, volume, iso);
      std::printf("extracted triangles off the isosurface: rms %.4f max %.3f cell (area-weighted)\n", deviation.rms,
                  deviation.max);
      for (int level = final_quality_only ? levels : 0; level <= levels; ++level)
        print_quality(measure_fit_quality(hierarchy, level,
                                          level < levels ? wrapped.level_positions[std::size_t(level)] : wrapped.positions,
                                          extracted, reference, volume, iso, Orientation::TowardLower));
      std::printf("quality measured in %.1f s\n", seconds_since(start));
    }
    if (rmse) {
      start = std::chrono::steady_clock::now();
      std::vector<Vec3> coefficients = wrapped.positions;
      analyze(hierarchy, coefficients);
      const std::vector<double> weights = wavelet_norms(hierarchy);
      const double cell = volume.cell_size();
      std::printf("Table 1 (cell %g):", cell);
      for (double percent : {20.0, 10.0, 5.0, 0.0}) {
        std::vector<Vec3> kept = coefficients;
        keep_most_important(hierarchy, kept, weights, coefficients_for_percent(hierarchy, percent));
        synthesize(hierarchy, kept);
        const PointErrors errors = point_errors(kept, wrapped.positions, hierarchy.fine_vertex_count());
        std::printf("  %g%% %.2f", percent, 100 * errors.rms / cell);
        if (rmse_spread) {
          // How the squared error is spread over the fine points: a few
          // outliers (folds, points off the surface) or the whole surface.
          std::vector<double> squared(hierarchy.fine_vertex_count());
          for (std::size_t i = 0; i < squared.size(); ++i) squared[i] = squared_norm(kept[i] - wrapped.positions[i]);
          std::sort(squared.begin(), squared.end());
          const double total = std::accumulate(squared.begin(), squared.end(), 0.0);
          const auto share_of_largest = [&](double fraction) {
            const auto first = squared.begin() + std::ptrdiff_t(double(squared.size()) * (1 - fraction));
            return total > 0 ? 100 * std::accumulate(first, squared.end(), 0.0) / total : 0.0;
          };
          const auto quantile = [&](double q) {
            return 100 * std::sqrt(squared[std::min(squared.size() - 1, std::size_t(q * double(squared.size())))]) / cell;
          };
          std::printf(" [p50 %.1f p90 %.1f p99 %.1f; largest 1%% %.0f%% of the squared error]", quantile(0.5),
                      quantile(0.9), quantile(0.99), share_of_largest(0.01));
        }
      }
      std::printf("  (%% of a cell, %.1f s)\n", seconds_since(start));
    }
    std::printf("peak memory: %.0f MB\n", peak_megabytes());
  } catch (const Error& error) {
    std::fprintf(stderr, "bench_fit: %s\n", error.what());
    return 1;
  }
  return 0;
}
