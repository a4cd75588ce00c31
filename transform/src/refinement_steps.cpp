#include "isowave/transform/refinement_steps.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "parallel_range.h"
#include "sharp_rules.h"

namespace isowave::detail {

namespace {

// Chunks of the per-element loops below.
constexpr std::uint32_t kGrain = 16384;

// `count` elements, on faulted-in huge pages: the arrays of the finer levels
// are hundreds of megabytes, written once at scattered places.
template <class T>
void allocate(std::vector<T>& values, std::size_t count) {
  reserve_fresh_on_huge_pages(values, count);
  values.resize(count);
}

// Throws Error(InvalidArgument) unless the finest of `levels` refinements of a
// level with these counts fits 32-bit indices (with room for the offsets of
// the arrays the lifting steps read): V' = V + F + E, and every finer level
// has F' = corners, E' = 2 E + corners.
void require_32_bit_indices(double vertices, double faces, double edges, double corners, int levels) {
  vertices = refinement_counts({vertices, faces, edges, corners}, levels).back().vertices;
  if (vertices >= static_cast<double>(std::numeric_limits<std::int32_t>::max()))
    throw Error(ErrorKind::InvalidArgument, "the finest level would have " +
                                                std::to_string(static_cast<long long>(vertices)) +
                                                " vertices, more than 32-bit indices allow; use fewer levels");
}

// ------------------------------------------------------------ own refinement

// One level's complete topology in flat arrays, indices local to the level
// (faces, edges and vertices each numbered from 0), as Vtr::Level holds it.
struct LevelTopology {
  std::uint32_t vertex_count = 0, face_count = 0, edge_count = 0;
  // Face f: corners and edges in rows face_offsets[f] .. face_offsets[f+1];
  // edge k joins corners k and k+1.
  std::vector<std::uint32_t> face_offsets, face_vertices, face_edges;
  // Two entries per edge: its vertices; its faces (a boundary edge lists its
  // one face twice) and its index within each of them.
  std::vector<std::uint32_t> edge_vertices, edge_faces;
  std::vector<std::uint16_t> edge_face_local;
  std::vector<std::uint8_t> edge_boundary;
  // Vertex v: incident edges (with the vertex's end of each, 0 or 1) and
  // incident faces (with the vertex's corner in each), in OpenSubdiv's order.
  std::vector<std::uint32_t> vertex_edge_offsets, vertex_edges;
  std::vector<std::uint8_t> vertex_edge_local;
  std::vector<std::uint32_t> vertex_face_offsets, vertex_faces;
  std::vector<std::uint16_t> vertex_face_local;

  std::uint32_t face_size(std::uint32_t f) const { return face_offsets[f + 1] - face_offsets[f]; }
  std::uint32_t corner_count() const { return face_offsets[face_count]; }
};

// Per vertex during completion: its faces, and slots for its edges (faces + 1
// per vertex, enough for a manifold vertex) filled in order of appearance.
struct EdgeSlots {
  std::vector<std::uint32_t> face_count_of, edge_count_of;
  std::vector<std::uint32_t> offsets, edges;  // vertex v's edges: edges[offsets[v] ..][0 .. edge_count_of[v])
};

constexpr std::uint32_t kValenceLimit = 0xFFFF;  // OpenSubdiv's VALENCE_LIMIT (16-bit local indices)
constexpr std::uint32_t kNoEdge = ~std::uint32_t{0};

Error not_manifold() { return Error(ErrorKind::Topology, "the base mesh is not a consistently oriented manifold"); }

std::uint32_t corner_of(const LevelTopology& t, std::uint32_t face, std::uint32_t v) {
  const std::uint32_t offset = t.face_offsets[face];
  return static_cast<std::uint32_t>(std::find(&t.face_vertices[offset], &t.face_vertices[t.face_offsets[face + 1]], v) -
                                    &t.face_vertices[offset]);
}

// Faces per vertex in face order; a manifold vertex has as many edges as
// faces, or one more on the boundary.
EdgeSlots count_vertex_faces(LevelTopology& t) {
  const std::uint32_t V = t.vertex_count, F = t.face_count, C = t.corner_count();
  for (std::uint32_t f = 0; f < F; ++f)
    if (t.face_size(f) > kValenceLimit) throw Error(ErrorKind::Topology, "a base face has more than 65535 corners");
  EdgeSlots slots;
  slots.face_count_of.assign(V + 1, 0);
  for (std::uint32_t c = 0; c < C; ++c) ++slots.face_count_of[t.face_vertices[c]];
  t.vertex_face_offsets.resize(std::size_t{V} + 1);
  t.vertex_face_offsets[0] = 0;
  for (std::uint32_t v = 0; v < V; ++v) {
    if (slots.face_count_of[v] > kValenceLimit) throw Error(ErrorKind::Topology, "a base vertex has more than 65535 faces");
    t.vertex_face_offsets[v + 1] = t.vertex_face_offsets[v] + slots.face_count_of[v];
  }
  t.vertex_faces.resize(C);
  slots.offsets.resize(std::size_t{V} + 1);
  slots.offsets[0] = 0;
  for (std::uint32_t v = 0; v < V; ++v) slots.offsets[v + 1] = slots.offsets[v] + slots.face_count_of[v] + 1;
  slots.edges.resize(slots.offsets[V]);
  slots.edge_count_of.assign(V, 0);
  return slots;
}

// Edges numbered in order of first appearance over the faces' corners,
// oriented as in the face that creates them, their faces in face order.
void complete_edges(LevelTopology& t, EdgeSlots& slots) {
  const std::uint32_t V = t.vertex_count, F = t.face_count, C = t.corner_count();
  std::vector<std::uint32_t> faces_filled(V, 0);
  t.face_edges.resize(C);
  t.edge_vertices.reserve(C + 2);
  std::vector<std::uint32_t> first_face, second_face;
  first_face.reserve(C / 2 + 1);
  second_face.reserve(C / 2 + 1);
  for (std::uint32_t f = 0; f < F; ++f) {
    const std::uint32_t offset = t.face_offsets[f], n = t.face_size(f);
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t v0 = t.face_vertices[offset + i], v1 = t.face_vertices[offset + (i + 1 == n ? 0 : i + 1)];
      std::uint32_t edge = kNoEdge;
      for (std::uint32_t k = 0; k < slots.edge_count_of[v0]; ++k) {
        const std::uint32_t candidate = slots.edges[slots.offsets[v0] + k];
        if (t.edge_vertices[2 * candidate] == v1 || t.edge_vertices[2 * candidate + 1] == v1) {
          edge = candidate;
          break;
        }
      }
      if (edge == kNoEdge) {
        edge = static_cast<std::uint32_t>(first_face.size());
        t.edge_vertices.push_back(v0);
        t.edge_vertices.push_back(v1);
        first_face.push_back(f);
        second_face.push_back(kNoEdge);
        for (const std::uint32_t end : {v0, v1}) {
          if (slots.edge_count_of[end] == slots.face_count_of[end] + 1) throw not_manifold();
          slots.edges[slots.offsets[end] + slots.edge_count_of[end]++] = edge;
        }
      } else {
        // Its second face must run along it the other way.
        if (second_face[edge] != kNoEdge || t.edge_vertices[2 * edge] == v0) throw not_manifold();
        second_face[edge] = f;
      }
      t.face_edges[offset + i] = edge;
      t.vertex_faces[t.vertex_face_offsets[v0] + faces_filled[v0]++] = f;
    }
  }
  t.edge_count = static_cast<std::uint32_t>(first_face.size());
  const std::uint32_t E = t.edge_count;
  t.edge_faces.resize(2 * std::size_t{E});
  t.edge_boundary.resize(E);
  for (std::uint32_t e = 0; e < E; ++e) {
    t.edge_boundary[e] = second_face[e] == kNoEdge ? 1 : 0;
    t.edge_faces[2 * e] = first_face[e];
    t.edge_faces[2 * e + 1] = second_face[e] == kNoEdge ? first_face[e] : second_face[e];
  }
  t.vertex_edge_offsets.resize(std::size_t{V} + 1);
  t.vertex_edge_offsets[0] = 0;
  for (std::uint32_t v = 0; v < V; ++v) t.vertex_edge_offsets[v + 1] = t.vertex_edge_offsets[v] + slots.edge_count_of[v];
  t.vertex_edges.resize(t.vertex_edge_offsets[V]);
  for (std::uint32_t v = 0; v < V; ++v)
    if (slots.edge_count_of[v] > kValenceLimit) throw Error(ErrorKind::Topology, "a base vertex has more than 65535 edges");
}

// Each vertex's faces and edges in order around it
// (Level::orderVertexFacesAndEdges): from its first face, or on the boundary
// from the boundary edge leaving it, walking to the edge entering it in each
// face and across to the next face.
void order_vertex_neighbourhoods(LevelTopology& t, const EdgeSlots& slots) {
  const std::uint32_t V = t.vertex_count;
  parallel_range(V, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    std::vector<std::uint32_t> ordered_faces, ordered_edges;
    for (std::uint32_t v = begin; v < end; ++v) {
      const std::uint32_t face_total = slots.face_count_of[v], edge_total = slots.edge_count_of[v];
      const std::uint32_t* edges = &slots.edges[slots.offsets[v]];
      std::uint32_t* faces = &t.vertex_faces[t.vertex_face_offsets[v]];
      if (face_total == 0 || edge_total < 2 || (edge_total != face_total && edge_total != face_total + 1)) throw not_manifold();
      std::uint32_t face = kNoEdge, corner = 0, edge = kNoEdge;
      if (edge_total == face_total) {
        face = faces[0];
        corner = corner_of(t, face, v);
        edge = t.face_edges[t.face_offsets[face] + corner];
      } else {
        for (std::uint32_t k = 0; k < edge_total; ++k) {
          if (!t.edge_boundary[edges[k]]) continue;
          edge = edges[k];
          face = t.edge_faces[2 * edge];
          corner = corner_of(t, face, v);
          if (edge == t.face_edges[t.face_offsets[face] + corner]) break;
        }
        if (edge == kNoEdge) throw not_manifold();
      }
      ordered_faces.assign(1, face);
      ordered_edges.assign(1, edge);
      const std::uint32_t first_edge = edge;
      while (ordered_edges.size() < edge_total) {
        const std::uint32_t n = t.face_size(face);
        const std::uint32_t next = t.face_edges[t.face_offsets[face] + (corner ? corner - 1 : n - 1)];
        if (next == edge || next == first_edge) throw not_manifold();
        ordered_edges.push_back(next);
        if (ordered_faces.size() < face_total) {
          if (t.edge_boundary[next]) throw not_manifold();
          face = t.edge_faces[2 * next] == face ? t.edge_faces[2 * next + 1] : t.edge_faces[2 * next];
          const std::uint32_t offset = t.face_offsets[face];
          corner = static_cast<std::uint32_t>(
              std::find(&t.face_edges[offset], &t.face_edges[t.face_offsets[face + 1]], next) - &t.face_edges[offset]);
          ordered_faces.push_back(face);
        }
        edge = next;
      }
      if (ordered_faces.size() != face_total) throw not_manifold();
      std::copy(ordered_faces.begin(), ordered_faces.end(), faces);
      std::copy(ordered_edges.begin(), ordered_edges.end(), t.vertex_edges.begin() + t.vertex_edge_offsets[v]);
    }
  });
}

// Local indices: a vertex's corner in each face, its end of each edge, an
// edge's index in each face.
void fill_local_indices(LevelTopology& t) {
  const std::uint32_t V = t.vertex_count, F = t.face_count, C = t.corner_count(), E = t.edge_count;
  t.vertex_face_local.resize(C);
  t.vertex_edge_local.resize(t.vertex_edges.size());
  parallel_range(V, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t v = begin; v < end; ++v) {
      for (std::uint32_t k = t.vertex_face_offsets[v]; k < t.vertex_face_offsets[v + 1]; ++k)
        t.vertex_face_local[k] = static_cast<std::uint16_t>(corner_of(t, t.vertex_faces[k], v));
      for (std::uint32_t k = t.vertex_edge_offsets[v]; k < t.vertex_edge_offsets[v + 1]; ++k)
        t.vertex_edge_local[k] = t.edge_vertices[2 * t.vertex_edges[k] + 1] == v ? 1 : 0;
    }
  });
  t.edge_face_local.resize(2 * std::size_t{E});
  for (std::uint32_t f = 0; f < F; ++f)
    for (std::uint32_t k = t.face_offsets[f]; k < t.face_offsets[f + 1]; ++k) {
      const std::uint32_t e = t.face_edges[k];
      const std::uint32_t side = t.edge_faces[2 * e] == f ? 0 : 1;
      t.edge_face_local[2 * e + side] = static_cast<std::uint16_t>(k - t.face_offsets[f]);
      if (t.edge_boundary[e]) t.edge_face_local[2 * e + 1] = t.edge_face_local[2 * e];
    }
}

// The base level, completed from the face-vertex lists as
// Vtr::Level::completeTopologyFromFaceVertices() completes it for a
// consistently oriented manifold.
LevelTopology level_from_base(const PolygonMesh& base) {
  LevelTopology t;
  t.vertex_count = static_cast<std::uint32_t>(base.vertex_count());
  t.face_count = static_cast<std::uint32_t>(base.face_count());
  t.face_offsets = base.face_offsets;
  t.face_vertices = base.face_vertices;
  EdgeSlots slots = count_vertex_faces(t);
  complete_edges(t, slots);
  order_vertex_neighbourhoods(t, slots);
  fill_local_indices(t);
  return t;
}


// Whether a refined level gets the *_local arrays it needs to be refined once more.
enum class LocalIndices { Omit, Compute };

// Child faces, and the child edges interior to parent faces.
void refine_faces_and_interior_edges(const LevelTopology& p, LocalIndices local, LevelTopology& c) {
  const bool with_local_indices = local == LocalIndices::Compute;
  const std::uint32_t V = p.vertex_count, F = p.face_count, C = p.corner_count();
  const std::uint32_t first_face_vertex = V, first_edge_vertex = V + F;
  allocate(c.face_offsets, std::size_t{C} + 1);
  allocate(c.face_vertices, 4 * std::size_t{C});
  allocate(c.face_edges, 4 * std::size_t{C});
  allocate(c.edge_vertices, 2 * std::size_t{c.edge_count});
  allocate(c.edge_faces, 2 * std::size_t{c.edge_count});
  if (with_local_indices) allocate(c.edge_face_local, 2 * std::size_t{c.edge_count});
  allocate(c.edge_boundary, c.edge_count);
  c.face_offsets[C] = 4 * C;
  parallel_range(F, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t f = begin; f < end; ++f) {
      const std::uint32_t offset = p.face_offsets[f], n = p.face_size(f);
      const bool quad = n == 4;
      for (std::uint32_t j = 0; j < n; ++j) {
        const std::uint32_t previous = j ? j - 1 : n - 1, next = j + 1 < n ? j + 1 : 0;
        const std::uint32_t corner = p.face_vertices[offset + j];
        const std::uint32_t previous_edge = p.face_edges[offset + previous], next_edge = p.face_edges[offset + j];
        // The halves of the previous and next edges at this corner.
        const std::uint32_t half_previous = C + 2 * previous_edge + (p.edge_vertices[2 * previous_edge] != corner ? 1 : 0);
        const std::uint32_t half_next = C + 2 * next_edge + (p.edge_vertices[2 * next_edge] != corner ? 1 : 0);
        const std::uint32_t child = offset + j;
        const std::uint32_t rotation = quad ? j : 0;
        std::uint32_t* vertices = &c.face_vertices[4 * std::size_t{child}];
        std::uint32_t* edges = &c.face_edges[4 * std::size_t{child}];
        vertices[rotation] = corner;
        vertices[(rotation + 1) & 3] = first_edge_vertex + next_edge;
        vertices[(rotation + 2) & 3] = first_face_vertex + f;
        vertices[(rotation + 3) & 3] = first_edge_vertex + previous_edge;
        edges[rotation] = half_next;
        edges[(rotation + 1) & 3] = offset + j;  // perpendicular to the next edge
        edges[(rotation + 2) & 3] = offset + previous;  // perpendicular to the previous edge
        edges[(rotation + 3) & 3] = half_previous;
        c.face_offsets[child] = 4 * child;
        // Child edge `child`: from the f vertex to the e vertex of edge j,
        // between child faces j and j+1.
        c.edge_vertices[2 * std::size_t{child}] = first_face_vertex + f;
        c.edge_vertices[2 * std::size_t{child} + 1] = first_edge_vertex + next_edge;
        c.edge_faces[2 * std::size_t{child}] = offset + j;
        c.edge_faces[2 * std::size_t{child} + 1] = offset + next;
        if (with_local_indices) {
          c.edge_face_local[2 * std::size_t{child}] = static_cast<std::uint16_t>(quad ? next : 1);
          c.edge_face_local[2 * std::size_t{child} + 1] = static_cast<std::uint16_t>(quad ? (next + 2) & 3 : 2);
        }
        c.edge_boundary[child] = 0;
      }
    }
  });
}

// The two halves of each parent edge.
void refine_edge_halves(const LevelTopology& p, LocalIndices local, LevelTopology& c) {
  const bool with_local_indices = local == LocalIndices::Compute;
  const std::uint32_t E = p.edge_count, C = p.corner_count();
  const std::uint32_t first_edge_vertex = p.vertex_count + p.face_count;
  parallel_range(E, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t e = begin; e < end; ++e) {
      const std::uint32_t face_count = p.edge_boundary[e] ? 1 : 2;
      for (std::uint32_t i = 0; i < 2; ++i) {
        const std::size_t child = C + 2 * std::size_t{e} + i;
        const std::uint32_t end_vertex = p.edge_vertices[2 * e + i];
        c.edge_vertices[2 * child] = first_edge_vertex + e;
        c.edge_vertices[2 * child + 1] = end_vertex;
        for (std::uint32_t k = 0; k < face_count; ++k) {
          const std::uint32_t face = p.edge_faces[2 * e + k], in_face = p.edge_face_local[2 * e + k];
          const std::uint32_t offset = p.face_offsets[face], n = p.face_size(face);
          // The half at `end_vertex` lies in the child face of that corner.
          const std::uint32_t after = p.face_vertices[offset + in_face] != end_vertex ? 1 : 0;
          const std::uint32_t corner = in_face + after == n ? 0 : in_face + after;
          c.edge_faces[2 * child + k] = offset + corner;
          if (with_local_indices)
            c.edge_face_local[2 * child + k] = static_cast<std::uint16_t>(n == 4 ? in_face : (after ? 3 : 0));
        }
        if (face_count == 1) {
          c.edge_faces[2 * child + 1] = c.edge_faces[2 * child];
          if (with_local_indices) c.edge_face_local[2 * child + 1] = c.edge_face_local[2 * child];
        }
        c.edge_boundary[child] = p.edge_boundary[e];
      }
    }
  });
}

// Vertex neighbourhood offsets: a v vertex keeps its parent's valence, an
// f vertex has n edges and faces, an e vertex 2 + k edges and 2 k faces
// for an edge of k faces.
void allocate_child_vertex_rows(const LevelTopology& p, LocalIndices local, LevelTopology& c) {
  const bool with_local_indices = local == LocalIndices::Compute;
  const std::uint32_t V = p.vertex_count, F = p.face_count, E = p.edge_count, C = p.corner_count();
  const std::uint32_t first_face_vertex = V, first_edge_vertex = V + F;
  std::vector<std::uint32_t> boundary_before(std::size_t{E} + 1);
  boundary_before[0] = 0;
  for (std::uint32_t e = 0; e < E; ++e) boundary_before[e + 1] = boundary_before[e] + p.edge_boundary[e];
  allocate(c.vertex_edge_offsets, std::size_t{c.vertex_count} + 1);
  allocate(c.vertex_face_offsets, std::size_t{c.vertex_count} + 1);
  const std::uint32_t edge_rows_of_faces = p.vertex_edge_offsets[V];  // 2 E
  parallel_range(V, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t v = begin; v < end; ++v) {
      c.vertex_edge_offsets[v] = p.vertex_edge_offsets[v];
      c.vertex_face_offsets[v] = p.vertex_face_offsets[v];
    }
  });
  parallel_range(F, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t f = begin; f < end; ++f) {
      c.vertex_edge_offsets[first_face_vertex + f] = edge_rows_of_faces + p.face_offsets[f];
      c.vertex_face_offsets[first_face_vertex + f] = C + p.face_offsets[f];
    }
  });
  parallel_range(E + 1, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t e = begin; e < end; ++e) {
      c.vertex_edge_offsets[first_edge_vertex + e] = edge_rows_of_faces + C + 4 * e - boundary_before[e];
      c.vertex_face_offsets[first_edge_vertex + e] = 2 * C + 4 * e - 2 * boundary_before[e];
    }
  });
  allocate(c.vertex_edges, c.vertex_edge_offsets[c.vertex_count]);
  if (with_local_indices) allocate(c.vertex_edge_local, c.vertex_edges.size());
  allocate(c.vertex_faces, c.vertex_face_offsets[c.vertex_count]);
  if (with_local_indices) allocate(c.vertex_face_local, c.vertex_faces.size());
}

// v vertices: the child of each incident edge and face, in the parent's order.
void fill_vertex_vertex_rows(const LevelTopology& p, LocalIndices local, LevelTopology& c) {
  const bool with_local_indices = local == LocalIndices::Compute;
  const std::uint32_t V = p.vertex_count, C = p.corner_count();
  parallel_range(V, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t v = begin; v < end; ++v) {
      for (std::uint32_t k = p.vertex_edge_offsets[v]; k < p.vertex_edge_offsets[v + 1]; ++k) {
        c.vertex_edges[k] = C + 2 * p.vertex_edges[k] + p.vertex_edge_local[k];
        if (with_local_indices) c.vertex_edge_local[k] = 1;
      }
      for (std::uint32_t k = p.vertex_face_offsets[v]; k < p.vertex_face_offsets[v + 1]; ++k) {
        const std::uint32_t face = p.vertex_faces[k], corner = p.vertex_face_local[k];
        c.vertex_faces[k] = p.face_offsets[face] + corner;
        if (with_local_indices) c.vertex_face_local[k] = static_cast<std::uint16_t>(p.face_size(face) == 4 ? corner : 0);
      }
    }
  });
}

// f vertices: the interior child edges, each face's leading one first, and
// the child faces in corner order.
void fill_face_vertex_rows(const LevelTopology& p, LocalIndices local, LevelTopology& c) {
  const bool with_local_indices = local == LocalIndices::Compute;
  const std::uint32_t F = p.face_count, first_face_vertex = p.vertex_count;
  parallel_range(F, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t f = begin; f < end; ++f) {
      const std::uint32_t offset = p.face_offsets[f], n = p.face_size(f);
      const std::uint32_t edge_row = c.vertex_edge_offsets[first_face_vertex + f];
      const std::uint32_t face_row = c.vertex_face_offsets[first_face_vertex + f];
      for (std::uint32_t j = 0; j < n; ++j) {
        c.vertex_edges[edge_row + j] = offset + (j ? j - 1 : n - 1);
        c.vertex_faces[face_row + j] = offset + j;
        if (with_local_indices) {
          c.vertex_edge_local[edge_row + j] = 0;
          c.vertex_face_local[face_row + j] = static_cast<std::uint16_t>(n == 4 ? (j + 2) & 3 : 2);
        }
      }
    }
  });
}

// e vertices: edges ordered (half, interior edge of face 0, other half,
// interior edge of face 1); faces per parent face, the one after the edge
// first.
void fill_edge_vertex_rows(const LevelTopology& p, LocalIndices local, LevelTopology& c) {
  const bool with_local_indices = local == LocalIndices::Compute;
  const std::uint32_t E = p.edge_count, C = p.corner_count();
  const std::uint32_t first_edge_vertex = p.vertex_count + p.face_count;
  parallel_range(E, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t e = begin; e < end; ++e) {
      const std::uint32_t face_count = p.edge_boundary[e] ? 1 : 2;
      std::uint32_t* edges = &c.vertex_edges[c.vertex_edge_offsets[first_edge_vertex + e]];
      const std::uint32_t face_row = c.vertex_face_offsets[first_edge_vertex + e];
      for (std::uint32_t k = 0; k < face_count; ++k) {
        const std::uint32_t face = p.edge_faces[2 * e + k], in_face = p.edge_face_local[2 * e + k];
        const std::uint32_t offset = p.face_offsets[face], n = p.face_size(face);
        const std::uint32_t after = in_face + 1 == n ? 0 : in_face + 1;
        c.vertex_faces[face_row + 2 * k] = offset + after;
        c.vertex_faces[face_row + 2 * k + 1] = offset + in_face;
        if (with_local_indices) {
          c.vertex_face_local[face_row + 2 * k] = static_cast<std::uint16_t>(n == 4 ? in_face : 3);
          c.vertex_face_local[face_row + 2 * k + 1] = static_cast<std::uint16_t>(n == 4 ? after : 1);
        }
      }
      // The halves in the order the first face runs along the edge.
      const std::uint32_t face0 = p.edge_faces[2 * e], in_face0 = p.edge_face_local[2 * e];
      const bool reversed = p.face_vertices[p.face_offsets[face0] + in_face0] == p.edge_vertices[2 * e];
      edges[0] = C + 2 * e + (reversed ? 1 : 0);
      edges[1] = p.face_offsets[face0] + in_face0;
      edges[2] = C + 2 * e + (reversed ? 0 : 1);
      if (face_count == 2) edges[3] = p.face_offsets[p.edge_faces[2 * e + 1]] + p.edge_face_local[2 * e + 1];
      if (with_local_indices) {
        // The e vertex is the first end of its halves, the second of the interior edges.
        std::uint8_t* edge_ends = &c.vertex_edge_local[c.vertex_edge_offsets[first_edge_vertex + e]];
        edge_ends[0] = 0;
        edge_ends[1] = 1;
        edge_ends[2] = 0;
        if (face_count == 2) edge_ends[3] = 1;
      }
    }
  });
}

// The next level by uniform Catmull-Clark splitting, numbered as
// Vtr::QuadRefinement (uniform, vertices first) numbers it. With C corners in
// the parent:
//   faces:    face f's corner j -> child face face_offsets[f] + j;
//   edges:    face f's corner j -> the child edge from the f vertex to the e
//             vertex of face edge j, at face_offsets[f] + j; then edge e's
//             half at its end i -> C + 2 e + i;
//   vertices: v vertices, f vertices, e vertices (the hierarchy's layout).
// A child face of a quad is rotated so that its parent corner sits at the
// corner's own index; a child face of any other polygon starts at its corner.
// With LocalIndices::Omit the child lacks the *_local arrays: it can
// become a refinement step but not be refined further.
LevelTopology refine(const LevelTopology& p, LocalIndices local) {
  LevelTopology c;
  c.vertex_count = p.vertex_count + p.face_count + p.edge_count;
  c.face_count = p.corner_count();
  c.edge_count = p.corner_count() + 2 * p.edge_count;
  refine_faces_and_interior_edges(p, local, c);
  refine_edge_halves(p, local, c);
  allocate_child_vertex_rows(p, local, c);
  fill_vertex_vertex_rows(p, local, c);
  fill_face_vertex_rows(p, local, c);
  fill_edge_vertex_rows(p, local, c);
  return c;
}

// The refinement step from `level` to the next, taking over its arrays.
RefinementStep make_step(LevelTopology&& level, const std::vector<std::uint8_t>& flagged_sharp) {
  RefinementStep s;
  const std::uint32_t V = level.vertex_count, F = level.face_count, E = level.edge_count;
  s.parent_vertex_count = V;
  s.parent_face_count = F;
  s.parent_edge_count = E;
  const std::uint32_t f0 = s.first_face_vertex();
  const std::uint32_t e0 = s.first_edge_vertex();

  // Sharp edges are the boundary edges; vertex rules follow from them.
  allocate(s.vertex_rule, V);
  parallel_range(V, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t v = begin; v < end; ++v) {
      std::uint32_t sharp_edges = 0;
      for (std::uint32_t k = level.vertex_edge_offsets[v]; k < level.vertex_edge_offsets[v + 1]; ++k)
        sharp_edges += level.edge_boundary[level.vertex_edges[k]];
      s.vertex_rule[v] = vertex_rule(v < flagged_sharp.size() && flagged_sharp[v], sharp_edges);
    }
  });
  allocate(s.edge_smooth, E);
  parallel_range(E, kGrain, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t e = begin; e < end; ++e)
      s.edge_smooth[e] = edge_is_smooth(level.edge_boundary[e], s.vertex_rule[level.edge_vertices[2 * e]],
                                        s.vertex_rule[level.edge_vertices[2 * e + 1]]);
  });
  for (std::uint32_t v = 0; v < V; ++v) {
    if (s.vertex_rule[v] != VertexRule::Crease) continue;
    s.crease_vertices.push_back(v);
    for (std::uint32_t k = level.vertex_edge_offsets[v]; k < level.vertex_edge_offsets[v + 1]; ++k)
      if (level.edge_boundary[level.vertex_edges[k]]) s.crease_edges.push_back(e0 + level.vertex_edges[k]);
  }

  // Level-local indices become vertex indices of the child level.
  const auto add = [](std::vector<std::uint32_t>& values, std::uint32_t offset) {
    parallel_range(static_cast<std::uint32_t>(values.size()), kGrain, [&](std::uint32_t begin, std::uint32_t end) {
      for (std::uint32_t k = begin; k < end; ++k) values[k] += offset;
    });
  };
  add(level.edge_faces, f0);
  add(level.face_edges, e0);
  add(level.vertex_edges, e0);
  add(level.vertex_faces, f0);
  s.edge_vertices = std::move(level.edge_vertices);
  s.edge_faces = std::move(level.edge_faces);
  s.face_offsets = std::move(level.face_offsets);
  s.face_vertices = std::move(level.face_vertices);
  s.face_edges = std::move(level.face_edges);
  s.vertex_edge_offsets = std::move(level.vertex_edge_offsets);
  s.vertex_edges = std::move(level.vertex_edges);
  s.vertex_face_offsets = std::move(level.vertex_face_offsets);
  s.vertex_faces = std::move(level.vertex_faces);
  level = LevelTopology{};
  return s;
}

}  // namespace

std::vector<RefinementStep> build_refinement_steps(const PolygonMesh& base, int levels) {
  std::vector<RefinementStep> steps;
  if (levels <= 0) return steps;
  LevelTopology level = level_from_base(base);
  require_32_bit_indices(level.vertex_count, level.face_count, level.edge_count, level.corner_count(), levels);
  steps.reserve(static_cast<std::size_t>(levels));
  for (int l = 0; l < levels; ++l) {
    LevelTopology child;
    // The local indices serve only the next refinement.
    if (l + 1 < levels) child = refine(level, l + 2 < levels ? LocalIndices::Compute : LocalIndices::Omit);
    steps.push_back(make_step(std::move(level), base.sharp));
    level = std::move(child);
  }
  return steps;
}

}  // namespace isowave::detail
