// isowave subdivide: the paper's subdivision operator S (synthesis with zero
// wavelet coefficients), optionally followed by projection to the limit.
#include <chrono>
#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "isowave/core/error.h"
#include "isowave/core/memory_check.h"
#include "isowave/core/mesh_io.h"
#include "isowave/pipeline/prepare.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/limit_surface.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave::commands {

int subdivide(const Args& raw) {
  const cli::CommandSpec spec{
      "subdivide",
      "MESH --levels L [--limit] [--ascii] -o OUT.ply|OUT.obj|OUT.off",
      "Refines MESH (any polygons, any genus, boundaries) L times with the subdivision operator S of\n"
      "Bertram et al. 2000 (wavelet synthesis with every coefficient zero). Boundary edges are sharp;\n"
      "the PLY vertex property 'sharp' (uchar 1) marks sharp vertices on input and output.",
      {{"levels", true, "subdivision levels, 0..8", "L"},
       {"limit", false, "move the level-L vertices to the limit surface (OpenSubdiv)", ""},
       {"ascii", false, "write ASCII PLY instead of binary", ""},
       {"quiet", false, "print nothing on success", ""},
       cli::force_option(),
       {"output", true, "output mesh (.ply, .obj or .off)", "OUT"}},
      1,
      1,
      "subdivide engine_base.ply --levels 2 --limit -o engine_smooth.ply"};
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  const int levels = args.get_int("levels", -1, 0, 8);
  if (levels < 0) throw Error(ErrorKind::InvalidArgument, "missing required option --levels");
  const std::string output = args.require("output");
  cli::check_outputs(args, {output});
  mesh_format_from_path(output);  // reject a bad extension before any work

  const auto start = std::chrono::steady_clock::now();
  const std::string& input = args.positional()[0];
  PolygonMesh base = read_mesh(input);
  const std::size_t unreferenced = remove_unreferenced_vertices(base);
  // Peak about 80 bytes per fine vertex (8.5 GB at 105 M), more for the limit surface.
  check_memory(static_cast<double>(fine_vertex_count(base, levels)), args.has("limit") ? 160 : 100,
                    "--levels " + std::to_string(levels));
  const SubdivisionHierarchy hierarchy(base, levels);
  const std::vector<Vec3> points = subdivide(hierarchy, base.positions);
  PolygonMesh result = hierarchy.control_mesh(levels, points);
  if (args.has("limit")) result.positions = limit_surface(result).positions;
  MeshWriteOptions options;
  options.ascii = args.has("ascii");
  write_mesh(output, result, options);

  if (!args.has("quiet")) {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%s: %zu vertices, %zu faces", input.c_str(), base.vertex_count(), base.face_count());
    if (unreferenced) std::printf(" (%zu unreferenced vertices dropped)", unreferenced);
    std::printf("\n%s: level %d%s, %zu vertices, %zu %s, %zu sharp vertices (%.2f s)\n", output.c_str(), levels,
                args.has("limit") ? " limit surface" : "", result.vertex_count(), result.face_count(),
                levels > 0 ? "quads" : "faces", result.sharp_count(), seconds);
  }
  return 0;
}

}  // namespace isowave::commands
