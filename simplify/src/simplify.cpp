// simplify(): the driver of base-mesh construction (paper Sec. 4.1), a list
// of steps: check, build the corner table, collapse, edge removal, report.
#include "isowave/simplify/simplify.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "edge_removal.h"
#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "simplify_steps.h"
#include "surface_map_tracker.h"

namespace isowave::simplify {

namespace {

void check_options(const SimplifyOptions& options) {
  const auto fail = [](const std::string& what) { throw Error(ErrorKind::InvalidArgument, "simplify: " + what); };
  if (!(options.edge_removal_min_normal_dot >= -1 && options.edge_removal_min_normal_dot <= 1))
    fail("edge-removal normal threshold must be in [-1, 1]");
  if (!(options.collapse_min_normal_dot >= -1 && options.collapse_min_normal_dot < 1))
    fail("collapse normal threshold must be in [-1, 1)");
  if (!(options.flip_min_normal_dot >= -1 && options.flip_min_normal_dot <= 1))
    fail("flip normal threshold must be in [-1, 1]");
  if (options.max_valence < 3 || options.max_valence > 32) fail("maximum valence must be in 3..32");
  if (options.bucket_count < 1) fail("bucket count must be at least 1");
  if (options.max_flip_rounds < 0) fail("flip rounds must not be negative");
  if (!(options.batch_error_factor >= 1 && options.batch_error_factor <= 1e20))
    fail("batch error factor must be in [1, 1e20]");
  if (!(options.max_vertex_area_share >= 0 && options.max_vertex_area_share <= 1e6))
    fail("area share must be in [0, 1e6]");
}

// The triangles' total area.
double surface_area(const PolygonMesh& mesh) {
  double area = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* v = mesh.face_begin(f);
    area += 0.5 * std::sqrt(squared_norm(cross(mesh.positions[v[1]] - mesh.positions[v[0]],
                                               mesh.positions[v[2]] - mesh.positions[v[0]])));
  }
  return area;
}

// Error for anything wrong with the data.
void check_input(const PolygonMesh& input, const std::string& source) {
  validate_indices(input, source);
  for (std::size_t f = 0; f < input.face_count(); ++f)
    if (input.face_size(f) != 3)
      throw Error(ErrorKind::Unsupported, source + ": face " + std::to_string(f) + " has " +
                                              std::to_string(input.face_size(f)) +
                                              " sides; base-mesh construction needs a triangle mesh");
  if (input.vertex_count() >= (std::size_t{1} << 31) || input.face_vertices.size() >= (std::size_t{1} << 31))
    throw Error(ErrorKind::Unsupported, source + ": more than 2^31 vertices or corners");
}

// The corner table, with the input vertices above the valence limit flipped
// down when valence flips are on (marching cubes makes a few of valence
// 9..12; no collapse may touch them otherwise).
// With a surface map, its tracker is attached before the flips, and `vertex_order`
// receives the table's order.
CollapseMesh build_collapse_mesh(const PolygonMesh& input, const SimplifyOptions& options, const std::string& source,
                                 SimplifyReport& report, std::unique_ptr<SurfaceMapTracker>& tracker,
                                 std::vector<std::uint32_t>& vertex_order) {
  CollapseRules rules;
  rules.max_valence = options.max_valence;
  rules.min_normal_dot = options.collapse_min_normal_dot;
  rules.boundary_curve_error = options.boundary_curve_error;
  rules.flip_min_normal_dot = options.flip_min_normal_dot;
  if (options.max_vertex_area_share > 0 && options.target_vertices > 0)
    rules.max_vertex_area = options.max_vertex_area_share * surface_area(input) / double(options.target_vertices);
  const bool mapped = options.surface_map == SurfaceMapping::Build;
  CollapseMesh mesh = build_table(input, rules, source, mapped ? &vertex_order : nullptr);
  if (mapped) {
    tracker = std::make_unique<SurfaceMapTracker>(mesh);
    mesh.set_surface_map_tracker(tracker.get());
  }
  if (options.valence_flips) {
    std::vector<std::uint32_t> flipped;
    for (std::uint32_t v = 0; v < mesh.vertex_slots(); ++v) {
      const int excess = mesh.vertex_alive(v) ? int(mesh.valence(v)) - options.max_valence : 0;
      if (excess > 0) mesh.lower_valence(v, excess, nullptr, 0, flipped);
    }
    report.input_valence_flips = flipped.size();
    if (options.validate_every_collapse && !mesh.validate().empty())
      throw std::logic_error("simplify: invariant broken by the input flips: " + mesh.validate());
  }
  count_input_topology(mesh, report);
  return mesh;
}

// Distance from every input vertex to the base mesh surface.
void measure_distance(const PolygonMesh& input, const PolygonMesh& base, SimplifyReport& report) {
  const std::vector<double> distances = BinnedSurfaceDistance(base).distances(input.positions);
  double sum = 0;
  for (double d : distances) {
    sum += d * d;
    report.distance_max = std::max(report.distance_max, d);
  }
  report.distance_computed = true;
  report.distance_rms = distances.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(distances.size()));
}

}  // namespace

SimplifyResult simplify(const PolygonMesh& input, const SimplifyOptions& options, ProgressSink& progress) {
  check_options(options);
  SimplifyResult result;
  SimplifyReport& report = result.report;
  Clock::time_point clock = Clock::now();
  const std::string source = "simplify input";
  check_input(input, source);
  report.input_vertices = input.vertex_count();
  report.input_faces = input.face_count();
  report.seconds_check = seconds_since(clock);

  progress.begin_stage("simplify: build");
  std::unique_ptr<SurfaceMapTracker> tracker;
  std::vector<std::uint32_t> vertex_order;
  CollapseMesh mesh = build_collapse_mesh(input, options, source, report, tracker, vertex_order);
  progress.end_stage();
  report.seconds_build = seconds_since(clock);

  collapse_to_target(mesh, options, report, progress, clock);

  std::vector<std::uint32_t> vertex_map;
  result.base = mesh.to_polygon_mesh(tracker ? &vertex_map : nullptr);
  if (tracker) {
    result.map = tracker->finish(mesh, vertex_map, vertex_order);
    tracker.reset();
  }
  {
    // Free the corner table before the polygon phase.
    CollapseMesh released = std::move(mesh);
  }
  if (options.edge_removal) {
    progress.begin_stage("simplify: edge removal");
    report.edges_removed = remove_edges(result.base, options.edge_removal_min_normal_dot,
                                        options.surface_map == SurfaceMapping::Build ? &result.map.triangle_face : nullptr);
    progress.end_stage();
  }
  report.seconds_edge_removal = seconds_since(clock);

  report.output_vertices = result.base.vertex_count();
  report.output_faces = result.base.face_count();
  fill_histograms(result.base, options.max_valence, report);
  report.seconds_output = seconds_since(clock);

  if (options.compute_distance) {
    progress.begin_stage("simplify: distance");
    measure_distance(input, result.base, report);
    progress.end_stage();
    report.seconds_distance = seconds_since(clock);
  }
  return result;
}

}  // namespace isowave::simplify
