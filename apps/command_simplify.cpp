// isowave simplify: base-mesh construction of paper Sec. 4.1 (bucket-priority
// edge collapse, then edge removal into quads and pentagons).
#include <cmath>
#include <cstdio>
#include <limits>

#include "cli.h"
#include "commands.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/extract/isosurface.h"
#include "isowave/simplify/simplify.h"

namespace isowave::commands {

int simplify(const Args& raw) {
  const cli::CommandSpec spec{
      "simplify",
      "MESH (--target-vertices N | --ratio R) [options] -o BASE.ply|BASE.obj",
      "Builds a base mesh from a 2-manifold triangle mesh (Bertram et al. 2000, Sec. 4.1): edge collapses in\n"
      "bucket-priority order keep genus, components and boundary loops and valences 3..8 (2..8 on the\n"
      "boundary); then edges are removed to form quads and pentagons. Unreferenced vertices are dropped\n"
      "first. --target-vertices 0 simplifies as far as the rules allow. The PLY vertex property 'sharp'\n"
      "(uchar 1) marks sharp vertices on input and output; sharp vertices never move.",
      {{"target-vertices", true, "stop at this many vertices (0: as far as possible)", "N"},
       {"ratio", true, "target as a fraction of the input vertex count, in (0, 1]", "R"},
       {"no-edge-removal", false, "keep the triangles of the collapse phase", ""},
       {"flips", false, "valence-lowering edge flips: the input's vertices above valence 8 first, then where the paper's rules stall (a base up to 16% smaller on high-genus surfaces; off by default and in convert: the fits then lie farther from noisy isosurfaces)", ""},
       {"no-boundary-curve-error", false, "the paper's collapse error (4.1) only: boundary collapses pay nothing for moving the boundary curve within the surface", ""},
       {"eager-stencil", false, "re-evaluate every edge of a collapse's stencil at once, as the paper does (slower)", ""},
       {"batch-factor", true, "in the two-thread phase (large meshes) and the flip round, collapse the edges whose errors lie within a factor F of the best one a batch at a time, in memory order (default 10, faster; 1: one at a time in priority order, as the paper does)", "F"},
       {"flip-threshold", true, "with --flips: a flip needs the old and new triangles' unit normals to have dot >= D, in [-1, 1] (default 0.7)", "D"},
       {"normal-threshold", true, "edge removal needs unit face normals with dot >= D, in [-1, 1] (default 0.5)",
        "D"},
       {"topology-tolerance", true,
        "first drop components under T across, in the mesh's units (cells for meshes `extract` made from a "
        "unit-spaced grid); handles and tunnels are removed at extraction, where the field is known",
        "T"},
       {"no-distance", false, "skip the distance from the input vertices to the base mesh", ""},
       {"ascii", false, "write ASCII PLY instead of binary", ""},
       {"quiet", false, "print nothing on success", ""},
       cli::force_option(),
       {"output", true, "base mesh (.ply or .obj)", "BASE"}},
      1,
      1,
      "simplify engine.ply --ratio 0.0625 -o engine_base.ply"};
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  if (args.has("target-vertices") == args.has("ratio"))
    throw Error(ErrorKind::InvalidArgument, "give exactly one of --target-vertices and --ratio");
  const std::string output = args.require("output");
  cli::check_outputs(args, {output});
  if (mesh_format_from_path(output) == MeshFormat::Off)
    throw Error(ErrorKind::InvalidArgument, "the base mesh must be written as .ply or .obj: " + output);
  simplify::SimplifyOptions options;
  const double ratio = args.get_double("ratio", 1.0);
  if (args.has("ratio") && !(ratio > 0 && ratio <= 1))
    throw Error(ErrorKind::InvalidArgument, "--ratio must be in (0, 1], got " + args.get("ratio"));
  const int target = args.get_int("target-vertices", 0, 0, std::numeric_limits<int>::max());
  options.edge_removal = !args.has("no-edge-removal");
  options.valence_flips = args.has("flips");
  options.boundary_curve_error = !args.has("no-boundary-curve-error");
  options.lazy_stencil = !args.has("eager-stencil");
  options.batch_error_factor = args.get_double("batch-factor", options.batch_error_factor);
  if (!(options.batch_error_factor >= 1 && options.batch_error_factor <= 1e20))
    throw Error(ErrorKind::InvalidArgument, "--batch-factor must be in [1, 1e20], got " + args.get("batch-factor"));
  options.flip_min_normal_dot = args.get_double("flip-threshold", options.flip_min_normal_dot);
  if (!(options.flip_min_normal_dot >= -1 && options.flip_min_normal_dot <= 1))
    throw Error(ErrorKind::InvalidArgument, "--flip-threshold must be in [-1, 1], got " + args.get("flip-threshold"));
  options.edge_removal_min_normal_dot = args.get_double("normal-threshold", 0.5);
  if (!(options.edge_removal_min_normal_dot >= -1 && options.edge_removal_min_normal_dot <= 1))
    throw Error(ErrorKind::InvalidArgument, "--normal-threshold must be in [-1, 1], got " + args.get("normal-threshold"));
  options.compute_distance = !args.has("no-distance");

  const std::string& input = args.positional()[0];
  PolygonMesh mesh = read_mesh(input);
  const std::size_t unreferenced = remove_unreferenced_vertices(mesh);
  const double tolerance = args.get_double("topology-tolerance", 0.0);
  if (!(tolerance >= 0))
    throw Error(ErrorKind::InvalidArgument, "--topology-tolerance must be >= 0, got " + args.get("topology-tolerance"));
  const ComponentRemoval specks = remove_components_under(mesh, tolerance);
  options.target_vertices = args.has("ratio")
                                ? static_cast<std::size_t>(std::llround(ratio * double(mesh.vertex_count())))
                                : static_cast<std::size_t>(target);
  const simplify::SimplifyResult result = simplify::simplify(mesh, options);
  MeshWriteOptions write_options;
  write_options.ascii = args.has("ascii");
  write_mesh(output, result.base, write_options);

  if (!args.has("quiet")) {
    std::printf("%s", input.c_str());
    if (unreferenced) std::printf(" (%zu unreferenced vertices dropped)", unreferenced);
    if (tolerance > 0)
      std::printf("\ntopology tolerance %g: dropped %zu components under %g across (%zu vertices, area %.6g)",
                  tolerance, specks.components, tolerance, specks.vertices, specks.area);
    std::printf("\n%s", simplify::format_report(result.report).c_str());
    std::printf("written: %s\n", output.c_str());
  }
  return 0;
}

}  // namespace isowave::commands
