#include "isowave/transform/hierarchy.h"

#include <algorithm>
#include <limits>

#include <opensubdiv/far/topologyLevel.h>

#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "opensubdiv_bridge.h"

namespace isowave {

using OpenSubdiv::Far::TopologyLevel;

namespace {

template <class T>
std::size_t vector_bytes(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

// Extracts the arrays of the refinement from `parent` to the next level.
// `flagged_sharp` gives the sharp flags of the parent's vertices.
RefinementStep make_step(const TopologyLevel& parent, const std::vector<std::uint8_t>& flagged_sharp) {
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
  for (std::uint32_t v = 0; v < V; ++v) {
    if ((v < flagged_sharp.size() && flagged_sharp[v]) || sharp_edge_count[v] >= 3) s.vertex_rule[v] = VertexRule::Sharp;
    else if (sharp_edge_count[v] == 2) s.vertex_rule[v] = VertexRule::Crease;
    else s.vertex_rule[v] = VertexRule::Smooth;
  }

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
    s.edge_smooth[e] = !edge_sharp[e] && s.vertex_rule[ends[0]] != VertexRule::Sharp &&
                       s.vertex_rule[ends[1]] != VertexRule::Sharp;
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

std::size_t RefinementStep::memory_bytes() const {
  return sizeof(*this) + vector_bytes(edge_vertices) + vector_bytes(edge_faces) + vector_bytes(edge_smooth) +
         vector_bytes(face_offsets) + vector_bytes(face_vertices) + vector_bytes(face_edges) +
         vector_bytes(vertex_edge_offsets) + vector_bytes(vertex_edges) + vector_bytes(vertex_face_offsets) +
         vector_bytes(vertex_faces) + vector_bytes(vertex_rule) + vector_bytes(crease_vertices) +
         vector_bytes(crease_edges);
}

SubdivisionHierarchy::SubdivisionHierarchy(const PolygonMesh& base, int levels) {
  if (levels < 0 || levels > kMaxLevels)
    throw Error(ErrorKind::InvalidArgument,
                "subdivision levels must be in 0.." + std::to_string(kMaxLevels) + ", got " + std::to_string(levels));
  require_manifold(base, "base mesh");
  base_.face_offsets = base.face_offsets;
  base_.face_vertices = base.face_vertices;
  base_.sharp = base.sharp;
  base_.positions.assign(base.vertex_count(), Vec3{});

  // Check the size before refining: V_l = V + F + E of level l-1, and every
  // finer level has F' = sum of face sizes, E' = 2E + sum of face sizes.
  {
    double v = static_cast<double>(base.vertex_count());
    double f = static_cast<double>(base.face_count());
    double corners = static_cast<double>(base.face_vertices.size());
    double e = (corners + static_cast<double>(summarize_topology(base).boundary_edges)) / 2;
    for (int l = 0; l < levels; ++l) {
      const double next_v = v + f + e, next_f = corners, next_e = 2 * e + corners;
      v = next_v; f = next_f; e = next_e; corners = 4 * next_f;
    }
    if (v >= static_cast<double>(std::numeric_limits<std::int32_t>::max()))
      throw Error(ErrorKind::InvalidArgument, "the finest level would have " + std::to_string(static_cast<long long>(v)) +
                                                  " vertices, more than 32-bit indices allow; use fewer levels");
  }

  vertex_counts_.push_back(base.vertex_count());
  if (levels == 0) return;
  auto refiner = detail::make_refiner(base_);
  OpenSubdiv::Far::TopologyRefiner::UniformOptions options(levels);
  options.fullTopologyInLastLevel = false;
  refiner->RefineUniform(options);
  for (int l = 0; l < levels; ++l) {
    steps_.push_back(make_step(refiner->GetLevel(l), base_.sharp));
    vertex_counts_.push_back(steps_.back().child_vertex_count());
  }
}

int SubdivisionHierarchy::level_of_index(std::size_t index) const {
  const auto it = std::upper_bound(vertex_counts_.begin(), vertex_counts_.end(), index);
  return static_cast<int>(it - vertex_counts_.begin());
}

std::vector<std::uint8_t> SubdivisionHierarchy::sharp_flags(int level) const {
  std::vector<std::uint8_t> flags(vertex_count(level), 0);
  std::copy(base_.sharp.begin(), base_.sharp.end(), flags.begin());
  return flags;
}

PolygonMesh SubdivisionHierarchy::control_mesh(int level, const std::vector<Vec3>& positions) const {
  PolygonMesh mesh;
  const std::size_t n = vertex_count(level);
  mesh.positions.assign(positions.begin(), positions.begin() + static_cast<std::ptrdiff_t>(std::min(n, positions.size())));
  mesh.positions.resize(n);
  if (base_.sharp_count() > 0) mesh.sharp = sharp_flags(level);
  if (level == 0) {
    mesh.face_offsets = base_.face_offsets;
    mesh.face_vertices = base_.face_vertices;
    return mesh;
  }
  // Each parent face with n corners splits into n quads: corner k, the e
  // vertex of edge k, the f vertex, the e vertex of edge k-1 (orientation kept).
  const RefinementStep& s = step(level);
  mesh.face_vertices.reserve(4 * std::size_t{s.face_offsets.back()});
  mesh.face_offsets.reserve(std::size_t{s.face_offsets.back()} + 1);
  for (std::uint32_t f = 0; f < s.parent_face_count; ++f) {
    const std::uint32_t begin = s.face_offsets[f], end = s.face_offsets[f + 1];
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::uint32_t previous = k == begin ? end - 1 : k - 1;
      mesh.add_face({s.face_vertices[k], s.face_edges[k], s.first_face_vertex() + f, s.face_edges[previous]});
    }
  }
  return mesh;
}

std::size_t SubdivisionHierarchy::memory_bytes() const {
  std::size_t bytes = sizeof(*this) + vector_bytes(base_.positions) + vector_bytes(base_.face_offsets) +
                      vector_bytes(base_.face_vertices) + vector_bytes(base_.sharp) + vector_bytes(vertex_counts_);
  for (const RefinementStep& s : steps_) bytes += s.memory_bytes();
  return bytes;
}

}  // namespace isowave
