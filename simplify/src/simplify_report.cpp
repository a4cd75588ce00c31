// What simplify() reports: the input's topology and the lower bound it
// implies, the output's histograms, and the one-line-per-figure text.
#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "simplify_steps.h"

namespace isowave::simplify {

namespace {

// Fewest vertices the rules allow for one component (see SimplifyReport).
std::size_t component_lower_bound(const CollapseMesh::ComponentCounts& counts) {
  const long long g = counts.genus();
  const long long b = static_cast<long long>(counts.boundary_loops);
  long long bound = 0;
  if (b == 0) bound = std::max(4LL, 6 * g - 6);
  else bound = std::max(3 * b, (6 * g - 6 + 3 * b + 1) / 2);
  return static_cast<std::size_t>(std::max(bound, 3LL));
}

}  // namespace

void count_input_topology(const CollapseMesh& mesh, SimplifyReport& report) {
  for (const CollapseMesh::ComponentCounts& counts : mesh.components()) {
    ++report.input_components;
    report.input_boundary_loops += counts.boundary_loops;
    report.input_genus += counts.genus();
    report.lower_bound_vertices += component_lower_bound(counts);
  }
}

void fill_histograms(const PolygonMesh& mesh, int max_valence, SimplifyReport& report) {
  report.face_size_histogram.clear();
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::size_t size = mesh.face_size(f);
    if (report.face_size_histogram.size() <= size) report.face_size_histogram.resize(size + 1, 0);
    ++report.face_size_histogram[size];
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(mesh.face_vertices.size());
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    const std::uint32_t size = mesh.face_size(f);
    for (std::uint32_t k = 0; k < size; ++k) {
      const std::uint32_t u = face[k], w = face[(k + 1) % size];
      edges.emplace_back(std::min(u, w), std::max(u, w));
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::uint32_t> valence(mesh.vertex_count(), 0);
  std::vector<std::uint8_t> boundary(mesh.vertex_count(), 0);
  std::size_t unique_edges = 0;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    ++unique_edges;
    ++valence[edges[i].first];
    ++valence[edges[i].second];
    if (j - i == 1) boundary[edges[i].first] = boundary[edges[i].second] = 1;
    i = j;
  }
  report.output_edges = unique_edges;
  report.valence_histogram.clear();
  report.vertices_outside_valence_range = 0;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    if (report.valence_histogram.size() <= valence[v]) report.valence_histogram.resize(valence[v] + 1, 0);
    ++report.valence_histogram[valence[v]];
    const std::uint32_t low = boundary[v] ? 2 : 3;
    if (valence[v] < low || valence[v] > static_cast<std::uint32_t>(max_valence)) ++report.vertices_outside_valence_range;
  }
}

std::string format_report(const SimplifyReport& r) {
  std::string out;
  char line[512];
  const auto add = [&](const char* format, auto... values) {
    std::snprintf(line, sizeof line, format, values...);
    out += line;
  };
  add("input: %zu vertices, %zu triangles, %zu components, genus %lld, %zu boundary loops\n", r.input_vertices,
      r.input_faces, r.input_components, r.input_genus, r.input_boundary_loops);
  add("target: %zu vertices (lower bound from topology and valence <= 8: %zu)\n", r.target_vertices,
      r.lower_bound_vertices);
  if (r.input_valence_flips) add("input: %zu flips to bring valences down to the limit\n", r.input_valence_flips);
  add("collapse: %zu collapses -> %zu vertices, %zu triangles; %s\n", r.collapses, r.vertices_after_collapse,
      r.triangles_after_collapse, r.stop_reason.c_str());
  if (r.parallel_collapses)
    add("parallel: %zu collapses on two threads inside two halves of the mesh (%zu of them in the flip rounds), "
        "the rest serial; %.3f s before the first serial loop\n",
        r.parallel_collapses, r.parallel_flip_round_collapses, r.seconds_parallel);
  if (r.collapses_after_flips)
    add("valence flips: the paper's rules stalled at %zu vertices; %zu rounds, %zu more collapses after %zu flips "
        "(%zu flips undone in %zu failed attempts)\n",
        r.vertices_after_paper_collapse, r.flip_rounds, r.collapses_after_flips, r.flips, r.flips_undone,
        r.flip_attempts_failed);
  std::string rejected;
  for (int k = 1; k < kLegalityCount; ++k)
    if (r.rejected_at_pop[k]) rejected += std::string(rejected.empty() ? "" : ", ") + to_string(Legality(k)) + " " +
                                          std::to_string(r.rejected_at_pop[k]);
  if (!rejected.empty()) add("rejected when popped: %s\n", rejected.c_str());
  add("edge removal: %zu edges removed\n", r.edges_removed);
  add("base mesh: %zu vertices, %zu edges, %zu faces\n", r.output_vertices, r.output_edges, r.output_faces);
  std::string sizes;
  for (std::size_t s = 0; s < r.face_size_histogram.size(); ++s)
    if (r.face_size_histogram[s]) sizes += " " + std::to_string(s) + ":" + std::to_string(r.face_size_histogram[s]);
  add("face sizes:%s\n", sizes.c_str());
  std::string valences;
  for (std::size_t k = 0; k < r.valence_histogram.size(); ++k)
    if (r.valence_histogram[k]) valences += " " + std::to_string(k) + ":" + std::to_string(r.valence_histogram[k]);
  add("valences:%s (%zu outside 3..8 / 2..8 on the boundary)\n", valences.c_str(), r.vertices_outside_valence_range);
  if (r.distance_computed)
    add("distance input vertices -> base surface: max %.6g, rms %.6g\n", r.distance_max, r.distance_rms);
  add("time: check %.3f s, build %.3f s, queue %.3f s, collapse %.3f s (%.3f s of it in flip rounds), edge removal %.3f s, output %.3f s, "
      "distance %.3f s, total %.3f s\n",
      r.seconds_check, r.seconds_build, r.seconds_queue, r.seconds_collapse, r.seconds_flip_rounds, r.seconds_edge_removal, r.seconds_output,
      r.seconds_distance, r.seconds_total());
  return out;
}

}  // namespace isowave::simplify
