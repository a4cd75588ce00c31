// The reference refinement builder (refinement_steps.h): OpenSubdiv's
// uniform refinement read level by level, which a test compares with the
// library's own builder array by array. Apart from the rest of the
// refinement so that the decoder builds without OpenSubdiv (the browser's).
#include <cstdint>
#include <vector>

#include <opensubdiv/far/topologyLevel.h>
#include <opensubdiv/far/topologyRefiner.h>

#include "isowave/core/error.h"
#include "isowave/transform/refinement_steps.h"
#include "opensubdiv_bridge.h"
#include "sharp_rules.h"

namespace isowave::detail {

using OpenSubdiv::Far::TopologyLevel;

namespace {

// Extracts the arrays of the refinement from `parent` to the next level.
// `flagged_sharp` gives the sharp flags of the parent's vertices.
RefinementStep make_step_from_opensubdiv(const TopologyLevel& parent, const std::vector<std::uint8_t>& flagged_sharp) {
  RefinementStep s;
  const auto V = static_cast<std::uint32_t>(parent.GetNumVertices());
  const auto F = static_cast<std::uint32_t>(parent.GetNumFaces());
  const auto E = static_cast<std::uint32_t>(parent.GetNumEdges());
  s.parent_vertex_count = V;
  s.parent_face_count = F;
  s.parent_edge_count = E;
  const std::uint32_t f0 = s.first_face_vertex();
  const std::uint32_t e0 = s.first_edge_vertex();

  // The in-place layout depends on OpenSubdiv numbering children v, f, e in
  // parent order; check rather than assume.
  for (std::uint32_t v = 0; v < V; ++v)
    if (static_cast<std::uint32_t>(parent.GetVertexChildVertex(static_cast<int>(v))) != v)
      throw Error(ErrorKind::Unsupported, "unexpected OpenSubdiv child vertex order");
  for (std::uint32_t f = 0; f < F; ++f)
    if (static_cast<std::uint32_t>(parent.GetFaceChildVertex(static_cast<int>(f))) != f0 + f)
      throw Error(ErrorKind::Unsupported, "unexpected OpenSubdiv child vertex order");
  for (std::uint32_t e = 0; e < E; ++e)
    if (static_cast<std::uint32_t>(parent.GetEdgeChildVertex(static_cast<int>(e))) != e0 + e)
      throw Error(ErrorKind::Unsupported, "unexpected OpenSubdiv child vertex order");

  // Sharp edges are the boundary edges; vertex rules follow from them.
  std::vector<std::uint8_t> edge_sharp(E);
  std::vector<std::uint8_t> sharp_edge_count(V, 0);
  for (std::uint32_t e = 0; e < E; ++e) {
    edge_sharp[e] = parent.IsEdgeBoundary(static_cast<int>(e)) ? 1 : 0;
    if (!edge_sharp[e]) continue;
    for (int endpoint : parent.GetEdgeVertices(static_cast<int>(e)))
      sharp_edge_count[endpoint] = static_cast<std::uint8_t>(std::min(255, sharp_edge_count[endpoint] + 1));
  }
  s.vertex_rule.resize(V);
  for (std::uint32_t v = 0; v < V; ++v)
    s.vertex_rule[v] = vertex_rule(v < flagged_sharp.size() && flagged_sharp[v], sharp_edge_count[v]);

  s.edge_vertices.resize(2 * std::size_t{E});
  s.edge_faces.resize(2 * std::size_t{E});
  s.edge_smooth.resize(E);
  for (std::uint32_t e = 0; e < E; ++e) {
    const auto ends = parent.GetEdgeVertices(static_cast<int>(e));
    const auto faces = parent.GetEdgeFaces(static_cast<int>(e));
    s.edge_vertices[2 * e] = static_cast<std::uint32_t>(ends[0]);
    s.edge_vertices[2 * e + 1] = static_cast<std::uint32_t>(ends[1]);
    s.edge_faces[2 * e] = f0 + static_cast<std::uint32_t>(faces[0]);
    s.edge_faces[2 * e + 1] = f0 + static_cast<std::uint32_t>(faces[faces.size() > 1 ? 1 : 0]);
    s.edge_smooth[e] = edge_is_smooth(edge_sharp[e], s.vertex_rule[ends[0]], s.vertex_rule[ends[1]]);
  }

  s.face_offsets.resize(std::size_t{F} + 1);
  s.face_offsets[0] = 0;
  for (std::uint32_t f = 0; f < F; ++f)
    s.face_offsets[f + 1] = s.face_offsets[f] + static_cast<std::uint32_t>(parent.GetFaceVertices(static_cast<int>(f)).size());
  s.face_vertices.resize(s.face_offsets[F]);
  s.face_edges.resize(s.face_offsets[F]);
  for (std::uint32_t f = 0; f < F; ++f) {
    const auto corners = parent.GetFaceVertices(static_cast<int>(f));
    const auto edges = parent.GetFaceEdges(static_cast<int>(f));
    for (int k = 0; k < corners.size(); ++k) {
      s.face_vertices[s.face_offsets[f] + k] = static_cast<std::uint32_t>(corners[k]);
      s.face_edges[s.face_offsets[f] + k] = e0 + static_cast<std::uint32_t>(edges[k]);
    }
  }

  s.vertex_edge_offsets.resize(std::size_t{V} + 1);
  s.vertex_face_offsets.resize(std::size_t{V} + 1);
  s.vertex_edge_offsets[0] = s.vertex_face_offsets[0] = 0;
  for (std::uint32_t v = 0; v < V; ++v) {
    s.vertex_edge_offsets[v + 1] = s.vertex_edge_offsets[v] + static_cast<std::uint32_t>(parent.GetVertexEdges(static_cast<int>(v)).size());
    s.vertex_face_offsets[v + 1] = s.vertex_face_offsets[v] + static_cast<std::uint32_t>(parent.GetVertexFaces(static_cast<int>(v)).size());
  }
  s.vertex_edges.resize(s.vertex_edge_offsets[V]);
  s.vertex_faces.resize(s.vertex_face_offsets[V]);
  for (std::uint32_t v = 0; v < V; ++v) {
    const auto edges = parent.GetVertexEdges(static_cast<int>(v));
    const auto faces = parent.GetVertexFaces(static_cast<int>(v));
    for (int k = 0; k < edges.size(); ++k) s.vertex_edges[s.vertex_edge_offsets[v] + k] = e0 + static_cast<std::uint32_t>(edges[k]);
    for (int k = 0; k < faces.size(); ++k) s.vertex_faces[s.vertex_face_offsets[v] + k] = f0 + static_cast<std::uint32_t>(faces[k]);
    if (s.vertex_rule[v] != VertexRule::Crease) continue;
    s.crease_vertices.push_back(v);
    for (int edge : edges)
      if (edge_sharp[edge]) s.crease_edges.push_back(e0 + static_cast<std::uint32_t>(edge));
  }
  return s;
}

}  // namespace

std::vector<RefinementStep> build_refinement_steps_with_opensubdiv(const PolygonMesh& base, int levels) {
  std::vector<RefinementStep> steps;
  if (levels <= 0) return steps;
  auto refiner = make_refiner(base);
  OpenSubdiv::Far::TopologyRefiner::UniformOptions options(levels);
  options.fullTopologyInLastLevel = false;
  refiner->RefineUniform(options);
  for (int l = 0; l < levels; ++l) steps.push_back(make_step_from_opensubdiv(refiner->GetLevel(l), base.sharp));
  return steps;
}

}  // namespace isowave::detail
