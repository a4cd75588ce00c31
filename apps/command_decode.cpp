// isowave decode: synthesis with the kept coefficients of an .isw file, written
// as a mesh at the chosen level (optionally its limit surface).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "cli.h"
#include "commands.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/region.h"
#include "isowave/codec/statistics.h"
#include "isowave/codec/view.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/transform/limit_surface.h"

namespace isowave::commands {

namespace {

// --roi / --roi-sphere: the region, or nothing.
std::optional<RegionOfInterest> region_option(const cli::Arguments& args) {
  if (args.has("roi") && args.has("roi-sphere"))
    throw Error(ErrorKind::InvalidArgument, "give at most one of --roi and --roi-sphere");
  if (!args.has("roi") && !args.has("roi-sphere")) {
    if (args.has("roi-falloff")) throw Error(ErrorKind::InvalidArgument, "--roi-falloff needs --roi or --roi-sphere");
    return std::nullopt;
  }
  RegionOfInterest region = args.has("roi") ? parse_region(args.get("roi"), false, "--roi")
                                            : parse_region(args.get("roi-sphere"), true, "--roi-sphere");
  region.falloff = args.get_double("roi-falloff", 0);
  if (!(region.falloff >= 0) || !std::isfinite(region.falloff))
    throw Error(ErrorKind::InvalidArgument, "--roi-falloff must be a non-negative distance");
  return region;
}

// region_mesh() with what --percent or --coefficients keep outside the
// region; prints what it kept unless quiet.
PolygonMesh decode_region(const cli::Arguments& args, const IswDecoded& decoded, const RegionOfInterest& region,
                        const std::string& input) {
  std::size_t outside = 0;
  if (args.has("percent")) outside = coefficients_for_percent(*decoded.hierarchy, args.get_double("percent", 0));
  if (args.has("coefficients")) outside = static_cast<std::size_t>(args.get_double("coefficients", 0));
  RegionReconstruction r;
  PolygonMesh mesh = isowave::region_mesh(decoded, region, outside, &r);
  if (!args.has("quiet"))
    std::printf("%s: region: %zu of %zu fine control points inside, %zu coefficients there, %zu kept in all (of %zu)\n",
                input.c_str(), r.inside_points, decoded.fine_vertices, r.region_coefficients, r.kept_coefficients,
                decoded.ranked.size());
  return mesh;
}

// The decoder's options from the command line: what is read (--bytes,
// --max-error), what is kept (--percent, --coefficients: outside a region,
// applied by region_mesh()) and, for a region alone, the partial read.
IswDecodeOptions decode_options(const cli::Arguments& args, const std::optional<RegionOfInterest>& region) {
  IswDecodeOptions options;
  // The surface needs no ranking unless a limit asks for it; with a region
  // the limit applies outside it, to a whole decode ranked by importance.
  const bool limited = args.has("percent") || args.has("coefficients");
  options.order = region && limited ? IswOrder::Importance : IswOrder::Index;
  if (args.has("percent")) {
    const double percent = args.get_double("percent", 100);
    if (!(percent >= 0 && percent <= 100)) throw Error(ErrorKind::InvalidArgument, "--percent must be in 0..100");
    if (!region) options.max_percent = percent;
  } else if (args.has("coefficients")) {
    const double n = args.get_double("coefficients", 0);
    if (!(n >= 0) || n != static_cast<double>(static_cast<std::uint64_t>(n)))
      throw Error(ErrorKind::InvalidArgument, "--coefficients must be a non-negative integer");
    if (!region) options.max_coefficients = static_cast<std::uint64_t>(n);
  }
  if (args.has("oracle")) {
    if (!limited || region)
      throw Error(ErrorKind::InvalidArgument, "--oracle chooses what --percent or --coefficients keep (not with --roi)");
    options.oracle = oracle_from_name(args.get("oracle"));
  }
  if (args.has("bytes")) {
    const double n = args.get_double("bytes", 0);
    if (!(n >= 1 && n <= 1e18) || n != std::floor(n))
      throw Error(ErrorKind::InvalidArgument, "--bytes must be a positive whole number");
    options.max_file_bytes = static_cast<std::uint64_t>(n);
  }
  if (args.has("max-error")) {
    options.max_error_cells = args.get_double("max-error", 0);
    if (!(options.max_error_cells > 0) || !std::isfinite(options.max_error_cells))
      throw Error(ErrorKind::InvalidArgument, "--max-error must be a positive number of cells");
  }
  // A region with nothing kept outside reads only the groups it needs (2.2).
  if (region && !limited) options.region = region;
  return options;
}

// --view and --pixel-error: view_mesh(); prints the faces per level unless quiet.
PolygonMesh decode_view(const cli::Arguments& args, const IswDecoded& decoded, const Camera& camera,
                        const std::string& input) {
  const double pixel_error = args.get_double("pixel-error", 1);
  ViewLevels levels;
  PolygonMesh mesh = view_mesh(decoded, camera, pixel_error, &levels,
                               args.has("cull-back-faces") ? BackFaces::Cull : BackFaces::Refine);
  if (!args.has("quiet")) {
    std::vector<std::size_t> count(static_cast<std::size_t>(decoded.levels) + 1, 0);
    for (const int l : levels.levels) ++count[static_cast<std::size_t>(l)];
    std::string per_level;
    for (std::size_t l = 0; l < count.size(); ++l)
      per_level += (l ? ", " : "") + std::to_string(count[l]) + " at level " + std::to_string(l);
    std::printf("%s: view at %g pixels: base faces %s; %zu outside the frustum, %zu facing away\n", input.c_str(),
                pixel_error, per_level.c_str(), levels.culled, levels.back_facing);
  }
  return mesh;
}

}  // namespace

int decode(const Args& raw) {
  const cli::CommandSpec spec{
      "decode",
      "IN.isw [--bytes N | --max-error E] [--percent P | --coefficients N [--oracle NAME] | --roi BOX | --view CAMERA.json]\n"
      "                [--level L] [--limit] [--triangulate] [--ascii] [--force] -o OUT.ply|OUT.obj|OUT.off",
      "Rebuilds the surface from the base mesh and the wavelet coefficients of IN.isw (all of them by default).\n"
      "--bytes reads only the first N bytes of the file: any prefix of a version 2 file's stream decodes to the\n"
      "best surface it allows. --max-error reads the shortest prefix whose error the file records within E.\n"
      "--percent then keeps the most important coefficients of what was read, counted as the paper does: the\n"
      "total is the number of fine control points (base vertices plus all coefficients), and the base mesh\n"
      "alone is the smallest choice: a percentage below the base mesh's share gives the base mesh, and says so.",
      {{"bytes", true, "read only the first N bytes of the file", "N"},
       {"max-error", true, "read the shortest prefix whose recorded error D is within E cells (version 2 files)", "E"},
       {"percent", true, "keep this percentage of full resolution (0..100)", "P"},
       {"coefficients", true, "keep this many wavelet coefficients (besides the base mesh)", "N"},
       {"oracle", true, "what --percent or --coefficients keep: weighted (default: class weight x magnitude), magnitude, or greedy (least error added, several syntheses)", "NAME"},
       {"roi", true, "full detail inside this box (world units), --percent or --coefficients outside (default none: the base mesh's surface); the finest level", "X0,Y0,Z0,X1,Y1,Z1"},
       {"roi-sphere", true, "the same inside this ball", "CX,CY,CZ,R"},
       {"roi-falloff", true, "with --percent or --coefficients: weight importance outside the region by a Gaussian of this width (world units)", "W"},
       {"view", true, "refine each base face as far as this camera sees it (JSON: position, target, up, fov, viewport)", "CAMERA.json"},
       {"pixel-error", true, "with --view: the detail left out may project to this many pixels (default 1)", "P"},
       {"cull-back-faces", false, "with --view: keep base faces facing away from the camera whole (a closed surface seen from outside)", ""},
       {"level", true, "write the control mesh of this level (default: the finest)", "L"},
       {"limit", false, "move the vertices to the limit surface (OpenSubdiv)", ""},
       {"triangulate", false, "split quads into triangles", ""},
       {"ascii", false, "write ASCII PLY instead of binary", ""},
       {"quiet", false, "print nothing on success", ""},
       cli::force_option(),
       {"output", true, "output mesh (.ply, .obj or .off)", "OUT"}},
      1,
      1,
      "decode engine.isw --percent 5 -o engine_5pct.ply"};
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  if (args.has("percent") && args.has("coefficients"))
    throw Error(ErrorKind::InvalidArgument, "give at most one of --percent and --coefficients");
  if (args.has("bytes") && args.has("max-error"))
    throw Error(ErrorKind::InvalidArgument, "give at most one of --bytes and --max-error");
  const std::string output = args.require("output");
  cli::check_outputs(args, {output});
  mesh_format_from_path(output);
  const auto start = std::chrono::steady_clock::now();

  const std::optional<RegionOfInterest> region = region_option(args);
  if (region && args.has("level")) throw Error(ErrorKind::InvalidArgument, "--roi gives the finest level: no --level");
  const bool view = args.has("view");
  if ((args.has("pixel-error") || args.has("cull-back-faces")) && !view)
    throw Error(ErrorKind::InvalidArgument, "--pixel-error and --cull-back-faces need --view");
  if (view && (region || args.has("level") || args.has("percent") || args.has("coefficients") || args.has("limit")))
    throw Error(ErrorKind::InvalidArgument,
                "--view chooses each face's level: no --roi, --level, --percent, --coefficients or --limit");
  IswDecodeOptions options = decode_options(args, region);
  // A view reads only the groups its frustum needs (2.2).
  if (view) {
    options.frustum = read_camera(args.get("view"));
    options.view_scope = IswDecodeOptions::ViewScope::Patch;
  }
  const std::string& input = args.positional()[0];
  IswDecoded decoded = read_isw(input, options);
  if (args.has("max-error") && decoded.stream.rate_table.empty())
    std::fprintf(stderr, "isowave decode: warning: %s records no errors: decoding the whole stream\n", input.c_str());
  if (decoded.truncated) std::fprintf(stderr, "isowave decode: warning: %s: %s\n", input.c_str(), decoded.truncation_note.c_str());
  const int level = args.get_int("level", decoded.levels, 0, decoded.levels);

  // Synthesis in the decoded array and the mesh around it: no copies of the
  // fine-level arrays.
  PolygonMesh mesh = view     ? decode_view(args, decoded, *options.frustum, input)
                     : region ? decode_region(args, decoded, *region, input)
                              : decoded.hierarchy->control_mesh(level, take_reconstruction(decoded, decoded.ranked.size(), level));
  if (args.has("limit")) mesh.positions = limit_surface(mesh).positions;
  // Base faces (level 0, or outside a region) may share two corners: their
  // quads' diagonals must not repeat an edge.
  if (args.has("triangulate"))
    mesh = triangulate(mesh, level == 0 || region || view ? QuadSplit::ShorterAvoidingEdges : QuadSplit::Shorter);
  MeshWriteOptions write_options;
  write_options.ascii = args.has("ascii");
  write_mesh(output, mesh, write_options);

  if (!args.has("quiet")) {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::size_t fine = decoded.fine_vertices, base = decoded.base_vertices;
    // The paper's count: base vertices plus kept coefficients, zeros included.
    const double base_percent = 100.0 * static_cast<double>(base) / static_cast<double>(fine);
    const double percent =
        args.has("percent")
            ? std::max(options.max_percent, base_percent)
            : 100.0 * static_cast<double>(base + std::min<std::uint64_t>(options.max_coefficients, fine - base)) /
                  static_cast<double>(fine);
    if (args.has("percent") && options.max_percent < base_percent)
      std::printf("%g%% is below the base mesh's share (%.2f%% of the fine control points): writing the base mesh "
                  "alone\n",
                  options.max_percent, base_percent);
    if (!region && !view)
      std::printf("%s: %.2f%% of %zu fine control points: base mesh + %zu non-zero coefficients (of %llu), level %d%s\n",
                input.c_str(), percent, fine, decoded.ranked.size(),
                static_cast<unsigned long long>(decoded.coefficients_total), level, args.has("limit") ? ", limit surface" : "");
    if (decoded.major_version >= 2 && decoded.stream.groups_decoded < decoded.stream.groups)
      std::printf("%s: read %llu of %llu file bytes: the headers and %zu of %zu groups' packets (%llu of %llu stream "
                  "bytes)\n",
                  input.c_str(), static_cast<unsigned long long>(decoded.file_bytes_read),
                  static_cast<unsigned long long>(decoded.file_bytes),
                  decoded.stream.groups_decoded, decoded.stream.groups,
                  static_cast<unsigned long long>(decoded.stream.decoded),
                  static_cast<unsigned long long>(decoded.stream.bytes));
    else if (decoded.major_version >= 2)
      std::printf("%s: read %llu of %llu file bytes (%llu of %llu stream bytes, %d of %d bit planes complete)\n",
                  input.c_str(), static_cast<unsigned long long>(decoded.file_bytes_read),
                  static_cast<unsigned long long>(decoded.file_bytes),
                  static_cast<unsigned long long>(decoded.stream.decoded),
                  static_cast<unsigned long long>(decoded.stream.bytes), decoded.stream.planes_decoded,
                  decoded.stream.planes);
    std::printf("%s: %zu vertices, %zu faces (%.2f s)\n", output.c_str(), mesh.vertex_count(), mesh.face_count(), seconds);
  }
  return 0;
}

}  // namespace isowave::commands
