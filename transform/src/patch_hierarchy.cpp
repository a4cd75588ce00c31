#include "isowave/transform/patch_hierarchy.h"

#include <algorithm>
#include <cassert>

#include "isowave/core/error.h"

namespace isowave {

namespace {

constexpr std::uint32_t kNone = ~std::uint32_t{0};

Error not_manifold() { return Error(ErrorKind::Topology, "the base mesh is not a consistently oriented manifold"); }

// The faces of each vertex, ascending (faces are visited in order).
void fill_vertex_faces(const PolygonMesh& base, BaseIncidence& in) {
  const std::size_t vertices = base.vertex_count();
  in.vertex_face_offsets.assign(vertices + 1, 0);
  for (const std::uint32_t v : base.face_vertices) ++in.vertex_face_offsets[v + 1];
  for (std::size_t v = 0; v < vertices; ++v) in.vertex_face_offsets[v + 1] += in.vertex_face_offsets[v];
  in.vertex_faces.resize(base.face_vertices.size());
  std::vector<std::uint32_t> fill(in.vertex_face_offsets.begin(), in.vertex_face_offsets.end() - 1);
  for (std::size_t f = 0; f < base.face_count(); ++f)
    for (std::uint32_t k = base.face_offsets[f]; k < base.face_offsets[f + 1]; ++k)
      in.vertex_faces[fill[base.face_vertices[k]]++] = static_cast<std::uint32_t>(f);
}

}  // namespace

BaseIncidence base_incidence(const PolygonMesh& base) {
  BaseIncidence in;
  fill_vertex_faces(base, in);
  // Edges in order of first appearance over the faces' corners, oriented as
  // in the face that creates them (refinement_steps.cpp's complete_edges):
  // a vertex's edges are found among those it started, or met, so far.
  const std::size_t vertices = base.vertex_count();
  std::vector<std::uint32_t> slot_offsets(vertices + 1, 0), slots_used(vertices, 0);
  for (std::size_t v = 0; v < vertices; ++v)
    slot_offsets[v + 1] = slot_offsets[v] + (in.vertex_face_offsets[v + 1] - in.vertex_face_offsets[v]) + 1;
  std::vector<std::uint32_t> slots(slot_offsets[vertices]);
  in.face_edges.resize(base.face_vertices.size());
  in.edge_vertices.reserve(base.face_vertices.size() + 2);
  in.edge_faces.reserve(base.face_vertices.size() + 2);
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t offset = base.face_offsets[f], n = base.face_size(f);
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t v0 = base.face_vertices[offset + i], v1 = base.face_vertices[offset + (i + 1 == n ? 0 : i + 1)];
      std::uint32_t edge = kNone;
      for (std::uint32_t k = 0; k < slots_used[v0] && edge == kNone; ++k) {
        const std::uint32_t candidate = slots[slot_offsets[v0] + k];
        if (in.edge_vertices[2 * candidate] == v1 || in.edge_vertices[2 * candidate + 1] == v1) edge = candidate;
      }
      if (edge == kNone) {
        edge = static_cast<std::uint32_t>(in.edge_count());
        in.edge_vertices.insert(in.edge_vertices.end(), {v0, v1});
        in.edge_faces.insert(in.edge_faces.end(), {static_cast<std::uint32_t>(f), static_cast<std::uint32_t>(f)});
        for (const std::uint32_t end : {v0, v1}) {
          if (slots_used[end] == slot_offsets[end + 1] - slot_offsets[end]) throw not_manifold();
          slots[slot_offsets[end] + slots_used[end]++] = edge;
        }
      } else {
        if (in.edge_faces[2 * edge + 1] != in.edge_faces[2 * edge] || in.edge_vertices[2 * edge] == v0) throw not_manifold();
        in.edge_faces[2 * edge + 1] = static_cast<std::uint32_t>(f);
      }
      in.face_edges[offset + i] = edge;
    }
  }
  return in;
}

std::vector<std::uint32_t> grow_patch(const PolygonMesh& base, const BaseIncidence& incidence,
                                      std::vector<std::uint8_t>& in_patch, int rings) {
  assert(in_patch.size() == base.face_count());
  std::vector<std::uint32_t> faces;
  for (std::size_t f = 0; f < in_patch.size(); ++f)
    if (in_patch[f]) faces.push_back(static_cast<std::uint32_t>(f));
  const auto add_fan = [&](std::uint32_t v) {  // whether it added a face
    const std::size_t before = faces.size();
    for (std::uint32_t k = incidence.vertex_face_offsets[v]; k < incidence.vertex_face_offsets[v + 1]; ++k) {
      const std::uint32_t g = incidence.vertex_faces[k];
      if (!in_patch[g]) {
        in_patch[g] = 1;
        faces.push_back(g);
      }
    }
    return faces.size() > before;
  };
  // Rings: the fans of every corner of the previous ring's faces.
  std::size_t ring_begin = 0;
  for (int r = 0; r < rings; ++r) {
    const std::size_t ring_end = faces.size();
    for (std::size_t k = ring_begin; k < ring_end; ++k)
      for (std::uint32_t c = base.face_offsets[faces[k]]; c < base.face_offsets[faces[k] + 1]; ++c)
        add_fan(base.face_vertices[c]);
    ring_begin = ring_end;
  }
  // Manifold: a vertex on more than two of the patch's boundary edges has
  // its faces in several fans, and takes all of them (which may open others;
  // a vertex of the base with several fans stays one, which the hierarchy
  // rejects).
  std::vector<std::uint32_t> boundary_edges(base.vertex_count(), 0), touched;
  for (bool changed = true; changed;) {
    changed = false;
    for (const std::uint32_t f : faces)
      for (std::uint32_t c = base.face_offsets[f]; c < base.face_offsets[f + 1]; ++c) {
        const std::uint32_t e = incidence.face_edges[c];
        const std::uint32_t a = incidence.edge_faces[2 * e], b = incidence.edge_faces[2 * e + 1];
        const std::uint32_t other = a == f ? b : a;
        if (other != f && in_patch[other]) continue;
        for (const std::uint32_t v : {incidence.edge_vertices[2 * e], incidence.edge_vertices[2 * e + 1]}) {
          if (boundary_edges[v]++ == 0) touched.push_back(v);
        }
      }
    for (const std::uint32_t v : touched) {
      if (boundary_edges[v] > 2 && add_fan(v)) changed = true;
      boundary_edges[v] = 0;
    }
    touched.clear();
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

namespace {

// The patch's base mesh: its faces in the given order, its vertices those
// they use (ascending by base index) renumbered, sharp flags copied.
PolygonMesh patch_mesh(const PolygonMesh& base, const std::vector<std::uint32_t>& faces,
                       std::vector<std::uint32_t>& vertices) {
  vertices.clear();
  for (const std::uint32_t f : faces)
    vertices.insert(vertices.end(), base.face_begin(f), base.face_begin(f) + base.face_size(f));
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  PolygonMesh mesh;
  mesh.positions.resize(vertices.size());
  if (!base.sharp.empty()) {
    mesh.sharp.resize(vertices.size());
    for (std::size_t v = 0; v < vertices.size(); ++v) mesh.sharp[v] = base.sharp[vertices[v]];
  }
  mesh.face_vertices.reserve(faces.size() * 4);
  for (const std::uint32_t f : faces) {
    for (const std::uint32_t* c = base.face_begin(f); c != base.face_begin(f) + base.face_size(f); ++c)
      mesh.face_vertices.push_back(
          static_cast<std::uint32_t>(std::lower_bound(vertices.begin(), vertices.end(), *c) - vertices.begin()));
    mesh.face_offsets.push_back(static_cast<std::uint32_t>(mesh.face_vertices.size()));
  }
  return mesh;
}

// The whole hierarchy's numbers of one level's faces and edges (and, at
// level 0, whether an edge runs the other way there).
struct LevelMap {
  std::vector<std::uint32_t> faces, edges;
  std::vector<std::uint8_t> flipped;
};

// A level-(l-1) face's first corner (its first child face and interior child
// edge): the base's face offsets at level 0, four per face above.
std::uint64_t first_corner(const PolygonMesh& base, int level, std::uint32_t face) {
  return level == 0 ? std::uint64_t{base.face_offsets[face]} : 4 * std::uint64_t{face};
}

// Level 0: faces as given; edges through each face's corners (edge k of a
// face joins its corners k and k+1 in both meshes).
LevelMap base_level_map(const PolygonMesh& base, const BaseIncidence& incidence, const std::vector<std::uint32_t>& faces,
                        const std::vector<std::uint32_t>& vertices, const RefinementStep& s) {
  LevelMap map;
  map.faces = faces;
  map.edges.assign(s.parent_edge_count, kNone);
  map.flipped.assign(s.parent_edge_count, 0);
  for (std::uint32_t f = 0; f < s.parent_face_count; ++f)
    for (std::uint32_t k = s.face_offsets[f]; k < s.face_offsets[f + 1]; ++k) {
      const std::uint32_t local = s.face_edges[k] - s.first_edge_vertex();
      const std::uint32_t global = incidence.face_edges[base.face_offsets[faces[f]] + (k - s.face_offsets[f])];
      map.edges[local] = global;
      map.flipped[local] = vertices[s.edge_vertices[2 * local]] != incidence.edge_vertices[2 * global];
    }
  return map;
}

// Level l + 1 from level l (refinement_steps.cpp's numbering): child face j
// of a face and its interior edge j at the face's first corner + j; the
// halves of edge e at 2 e + i after all corners, i its end.
LevelMap child_level_map(const PolygonMesh& base, const PolygonMesh& patch, int level, const LevelMap& parent,
                         const RefinementStep& s, const LevelCounts& whole) {
  LevelMap map;
  const std::uint64_t corners = level == 0 ? patch.face_vertices.size() : 4 * std::uint64_t{s.parent_face_count};
  map.faces.resize(corners);
  map.edges.resize(corners + 2 * std::uint64_t{s.parent_edge_count});
  for (std::uint32_t f = 0; f < s.parent_face_count; ++f) {
    const std::uint64_t local = first_corner(patch, level, f), global = first_corner(base, level, parent.faces[f]);
    for (std::uint32_t j = 0; j < s.face_offsets[f + 1] - s.face_offsets[f]; ++j)
      map.faces[local + j] = map.edges[local + j] = static_cast<std::uint32_t>(global + j);
  }
  const auto whole_corners = static_cast<std::uint64_t>(whole.corners);
  for (std::uint32_t e = 0; e < s.parent_edge_count; ++e)
    for (std::uint32_t i = 0; i < 2; ++i) {
      const std::uint32_t end = parent.flipped.empty() ? i : i ^ parent.flipped[e];
      map.edges[corners + 2 * std::uint64_t{e} + i] = static_cast<std::uint32_t>(whole_corners + 2 * std::uint64_t{parent.edges[e]} + end);
    }
  return map;
}

}  // namespace

PatchHierarchy::PatchHierarchy(const PolygonMesh& base, const BaseIncidence& incidence,
                               std::vector<std::uint32_t> faces, int levels)
    : faces_(std::move(faces)), hierarchy_(patch_mesh(base, faces_, vertices_), levels) {
  const std::vector<LevelCounts> whole = refinement_counts(level_counts(base, incidence.edge_count()), levels);
  entries_.resize(hierarchy_.fine_vertex_count());
  std::copy(vertices_.begin(), vertices_.end(), entries_.begin());
  if (levels == 0) return;
  LevelMap map = base_level_map(base, incidence, faces_, vertices_, hierarchy_.step(1));
  for (int level = 1; level <= levels; ++level) {
    const RefinementStep& s = hierarchy_.step(level);
    const auto& w = whole[static_cast<std::size_t>(level - 1)];
    const auto v = static_cast<std::uint32_t>(w.vertices), f = static_cast<std::uint32_t>(w.faces);
    for (std::uint32_t k = 0; k < s.parent_face_count; ++k) entries_[s.first_face_vertex() + k] = v + map.faces[k];
    for (std::uint32_t k = 0; k < s.parent_edge_count; ++k) entries_[s.first_edge_vertex() + k] = v + f + map.edges[k];
    if (level < levels) map = child_level_map(base, hierarchy_.base(), level - 1, map, s, w);
  }
}

}  // namespace isowave
