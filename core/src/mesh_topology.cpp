#include "isowave/core/mesh_topology.h"

#include <algorithm>
#include <numeric>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"

namespace isowave {
namespace {

constexpr std::uint32_t kNone = ~std::uint32_t{0};

// Half-edge view of a polygon mesh built from flat arrays: corner c of the
// face list is the half-edge from face_vertices[c] to the next corner's vertex.
struct HalfEdges {
  const PolygonMesh& mesh;
  std::vector<std::uint32_t> face_of;    // per corner
  std::vector<std::uint32_t> opposite;   // per corner, kNone on the boundary
  std::vector<std::uint32_t> outgoing;   // per vertex: one outgoing corner (a boundary one if any)
  std::vector<std::uint32_t> out_degree; // per vertex

  explicit HalfEdges(const PolygonMesh& m) : mesh(m) {}

  std::uint32_t next(std::uint32_t c) const {
    const std::uint32_t f = face_of[c];
    return c + 1 == mesh.face_offsets[f + 1] ? mesh.face_offsets[f] : c + 1;
  }
  std::uint32_t prev(std::uint32_t c) const {
    const std::uint32_t f = face_of[c];
    return c == mesh.face_offsets[f] ? mesh.face_offsets[f + 1] - 1 : c - 1;
  }
  std::uint32_t origin(std::uint32_t c) const { return mesh.face_vertices[c]; }
  std::uint32_t target(std::uint32_t c) const { return mesh.face_vertices[next(c)]; }
};

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; }

std::string edge_name(std::uint32_t a, std::uint32_t b) {
  return "(" + std::to_string(a) + ", " + std::to_string(b) + ")";
}

// Builds face_of, opposite, outgoing and out_degree; throws on edges with more
// than two faces and on edges traversed twice in the same direction. One
// parallel sort of the corners by undirected edge, then a linear scan.
HalfEdges build_half_edges(const PolygonMesh& mesh, const std::string& source) {
  HalfEdges he(mesh);
  const auto corners = static_cast<std::uint32_t>(mesh.face_vertices.size());
  he.face_of.resize(corners);
  for (std::uint32_t f = 0; f < mesh.face_count(); ++f)
    std::fill(he.face_of.begin() + mesh.face_offsets[f], he.face_of.begin() + mesh.face_offsets[f + 1], f);

  struct Entry {
    std::uint64_t edge;  // (smaller vertex, larger vertex)
    std::uint32_t corner;
  };
  // Sorted by (edge, corner): a counting sort by the smaller vertex (stable,
  // so corners stay in order), then each vertex's few entries by the larger.
  const auto vertices = static_cast<std::uint32_t>(mesh.vertex_count());
  std::vector<std::uint32_t> bucket_start(std::size_t{vertices} + 1, 0);
  for (std::uint32_t c = 0; c < corners; ++c) ++bucket_start[std::min(he.origin(c), he.target(c)) + 1];
  for (std::uint32_t v = 0; v < vertices; ++v) bucket_start[v + 1] += bucket_start[v];
  std::vector<Entry> entries(corners);
  {
    std::vector<std::uint32_t> fill(bucket_start.begin(), bucket_start.end() - 1);
    for (std::uint32_t c = 0; c < corners; ++c) {
      const std::uint32_t a = he.origin(c), b = he.target(c);
      entries[fill[std::min(a, b)]++] = {edge_key(std::min(a, b), std::max(a, b)), c};
    }
  }
  const auto before = [](const Entry& x, const Entry& y) {
    return x.edge < y.edge || (x.edge == y.edge && x.corner < y.corner);
  };
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, vertices, 4096), [&](const tbb::blocked_range<std::uint32_t>& r) {
    for (std::uint32_t v = r.begin(); v < r.end(); ++v)
      std::sort(entries.begin() + bucket_start[v], entries.begin() + bucket_start[v + 1], before);
  });
  he.opposite.assign(corners, kNone);
  for (std::size_t i = 0; i < entries.size();) {
    std::size_t j = i + 1;
    while (j < entries.size() && entries[j].edge == entries[i].edge) ++j;
    const auto a = static_cast<std::uint32_t>(entries[i].edge >> 32);
    const auto b = static_cast<std::uint32_t>(entries[i].edge);
    if (j - i > 2)
      throw Error(ErrorKind::Topology,
                  source + ": non-manifold edge " + edge_name(a, b) + " is shared by more than two faces");
    if (j - i == 2) {
      const std::uint32_t c0 = entries[i].corner, c1 = entries[i + 1].corner;
      if (he.origin(c0) == he.origin(c1))
        throw Error(ErrorKind::Topology, source + ": inconsistent face orientation: edge " +
                                             edge_name(he.origin(c0), he.target(c0)) +
                                             " is traversed twice in the same direction (faces " +
                                             std::to_string(he.face_of[c0]) + " and " + std::to_string(he.face_of[c1]) + ")");
      he.opposite[c0] = c1;
      he.opposite[c1] = c0;
    }
    i = j;
  }
  he.outgoing.assign(mesh.vertex_count(), kNone);
  he.out_degree.assign(mesh.vertex_count(), 0);
  for (std::uint32_t c = 0; c < corners; ++c) {
    const std::uint32_t v = he.origin(c);
    ++he.out_degree[v];
    if (he.outgoing[v] == kNone || he.opposite[c] == kNone) he.outgoing[v] = c;
  }
  return he;
}

struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace

void require_manifold(const PolygonMesh& mesh, const std::string& source) {
  validate_indices(mesh, source);
  if (mesh.face_count() == 0) throw Error(ErrorKind::Topology, source + ": the mesh has no faces");
  std::vector<std::uint32_t> sorted;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    const std::uint32_t n = mesh.face_size(f);
    std::uint32_t repeated = kNone;
    if (n <= 8) {  // typical faces: compare pairs without allocating
      for (std::uint32_t i = 0; i < n && repeated == kNone; ++i)
        for (std::uint32_t j = i + 1; j < n; ++j)
          if (face[i] == face[j]) {
            repeated = face[i];
            break;
          }
    } else {
      sorted.assign(face, face + n);
      std::sort(sorted.begin(), sorted.end());
      const auto it = std::adjacent_find(sorted.begin(), sorted.end());
      if (it != sorted.end()) repeated = *it;
    }
    if (repeated != kNone)
      throw Error(ErrorKind::Topology,
                  source + ": face " + std::to_string(f) + " uses vertex " + std::to_string(repeated) + " twice");
  }
  const HalfEdges he = build_half_edges(mesh, source);
  for (std::uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    const std::uint32_t start = he.outgoing[v];
    if (start == kNone)
      throw Error(ErrorKind::Topology, source + ": vertex " + std::to_string(v) + " is used by no face");
    // Walk the fan clockwise from the boundary half-edge (or any half-edge if
    // the vertex is interior); a manifold vertex reaches all its out-edges.
    std::uint32_t visited = 1;
    for (std::uint32_t c = he.opposite[he.prev(start)]; c != kNone && c != start; c = he.opposite[he.prev(c)]) {
      if (++visited > he.out_degree[v]) break;
    }
    if (visited != he.out_degree[v])
      throw Error(ErrorKind::Topology, source + ": non-manifold vertex " + std::to_string(v) +
                                           " (its faces form more than one fan)");
  }
}

std::vector<std::uint32_t> face_components(const PolygonMesh& mesh, std::size_t* component_count) {
  UnionFind sets(mesh.vertex_count());
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    for (std::uint32_t i = 1; i < mesh.face_size(f); ++i) sets.unite(face[0], face[i]);
  }
  std::vector<std::uint32_t> label(mesh.vertex_count(), kNone);
  std::vector<std::uint32_t> result(mesh.face_count());
  std::uint32_t count = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t root = sets.find(mesh.face_begin(f)[0]);
    if (label[root] == kNone) label[root] = count++;
    result[f] = label[root];
  }
  if (component_count) *component_count = count;
  return result;
}

namespace {

// Calls visit(c) with one boundary half-edge c of every boundary loop:
// follows boundary half-edges through each vertex's unique outgoing one.
template <typename Visit>
void for_each_boundary_loop(const HalfEdges& he, Visit&& visit) {
  std::vector<std::uint8_t> seen(he.opposite.size(), 0);
  for (std::uint32_t c = 0; c < he.opposite.size(); ++c) {
    if (he.opposite[c] != kNone || seen[c]) continue;
    visit(c);
    for (std::uint32_t b = c; b != kNone && !seen[b];) {
      seen[b] = 1;
      const std::uint32_t out = he.outgoing[he.target(b)];
      b = (out != kNone && he.opposite[out] == kNone) ? out : kNone;
    }
  }
}

void set_euler_and_genus(TopologySummary& s) {
  s.euler_characteristic = static_cast<long long>(s.vertices) - static_cast<long long>(s.edges) +
                           static_cast<long long>(s.faces);
  s.genus = (2 * static_cast<long long>(s.components) - s.euler_characteristic -
             static_cast<long long>(s.boundary_loops)) / 2;
}

}  // namespace

TopologySummary summarize_topology(const PolygonMesh& mesh) {
  TopologySummary s;
  const HalfEdges he = build_half_edges(mesh, "mesh");
  s.vertices = mesh.vertex_count();
  s.faces = mesh.face_count();
  std::size_t interior_half_edges = 0;
  for (std::uint32_t c = 0; c < he.opposite.size(); ++c) {
    if (he.opposite[c] == kNone) ++s.boundary_edges;
    else ++interior_half_edges;
  }
  s.edges = s.boundary_edges + interior_half_edges / 2;
  for_each_boundary_loop(he, [&](std::uint32_t) { ++s.boundary_loops; });
  face_components(mesh, &s.components);
  set_euler_and_genus(s);
  return s;
}

std::vector<TopologySummary> summarize_components(const PolygonMesh& mesh, std::vector<std::uint32_t>* face_component) {
  const HalfEdges he = build_half_edges(mesh, "mesh");
  std::size_t count = 0;
  std::vector<std::uint32_t> component = face_components(mesh, &count);
  std::vector<TopologySummary> result(count);
  for (TopologySummary& s : result) s.components = 1;
  std::vector<std::uint8_t> counted(mesh.vertex_count(), 0);
  for (std::uint32_t f = 0; f < mesh.face_count(); ++f) {
    TopologySummary& s = result[component[f]];
    ++s.faces;
    for (std::uint32_t c = mesh.face_offsets[f]; c < mesh.face_offsets[f + 1]; ++c) {
      const std::uint32_t v = mesh.face_vertices[c];
      if (!counted[v]) {
        counted[v] = 1;
        ++s.vertices;
      }
      if (he.opposite[c] == kNone) {
        ++s.boundary_edges;
        ++s.edges;
      } else if (c < he.opposite[c]) {
        ++s.edges;
      }
    }
  }
  for_each_boundary_loop(he, [&](std::uint32_t c) { ++result[component[he.face_of[c]]].boundary_loops; });
  for (TopologySummary& s : result) set_euler_and_genus(s);
  if (face_component) *face_component = std::move(component);
  return result;
}

}  // namespace isowave
