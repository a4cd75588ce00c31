// isowave fit: extract the isosurface, build its signed-distance field and
// shrink-wrap a base mesh's subdivision hierarchy onto it (paper Sec. 4.2);
// writes the fine control mesh and prints the quality report per level.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "cli.h"
#include "commands.h"
#include "console_progress.h"
#include "isowave/pipeline/prepare.h"
#include "isowave/core/error.h"
#include "isowave/core/memory_check.h"
#include "isowave/core/mesh_io.h"
#include "isowave/fit/fit_quality.h"
#include "isowave/fit/shrink_wrap.h"
#include "isowave/fit/surface_fit.h"
#include "isowave/core/binned_surface_distance.h"
#include "isowave/transform/hierarchy.h"
#include "volume_options.h"

namespace isowave::commands {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

void print_quality(const FitQuality& q) {
  std::printf("  level %d: %zu vertices, %zu faces%s\n", q.level, q.vertices, q.faces,
              q.nonfinite_vertices ? " (NON-FINITE VERTICES)" : "");
  std::printf("    on the isosurface (|f - iso| / |grad f|): rms %.4f, max %.4f cell, %zu vertices over a cell off%s\n",
              q.isosurface_rms, q.isosurface_max, q.isosurface_far,
              q.isosurface_undefined
                  ? (" (" + std::to_string(q.isosurface_undefined) + " off the isovalue without a gradient, left out)")
                        .c_str()
                  : "");
  std::printf("    to the extracted mesh: rms %.4f, max %.4f cell, %zu vertices over %.1f\n", q.surface_rms,
              q.surface_max, q.surface_far, kSurfaceFarCells);
  std::printf("    coverage (extracted vertices to the fit): rms %.4f, 99th percentile %.4f, max %.4f cell\n",
              q.coverage_rms, q.coverage_p99, q.coverage_max);
  std::printf("    folded faces: %zu (%.4f%%)\n", q.folded_faces, 100.0 * q.folded_fraction);
  std::printf("    face area / patch mean: min %.3f, 1%% %.3f, median %.3f, 99%% %.3f, max %.3f, deviation %.3f\n",
              q.area_ratio_min, q.area_ratio_p1, q.area_ratio_median, q.area_ratio_p99, q.area_ratio_max,
              q.area_ratio_deviation);
}


cli::CommandSpec fit_spec() {
  cli::CommandSpec spec{
      "fit",
      "INPUT --iso V --base BASE.ply --levels L [reader and extraction options] -o FINE.ply",
      "Fits the subdivision hierarchy of BASE (L levels) to the isosurface of INPUT by shrink-wrapping\n"
      "(Bertram et al. 2000, Sec. 4.2): per level a few rounds of relaxation and attraction toward the\n"
      "zero set of a signed-distance field, then refinement with the wavelet subdivision operator S; finally\n"
      "every fine vertex moves onto the isosurface along the field gradient. The extraction options must\n"
      "match those BASE came from. Writes the level-L control mesh (quads, PLY vertex property 'sharp') and\n"
      "prints a quality report per level (distances in cells).",
      {{"iso", true, "isovalue (samples >= V are inside)", "V"}},
      1,
      1,
      "fit engine.nrrd --iso 100 --base engine_base.ply --levels 3 -o engine_fine.ply"};
  cli::add_volume_options(spec.options);
  cli::add_extraction_options(spec.options);
  spec.options.push_back({"base", true, "base mesh (.ply, .obj, .off), e.g. from the base-mesh stage", "BASE"});
  spec.options.push_back({"levels", true, "subdivision levels, 0..8", "L"});
  spec.options.push_back({"iterations", true, "relaxation + attraction rounds per coarse level (default 3)", "N"});
  spec.options.push_back({"final-iterations", true, "rounds on the finest level (default 1)", "N"});
  spec.options.push_back({"reach", true, "attraction reach in edge lengths (default 2)", "R"});
  spec.options.push_back({"band", true, "signed-distance narrow band in cells, 0 = whole grid (default 3)", "K"});
  spec.options.push_back({"droplet-vertices", true,
                          "closed base components of at most N vertices, within 3 cells of their centre, are fitted "
                          "along rays from it; 0 = the paper's steps everywhere (default 8)", "N"});
  spec.options.push_back({"no-correction", false, "skip the final move onto the exact isosurface", ""});
  spec.options.push_back({"no-coverage-pull", false,
                          "skip the pull of the fine levels toward isosurface parts the fit leaves out", ""});
  cli::add_unfold_option(spec.options);
  spec.options.push_back({"no-report", false, "skip the quality report (it needs distance trees)", ""});
  spec.options.push_back({"ascii", false, "write ASCII PLY instead of binary", ""});
  spec.options.push_back({"quiet", false, "print nothing on success", ""});
  spec.options.push_back(cli::force_option());
  spec.options.push_back({"output", true, "output mesh (.ply, .obj or .off)", "FINE"});
  return spec;
}

struct FitOptions {
  std::string input, output, base_path;
  int levels = 0;  // 0..8
  PrepareOptions prepare;
  ShrinkWrapOptions wrap;  // surface is set once the isosurface exists
  VolumeReadOptions read;
  bool quiet = false;
  bool report = false;  // the quality report per level (not with --quiet)
  bool ascii = false;
};

// Checks the arguments before any work: the output's name and extension,
// --base, --levels, --iso, --band. Throws Error(InvalidArgument).
FitOptions fit_options(const cli::Arguments& args) {
  FitOptions o;
  o.input = args.positional()[0];
  o.output = args.require("output");
  cli::check_outputs(args, {o.output});
  mesh_format_from_path(o.output);  // reject a bad extension before any work
  o.base_path = args.require("base");
  o.levels = args.get_int("levels", -1, 0, 8);
  if (o.levels < 0) throw Error(ErrorKind::InvalidArgument, "missing required option --levels");
  if (!args.has("iso") && !cli::is_builtin_volume(o.input))
    throw Error(ErrorKind::InvalidArgument, "missing required option --iso (only builtin: inputs default to 0)");
  o.prepare.extract = cli::extraction_options(args);
  o.prepare.extract.iso = args.get_double("iso", 0.0);
  ShrinkWrapOptions& wrap = o.wrap;
  wrap.iterations = args.get_int("iterations", wrap.iterations, 0, 100);
  wrap.final_level_iterations = args.get_int("final-iterations", wrap.final_level_iterations, 0, 100);
  wrap.attraction.reach_edges = args.get_double("reach", wrap.attraction.reach_edges);
  wrap.droplet_vertices = static_cast<std::size_t>(
      args.get_int("droplet-vertices", static_cast<int>(wrap.droplet_vertices), 0, 1000000));
  wrap.final_correction = !args.has("no-correction");
  cli::set_unfold_limit(args, wrap);
  o.quiet = args.has("quiet");
  o.report = !args.has("no-report") && !o.quiet;
  wrap.keep_levels = o.report;
  wrap.coverage_pull = !args.has("no-coverage-pull");
  o.prepare.distance_band_cells = args.get_double("band", o.prepare.distance_band_cells);
  const double band = o.prepare.distance_band_cells;
  if (!(band >= 0 && band <= 1e6)) throw Error(ErrorKind::InvalidArgument, "--band must be in 0..1e6 cells");
  o.read = cli::volume_read_options(args);
  o.ascii = args.has("ascii");
  return o;
}

struct BaseMesh {
  PolygonMesh mesh;
  std::size_t unreferenced = 0;  // vertices no face used, dropped
};

// Reads the base mesh and checks the fit's memory for its levels; first, as
// it is cheap to read and its errors are the likeliest.
BaseMesh read_base(const FitOptions& o) {
  BaseMesh base{read_mesh(o.base_path)};
  base.unreferenced = remove_unreferenced_vertices(base.mesh);
  check_memory(static_cast<double>(fine_vertex_count(base.mesh, o.levels)), kFitBytesPerFineVertex,
               "--levels " + std::to_string(o.levels));
  return base;
}

struct StageSeconds {
  double extract = 0, distance = 0, wrap = 0;
};

// Loads the volume, extracts the isosurface and builds its signed-distance field.
PreparedSurface load_and_prepare(const FitOptions& o, cli::ConsoleProgress& progress, StageSeconds& seconds) {
  auto start = Clock::now();
  Volume loaded = load_volume(o.input, o.read, progress);
  cli::report_loaded_volume("fit", o.input, loaded, o.quiet ? cli::LoadReport::Nothing : cli::LoadReport::RangeAndWarnings);
  PreparedSurface prepared = extract_surface(std::move(loaded), o.prepare, o.input, progress);
  seconds.extract = seconds_since(start);
  start = Clock::now();
  prepared.distance = surface_distance_field(prepared, o.prepare, progress);
  seconds.distance = seconds_since(start);
  return prepared;
}

void write_fine(const FitOptions& o, const PolygonMesh& fine, cli::ConsoleProgress& progress) {
  MeshWriteOptions write_options;
  write_options.ascii = o.ascii;
  progress.begin_stage("write");
  write_mesh(o.output, fine, write_options);
  progress.end_stage();
}

// The inputs' sizes and each stage's time.
void print_stages(const FitOptions& o, const BaseMesh& base, const PreparedSurface& prepared,
                  const SubdivisionHierarchy& hierarchy, const StageSeconds& seconds) {
  const PolygonMesh& mesh = base.mesh;
  std::printf("%s: %zu vertices, %zu faces, %zu sharp%s\n", o.base_path.c_str(), mesh.vertex_count(), mesh.face_count(),
              mesh.sharp_count(),
              base.unreferenced ? (" (" + std::to_string(base.unreferenced) + " unreferenced vertices dropped)").c_str()
                                : "");
  std::printf("%s: isosurface %zu vertices, %zu triangles (%.2f s)\n", o.input.c_str(),
              prepared.isosurface.mesh.vertex_count(), prepared.isosurface.mesh.face_count(), seconds.extract);
  const SignedDistanceStatistics& ds = prepared.distance.statistics;
  const double band = o.prepare.distance_band_cells;
  if (band > 0)
    std::printf("signed distance: %zu nodes, %zu seeds, band %g cells (%.2f s)\n", ds.nodes, ds.seed_nodes, band,
                seconds.distance);
  else
    std::printf("signed distance: %zu nodes, %zu seeds, no band (%.2f s)\n", ds.nodes, ds.seed_nodes, seconds.distance);
  std::printf("shrink-wrap: %zu fine vertices (%.2f s)\n", hierarchy.fine_vertex_count(), seconds.wrap);
}

// Per level, the last attraction and the coverage pull; then the final
// correction, untangle and unfold.
void print_wrap_statistics(const FitOptions& o, const ShrinkWrapResult& result) {
  for (const WrapLevelStatistics& s : result.levels) {
    std::printf("  level %d: %zu vertices, last attraction %zu attracted, %zu out of reach", s.level, s.vertices,
                s.last_attraction.attracted, s.last_attraction.out_of_reach);
    if (s.pulled_vertices > 0)
      std::printf("; %zu pulled toward %zu isosurface vertices the fit left out", s.pulled_vertices, s.uncovered_samples);
    if (s.pulled_back > 0) std::printf(" (%zu of them returned: no root on the isosurface, or folding)", s.pulled_back);
    std::printf("\n");
  }
  const auto& c = result.correction;
  if (o.wrap.final_correction)
    std::printf("  correction: %zu vertices onto the isosurface (mean %.4f, max %.4f cell; %zu from the nearest zero "
                "of the distance field, %zu along a box face, %zu from their neighbours' centroid, %zu by the "
                "wide search, %zu stranded ones from the extracted surface), %zu left in place\n",
                c.corrected, c.mean_move_cells, c.max_move_cells, c.from_nearest_point, c.along_box_face,
                c.from_neighbours, c.from_wide_search, c.from_extracted_surface, c.failed);
  if (result.untangle.folded_before > 0)
    std::printf("  untangle: %zu folded faces on level %d before, %zu after %d rounds\n", result.untangle.folded_before,
                o.levels, result.untangle.folded_after, result.untangle.rounds);
  if (result.unfold.skipped)
    std::printf("  unfold: skipped, over %.2f%% of the faces folded (--unfold-limit 100 forces it)\n",
                100.0 * o.wrap.unfold_max_folded_fraction);
  else if (result.unfold.folded_before > 0)
    std::printf("  unfold: %zu folded faces before, %zu after %d rounds\n", result.unfold.folded_before,
                result.unfold.folded_after, result.unfold.rounds);
}

// A note when the fine mesh is too coarse for the isosurface, or else when
// many of its faces stay folded without a pre-filter.
void print_notes(const FitOptions& o, const PolygonMesh& fine, const PolygonMesh& isosurface,
                 const ShrinkWrapResult& result) {
  const bool coarse = fine_mesh_too_coarse(fine.vertex_count(), isosurface.vertex_count());
  const std::size_t suggested = std::max<std::size_t>(4, isosurface.vertex_count() >> (2 * o.levels));
  if (coarse)
    std::printf("  note: %zu fine vertices for an isosurface of %zu: %d levels of this base are too coarse to follow it "
                "(a base of about %zu vertices, or more levels, would)\n",
                fine.vertex_count(), isosurface.vertex_count(), o.levels, suggested);
  else if (o.prepare.extract.smooth_sigma == 0 && result.folded_faces > fine.face_count() / 1000)
    std::printf("  note: %.2f%% of the fine faces stay folded; folds sit mostly on necks and tunnels thinner than a "
                "cell, which a one-voxel pre-filter (--smooth 1) removes\n",
                100.0 * double(result.folded_faces) / double(fine.face_count()));
}

// Measures and prints the fit's quality on every level.
void report_quality(const FitOptions& o, const SubdivisionHierarchy& hierarchy, const ShrinkWrapResult& result,
                    const PreparedSurface& prepared, cli::ConsoleProgress& progress) {
  const IsosurfaceOptions& extract_options = o.prepare.extract;
  const PolygonMesh& isosurface = prepared.isosurface.mesh;
  std::fflush(stdout);  // the report so far before the live line of the measurement
  progress.begin_stage("quality");
  const BinnedSurfaceDistance reference(isosurface);
  std::vector<FitQuality> qualities;
  const SurfaceDeviation deviation = extracted_surface_deviation(isosurface, prepared.field, extract_options.iso);
  double work = 0, total = 0;  // each level's measurement takes about as long as its vertices
  for (int level = 0; level <= o.levels; ++level) total += double(hierarchy.vertex_count(level));
  for (int level = 0; level <= o.levels; ++level) {
    qualities.push_back(measure_fit_quality(
        hierarchy, level, level < o.levels ? result.level_positions[static_cast<std::size_t>(level)] : result.positions,
        isosurface, reference, prepared.field, extract_options.iso, orientation_from_flip(extract_options.flip)));
    work += double(hierarchy.vertex_count(level));
    progress.update(work / total);
  }
  progress.end_stage();
  std::printf("quality:\n");
  std::printf("  the extracted triangles themselves lie rms %.4f, max %.4f cell off the isosurface (a fit on the "
              "isosurface lies about as far from them)\n",
              deviation.rms, deviation.max);
  for (const FitQuality& quality : qualities) print_quality(quality);
}

}  // namespace

int fit(const Args& raw) {
  const cli::CommandSpec spec = fit_spec();
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  FitOptions options = fit_options(args);
  const BaseMesh base = read_base(options);
  const SubdivisionHierarchy hierarchy(base.mesh, options.levels);

  // A live line per stage on a terminal (the shrink-wrap and the quality
  // report take seconds on large volumes); nothing otherwise, as the report
  // below has the times.
  const bool live = cli::default_progress_mode(options.quiet) == cli::ProgressMode::LiveBar;
  cli::ConsoleProgress progress(options.input, live ? cli::ProgressMode::LiveBar : cli::ProgressMode::Quiet);
  StageSeconds seconds;
  const PreparedSurface prepared = load_and_prepare(options, progress, seconds);

  const auto start = Clock::now();
  options.wrap.surface = &prepared.isosurface.mesh;
  const ShrinkWrapResult result =
      shrink_wrap(hierarchy, base.mesh.positions, prepared.distance, prepared.field, options.wrap, progress);
  seconds.wrap = seconds_since(start);

  const PolygonMesh fine = hierarchy.control_mesh(options.levels, result.positions);
  write_fine(options, fine, progress);
  if (options.quiet) return 0;

  print_stages(options, base, prepared, hierarchy, seconds);
  print_wrap_statistics(options, result);
  print_notes(options, fine, prepared.isosurface.mesh, result);
  if (options.report) report_quality(options, hierarchy, result, prepared, progress);
  std::printf("%s: level %d, %zu vertices, %zu %s\n", options.output.c_str(), options.levels, fine.vertex_count(),
              fine.face_count(), options.levels > 0 ? "quads" : "faces (the base's polygons)");
  return 0;
}

}  // namespace isowave::commands
