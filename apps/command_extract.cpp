// isowave extract: a 2-manifold, consistently oriented isosurface of a volume,
// with the optional clean-ups (small components, Gaussian pre-filter) and a
// topology report.
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <climits>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "cli.h"
#include "commands.h"
#include "isowave/core/atomic_file.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "isowave/extract/volume_summary.h"
#include "volume_options.h"

namespace isowave::commands {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// "<10: 14900, <100: 9000, ..." from the decade histogram (empty decades left out).
std::string histogram_text(const std::vector<std::size_t>& histogram) {
  std::string text;
  std::size_t limit = 10;
  for (std::size_t bucket = 0; bucket < histogram.size(); ++bucket, limit *= 10) {
    if (histogram[bucket] == 0) continue;
    if (!text.empty()) text += ", ";
    text += "<" + std::to_string(limit) + ": " + std::to_string(histogram[bucket]);
  }
  return text;
}

void print_statistics(const char* label, const SurfaceStatistics& s) {
  std::printf("%s: %zu vertices, %zu triangles, area %.6g\n", label, s.vertices, s.faces, s.area);
  std::printf("  %zu components (by vertex count %s), %zu boundary loops, Euler characteristic %lld, genus %lld\n",
              s.components, histogram_text(s.component_size_histogram).c_str(), s.boundary_loops,
              s.euler_characteristic, s.genus);
}

std::string statistics_json(const SurfaceStatistics& s) {
  std::string histogram;
  for (std::size_t count : s.component_size_histogram)
    histogram += (histogram.empty() ? "" : ", ") + std::to_string(count);
  return "{\"vertices\": " + std::to_string(s.vertices) + ", \"triangles\": " + std::to_string(s.faces) +
         ", \"edges\": " + std::to_string(s.edges) + ", \"boundary_edges\": " + std::to_string(s.boundary_edges) +
         ", \"boundary_loops\": " + std::to_string(s.boundary_loops) +
         ", \"components\": " + std::to_string(s.components) +
         ", \"euler_characteristic\": " + std::to_string(s.euler_characteristic) +
         ", \"genus\": " + std::to_string(s.genus) + ", \"area\": " + number(s.area) +
         ", \"component_size_histogram_decades\": [" + histogram + "]}";
}

std::string report_json(const std::string& input, const Volume& volume, const IsosurfaceReport& r, double load_seconds,
                        double extract_seconds) {
  std::string json = "{\n";
  json += "  \"input\": " + cli::json_string(input) + ",\n";
  json += "  \"dims\": [" + std::to_string(volume.dims[0]) + ", " + std::to_string(volume.dims[1]) + ", " +
          std::to_string(volume.dims[2]) + "],\n";
  json += "  \"source_type\": " + cli::json_string(to_string(volume.source_type)) + ",\n";
  json += "  \"iso\": " + number(r.iso) + ",\n";
  json += "  \"flipped\": " + std::string(r.flipped ? "true" : "false") + ",\n";
  json += "  \"nonfinite_samples\": " + std::to_string(r.nonfinite_samples) + ",\n";
  json += "  \"smooth_sigma\": " + number(r.smooth_sigma) + ",\n";
  json += "  \"min_component_vertices\": " + std::to_string(r.min_component_vertices) + ",\n";
  json += "  \"topology_tolerance\": " + cli::topology_tolerance_json(r) + ",\n";
  json += "  \"before\": " + statistics_json(r.before) + ",\n";
  json += "  \"after\": " + statistics_json(r.after) + ",\n";
  json += "  \"dropped\": {\"components\": " + std::to_string(r.dropped_components) +
          ", \"vertices\": " + std::to_string(r.dropped_vertices) +
          ", \"triangles\": " + std::to_string(r.dropped_triangles) + ", \"area\": " + number(r.dropped_area) + "},\n";
  json += "  \"sharp_vertices\": " + std::to_string(r.sharp_vertices) + ",\n";
  json += "  \"centroid_vertices\": " + std::to_string(r.centroid_vertices) + ",\n";
  json += "  \"load_seconds\": " + number(load_seconds) + ",\n";
  json += "  \"extract_seconds\": " + number(extract_seconds) + "\n}\n";
  return json;
}

}  // namespace

int extract(const Args& raw) {
  cli::CommandSpec spec{
      "extract",
      "INPUT --iso V [reader options] [extraction options] -o MESH.ply|MESH.obj",
      "Extracts the isosurface of a volume as a 2-manifold, consistently oriented triangle mesh (normals\n"
      "toward lower values). INPUT is .raw, .nrrd/.nhdr, .vtk, .vti, .vdb or builtin:NAME[:N] with NAME one of\n"
      "sphere, torus, genus3, marschner-lobb, mixing (--iso defaults to 0 for these); with --dims and --type,\n"
      "any file is read as raw samples. Vertices where the surface meets an edge of the volume box are marked\n"
      "sharp (PLY vertex property 'sharp'). Prints the value range on load ('isowave info VOLUME' shows it\n"
      "with a histogram, to choose V) and a topology report.",
      {{"iso", true, "isovalue (samples >= V are inside)", "V"}},
      1,
      1,
      "extract engine.nrrd --iso 100 --min-component-vertices 50 -o engine.ply"};
  cli::add_volume_options(spec.options);
  cli::add_extraction_options(spec.options);
  spec.options.push_back({"ascii", false, "write ASCII PLY instead of binary", ""});
  spec.options.push_back({"stats-json", true, "also write the report as JSON", "FILE"});
  spec.options.push_back({"quiet", false, "print nothing on success", ""});
  spec.options.push_back(cli::force_option());
  spec.options.push_back({"output", true, "output mesh (.ply or .obj)", "MESH"});
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  const std::string& input = args.positional()[0];
  const std::string output = args.require("output");
  if (args.has("stats-json")) cli::check_outputs(args, {output, args.get("stats-json")});
  else cli::check_outputs(args, {output});
  if (mesh_format_from_path(output) == MeshFormat::Off)
    throw Error(ErrorKind::InvalidArgument, output + ": extract writes .ply or .obj");
  if (!args.has("iso") && !cli::is_builtin_volume(input))
    throw Error(ErrorKind::InvalidArgument, "missing required option --iso (only builtin: inputs default to 0)");
  IsosurfaceOptions options = cli::extraction_options(args);
  options.iso = args.get_double("iso", 0.0);
  const VolumeReadOptions read_options = cli::volume_read_options(args);

  const auto load_start = Clock::now();
  const Volume volume = read_volume(input, read_options);
  const double load_seconds = seconds_since(load_start);
  cli::report_loaded_volume("extract", input, volume,
                            args.has("quiet") ? cli::LoadReport::Nothing : cli::LoadReport::RangeAndWarnings);

  const auto extract_start = Clock::now();
  Isosurface result = extract_isosurface(volume, options);
  const double extract_seconds = seconds_since(extract_start);
  if (result.mesh.face_count() == 0)  // the range of the field the surface was extracted from
    throw empty_isosurface_error(input, options.iso,
                                 options.smooth_sigma > 0 ? gaussian_smoothed(volume, options.smooth_sigma) : volume,
                                 result.report.topology.changed() ? options.topology_tolerance : 0);
  MeshWriteOptions write_options;
  write_options.ascii = args.has("ascii");
  write_mesh(output, result.mesh, write_options);
  if (args.has("stats-json")) {
    AtomicFileWriter writer(args.get("stats-json"));
    writer.write(report_json(input, volume, result.report, load_seconds, extract_seconds));
    writer.commit();
  }

  if (!args.has("quiet")) {
    const IsosurfaceReport& r = result.report;
    std::printf("%s: %zu x %zu x %zu %s samples, spacing %g %g %g (loaded in %.2f s)\n", input.c_str(), volume.dims[0],
                volume.dims[1], volume.dims[2], to_string(volume.source_type), volume.spacing.x, volume.spacing.y,
                volume.spacing.z, load_seconds);
    if (r.nonfinite_samples) std::printf("  %zu NaN/Inf samples treated as outside\n", r.nonfinite_samples);
    std::printf("iso %g%s (extracted in %.2f s)\n", r.iso, r.flipped ? ", flipped" : "", extract_seconds);
    const bool cleaned = r.smooth_sigma > 0 || r.topology_tolerance > 0 || r.min_component_vertices > 1;
    print_statistics(cleaned ? "before clean-up" : "surface", r.before);
    if (cleaned) {
      if (r.smooth_sigma > 0) std::printf("smoothed with a Gaussian of sigma %g voxels\n", r.smooth_sigma);
      if (r.topology_tolerance > 0) std::printf("%s\n", cli::topology_tolerance_line(r).c_str());
      if (r.min_component_vertices > 1)
        std::printf("dropped %zu components under %zu vertices (%zu vertices, %zu triangles, area %.6g)\n",
                    r.dropped_components, r.min_component_vertices, r.dropped_vertices, r.dropped_triangles,
                    r.dropped_area);
      print_statistics("after clean-up", r.after);
    }
    std::printf("%s: %zu vertices (%zu sharp), %zu triangles\n", output.c_str(), result.mesh.vertex_count(),
                r.sharp_vertices, result.mesh.face_count());
  }
  return 0;
}

}  // namespace isowave::commands
