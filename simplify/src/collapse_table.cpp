// Building the corner table of CollapseMesh (see collapse_mesh.h): the
// spatial vertex order, vertex and corner records in that order, opposite
// half-edges, vertex fans with the manifold checks of require_manifold(),
// edge ids, boundary loops. Every step is O(n) and parallel except the
// boundary-loop walk (and the O(n log n) sort of the order).
#include <algorithm>
#include <atomic>
#include <cassert>
#include <numeric>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "collapse_mesh_internal.h"
#include "isowave/core/morton.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "simplify_steps.h"

namespace isowave::simplify {

namespace {

using Range = tbb::blocked_range<std::uint32_t>;
constexpr std::uint32_t kGrain = 1 << 14;

constexpr double kHuge = 1e300;

[[noreturn]] void not_manifold(const std::string& what) {
  throw Error(ErrorKind::Topology, "not a consistently oriented 2-manifold: " + what);
}

// Vertex order for the corner table: Morton order of the positions (the
// table then puts triangles in order of their first vertex). The collapse
// loop jumps between random places of a mesh of hundreds of megabytes; in
// scan order (marching cubes) a vertex's fan lies in three far-apart
// stretches of memory, in Morton order mostly in one, so each fan walk costs
// fewer cache misses.
std::vector<std::uint32_t> spatial_order(const PolygonMesh& mesh) {
  const std::size_t n = mesh.vertex_count();
  double low[3] = {kHuge, kHuge, kHuge}, high[3] = {-kHuge, -kHuge, -kHuge};
  for (const Vec3& p : mesh.positions)
    for (int axis = 0; axis < 3; ++axis) {
      low[axis] = std::min(low[axis], p[axis]);
      high[axis] = std::max(high[axis], p[axis]);
    }
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 65536), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t v = range.begin(); v != range.end(); ++v) {
      std::uint32_t cell[3];
      for (int axis = 0; axis < 3; ++axis) {
        const double extent = high[axis] - low[axis];
        const double t = extent > 0 ? (mesh.positions[v][axis] - low[axis]) / extent : 0.0;
        cell[axis] = static_cast<std::uint32_t>(t * double(0x1FFFFF));
      }
      keyed[v] = {morton_code(cell[0], cell[1], cell[2]), static_cast<std::uint32_t>(v)};
    }
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = keyed[k].second;
  return order;
}

}  // namespace

CollapseMesh::CollapseMesh(const PolygonMesh& mesh, CollapseRules rules) : rules_(rules) { build(mesh, nullptr); }

CollapseMesh::CollapseMesh(const PolygonMesh& mesh, const std::vector<std::uint32_t>& vertex_order, CollapseRules rules)
    : rules_(rules) {
  assert(vertex_order.size() == mesh.vertex_count());
  build(mesh, vertex_order.data());
}

void CollapseMesh::build(const PolygonMesh& mesh, const std::uint32_t* order) {
  assert(rules_.max_valence >= 3 && rules_.max_valence + 8 <= kMaxRing);
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(mesh.vertex_count());
  assert(mesh.face_vertices.size() == 3 * mesh.face_count());
  if (mesh.face_count() == 0) not_manifold("the mesh has no faces");

  std::vector<std::uint32_t> new_index;
  if (order) {
    new_index.resize(vertex_count);
    tbb::parallel_for(Range(0, vertex_count, kGrain), [&](const Range& range) {
      for (std::uint32_t k = range.begin(); k != range.end(); ++k) new_index[order[k]] = k;
    });
  }
  build_vertices(mesh, order);
  build_corners(mesh, order, new_index);
  std::vector<std::uint32_t>().swap(new_index);
  if (rules_.max_vertex_area > 0) share_area();
  pair_corners();
  number_edges();
  initial_vertices_ = vertex_count;
  initial_triangles_ = mesh.face_count();
  for (int l = 0; l < kLanes; ++l) lanes_[l].stamp = static_cast<std::uint32_t>(l);
  find_boundary_loops();
}

void CollapseMesh::build_vertices(const PolygonMesh& mesh, const std::uint32_t* order) {
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(mesh.vertex_count());
  input_had_sharp_ = !mesh.sharp.empty();
  // The big arrays' pages are faulted in on all threads before the fill.
  reserve_fresh_on_huge_pages(vertices_, vertex_count);
  vertices_.resize(vertex_count);
  tbb::parallel_for(Range(0, vertex_count, kGrain), [&](const Range& range) {
    for (std::uint32_t k = range.begin(); k != range.end(); ++k) {
      const std::uint32_t v = order ? order[k] : k;
      vertices_[k] = VertexRecord{mesh.positions[v], kNone, 0, kNone, mesh.is_sharp(v) ? kSharp : std::uint8_t{0}, 0};
    }
  });
}

void CollapseMesh::build_corners(const PolygonMesh& mesh, const std::uint32_t* order,
                                 const std::vector<std::uint32_t>& new_index) {
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(mesh.vertex_count());
  const std::uint32_t triangle_count = static_cast<std::uint32_t>(mesh.face_count());
  const std::uint32_t corner_count = 3 * triangle_count;
  // Renumbered triangles ordered by their smallest vertex: a counting sort,
  // stable, so that ties keep the input order.
  std::vector<std::uint32_t> triangle_order;
  if (order) {
    std::vector<std::uint32_t> smallest(triangle_count);
    tbb::parallel_for(Range(0, triangle_count, kGrain), [&](const Range& range) {
      for (std::uint32_t t = range.begin(); t != range.end(); ++t) {
        const std::uint32_t* face = mesh.face_vertices.data() + 3 * std::size_t{t};
        smallest[t] = std::min({new_index[face[0]], new_index[face[1]], new_index[face[2]]});
      }
    });
    std::vector<std::uint32_t> slot(vertex_count + 1, 0);
    for (std::uint32_t t = 0; t < triangle_count; ++t) ++slot[smallest[t] + 1];
    std::partial_sum(slot.begin(), slot.end(), slot.begin());
    triangle_order.resize(triangle_count);
    for (std::uint32_t t = 0; t < triangle_count; ++t) triangle_order[slot[smallest[t]]++] = t;
  }
  reserve_fresh_on_huge_pages(corners_, corner_count);
  corners_.resize(corner_count);
  std::atomic<bool> repeated_vertex{false};
  tbb::parallel_for(Range(0, triangle_count, kGrain), [&](const Range& range) {
    for (std::uint32_t t = range.begin(); t != range.end(); ++t) {
      const std::uint32_t* face = mesh.face_vertices.data() + 3 * std::size_t{order ? triangle_order[t] : t};
      std::uint32_t v[3];
      for (int i = 0; i < 3; ++i) {
        v[i] = order ? new_index[face[i]] : face[i];
        corners_[3 * t + i] = CornerRecord{v[i], kNone, kNone};
      }
      if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) repeated_vertex = true;
    }
  });
  if (repeated_vertex) not_manifold("a triangle uses a vertex twice");
}

void CollapseMesh::share_area() {
  vertex_area_.assign(vertices_.size(), 0.0f);
  for (std::uint32_t t = 0; 3 * t < corners_.size(); ++t) {
    const Vec3& a = vertices_[corners_[3 * t].vertex].position;
    const Vec3 ab = vertices_[corners_[3 * t + 1].vertex].position - a;
    const Vec3 ac = vertices_[corners_[3 * t + 2].vertex].position - a;
    const float third = static_cast<float>(std::sqrt(squared_norm(cross(ab, ac))) / 6.0);
    for (int k = 0; k < 3; ++k) vertex_area_[corners_[3 * t + k].vertex] += third;
  }
}

void CollapseMesh::pair_corners() {
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(vertices_.size());
  const std::uint32_t corner_count = static_cast<std::uint32_t>(corners_.size());
  // Outgoing corners per vertex (compressed rows, ascending) to pair
  // half-edges in O(n).
  std::vector<std::uint32_t> first(vertex_count + 1, 0);
  for (std::uint32_t c = 0; c < corner_count; ++c) ++first[corners_[c].vertex + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  // Each entry with the corner's target, so that pairing reads the rows only.
  struct Outgoing {
    std::uint32_t corner, target;
  };
  std::vector<Outgoing> outgoing;
  reserve_fresh_on_huge_pages(outgoing, corner_count);  // faulted in on all threads: the fill below is serial
  outgoing.resize(corner_count);
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::uint32_t c = 0; c < corner_count; ++c)
      outgoing[fill[corners_[c].vertex]++] = Outgoing{c, corners_[next(c)].vertex};
  }
  // Opposites. A corner u -> w with two candidates w -> u lies on an edge of
  // more than two triangles or traversed twice in one direction; the case
  // without any w -> u shows up below as a vertex with two boundary corners.
  std::atomic<bool> shared_edge{false};
  tbb::parallel_for(Range(0, corner_count, kGrain), [&](const Range& range) {
    for (std::uint32_t c = range.begin(); c != range.end(); ++c) {
      const std::uint32_t u = corners_[c].vertex, w = corners_[next(c)].vertex;
      std::uint32_t found = kNone, matches = 0;
      for (std::uint32_t i = first[w]; i < first[w + 1]; ++i)
        if (outgoing[i].target == u && matches++ == 0) found = outgoing[i].corner;
      if (matches > 1) shared_edge = true;
      corners_[c].opposite = found;
    }
  });
  if (shared_edge) not_manifold("an edge has more than two triangles or two of the same orientation");

  // Vertices: half-edge (the boundary one, else the first), valence, and the
  // manifold test of require_manifold(): walking the fan from there reaches
  // every corner of the vertex.
  std::atomic<bool> unreferenced{false}, several_fans{false};
  tbb::parallel_for(Range(0, vertex_count, kGrain), [&](const Range& range) {
    for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
      const std::uint32_t begin = first[v], end = first[v + 1];
      if (begin == end) {
        unreferenced = true;
        continue;
      }
      std::uint32_t start = outgoing[begin].corner, boundary_corners = 0;
      for (std::uint32_t i = begin; i < end; ++i)
        if (corners_[outgoing[i].corner].opposite == kNone) {
          start = outgoing[i].corner;
          ++boundary_corners;
        }
      VertexRecord& record = vertices_[v];
      record.halfedge = start;
      record.valence = end - begin + (boundary_corners > 0 ? 1 : 0);  // a boundary vertex has one more neighbour
      if (boundary_corners > 0) record.flags |= kBoundary;
      std::uint32_t visited = 0, c = start;
      do {
        ++visited;
        c = corners_[prev(c)].opposite;
      } while (c != kNone && c != start && visited <= end - begin);
      if (boundary_corners > 1 || visited != end - begin) several_fans = true;
    }
  });
  if (unreferenced) not_manifold("a vertex is used by no triangle");
  if (several_fans) not_manifold("a vertex's triangles form more than one fan");
  // Returning frees these before the edge records are allocated, which then
  // take over their pages: fresh pages cost more than the arithmetic here
  // (the kernel zeroes each).
}

void CollapseMesh::number_edges() {
  const std::uint32_t corner_count = static_cast<std::uint32_t>(corners_.size());
  // Edge ids in corner order: one per corner without an opposite or with a
  // later one. Counted per chunk, then numbered.
  constexpr std::uint32_t kChunk = 1 << 16;
  const std::uint32_t chunk_count = (corner_count + kChunk - 1) / kChunk;
  std::vector<std::uint32_t> chunk_first(chunk_count + 1, 0);
  const auto owns_edge = [&](std::uint32_t c) {
    const std::uint32_t o = corners_[c].opposite;
    return o == kNone || o > c;
  };
  tbb::parallel_for(std::uint32_t{0}, chunk_count, [&](std::uint32_t chunk) {
    std::uint32_t count = 0;
    for (std::uint32_t c = chunk * kChunk; c < std::min(corner_count, (chunk + 1) * kChunk); ++c) count += owns_edge(c);
    chunk_first[chunk + 1] = count;
  });
  std::partial_sum(chunk_first.begin(), chunk_first.end(), chunk_first.begin());
  reserve_fresh_on_huge_pages(edges_, chunk_first[chunk_count]);
  edges_.resize(chunk_first[chunk_count]);
  tbb::parallel_for(std::uint32_t{0}, chunk_count, [&](std::uint32_t chunk) {
    std::uint32_t edge = chunk_first[chunk];
    for (std::uint32_t c = chunk * kChunk; c < std::min(corner_count, (chunk + 1) * kChunk); ++c) {
      if (!owns_edge(c)) continue;
      edges_[edge] = EdgeRecord{c, 0.0f, 0.0f, 0, {kNone, kNone, BucketQueue::kNotQueued}, 0};
      corners_[c].edge = edge;
      if (corners_[c].opposite != kNone) corners_[corners_[c].opposite].edge = edge;
      ++edge;
    }
  });
}

void CollapseMesh::find_boundary_loops() {
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(vertices_.size());
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (!is_boundary(v) || vertices_[v].boundary_loop != kNone) continue;
    const std::uint32_t loop = static_cast<std::uint32_t>(loop_size_.size());
    std::uint32_t size = 0;
    for (std::uint32_t w = v; vertices_[w].boundary_loop == kNone; w = target(vertices_[w].halfedge)) {
      vertices_[w].boundary_loop = loop;
      ++size;
    }
    loop_size_.push_back(size);
  }
}

CollapseMesh build_table(const PolygonMesh& input, const CollapseRules& rules, const std::string& source,
                         std::vector<std::uint32_t>* vertex_order) {
  try {
    std::vector<std::uint32_t> order = spatial_order(input);
    CollapseMesh mesh(input, order, rules);
    if (vertex_order) *vertex_order = std::move(order);
    return mesh;
  } catch (const Error& error) {
    if (error.kind() == ErrorKind::Topology) require_manifold(input, source);
    throw Error(error.kind(), source + ": " + error.what());
  }
}

}  // namespace isowave::simplify
