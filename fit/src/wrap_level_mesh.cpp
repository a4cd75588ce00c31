#include "isowave/fit/wrap_level_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <utility>

#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/fit/trilinear.h"
#include "root_search.h"
#include "wrap_kernels.h"
#include "wrap_passes.h"

namespace isowave::wrap {
namespace {

// Connectivity of level l >= 1 straight from the refinement step: every list
// comes out in the order the generic edge-list construction of level 0 would
// give (a v vertex's neighbours by parent edge, an e vertex's ends then its
// f vertices, faces per vertex ascending), but the e and f vertices' rows are
// filled in parallel and only the v vertices' rows need a pass in order.
// `boundary_edge_count` receives each vertex's number of boundary edges.
void build_refined_connectivity(const RefinementStep& s, WrapLevelMesh& mesh,
                                std::vector<std::uint8_t>& boundary_edge_count) {
  const std::size_t n = mesh.vertex_count;
  const std::uint32_t parents = s.parent_vertex_count, first_face = s.first_face_vertex(),
                      first_edge = s.first_edge_vertex();
  const std::uint32_t parent_faces = s.parent_face_count, parent_edges = s.parent_edge_count;
  const std::size_t child_faces = s.face_offsets.back();
  const auto is_boundary = [&](std::uint32_t e) { return s.edge_faces[2 * e] == s.edge_faces[2 * e + 1]; };
  const auto face_size = [&](std::uint32_t f) { return s.face_offsets[f + 1] - s.face_offsets[f]; };

  // Row lengths, then offsets.
  mesh.neighbour_offsets.resize(n + 1);
  mesh.vertex_face_offsets.resize(n + 1);
  mesh.neighbour_offsets[0] = mesh.vertex_face_offsets[0] = 0;
  for_vertices(n, [&](std::size_t v) {
    std::uint32_t neighbours, faces;
    if (v < parents) {
      neighbours = s.vertex_edge_offsets[v + 1] - s.vertex_edge_offsets[v];
      faces = s.vertex_face_offsets[v + 1] - s.vertex_face_offsets[v];
    } else if (v < first_edge) {
      neighbours = faces = face_size(static_cast<std::uint32_t>(v - first_face));
    } else {
      const std::uint32_t adjacent = is_boundary(static_cast<std::uint32_t>(v - first_edge)) ? 1 : 2;
      neighbours = 2 + adjacent;
      faces = 2 * adjacent;
    }
    mesh.neighbour_offsets[v + 1] = neighbours;
    mesh.vertex_face_offsets[v + 1] = faces;
  });
  std::partial_sum(mesh.neighbour_offsets.begin(), mesh.neighbour_offsets.end(), mesh.neighbour_offsets.begin());
  std::partial_sum(mesh.vertex_face_offsets.begin(), mesh.vertex_face_offsets.end(), mesh.vertex_face_offsets.begin());
  reserve_on_huge_pages(mesh.neighbours, mesh.neighbour_offsets[n]);
  mesh.neighbours.resize(mesh.neighbour_offsets[n]);
  reserve_on_huge_pages(mesh.vertex_faces, mesh.vertex_face_offsets[n]);
  mesh.vertex_faces.resize(mesh.vertex_face_offsets[n]);
  mesh.boundary_neighbours.assign(2 * n, kNone);
  boundary_edge_count.assign(n, 0);

  // Faces: parent face corner k becomes child face k.
  mesh.face_offsets.resize(child_faces + 1);
  for_vertices(child_faces + 1, [&](std::size_t f) { mesh.face_offsets[f] = static_cast<std::uint32_t>(4 * f); });
  reserve_on_huge_pages(mesh.face_vertices, 4 * child_faces);
  mesh.face_vertices.resize(4 * child_faces);
  for_vertices(parent_faces, [&](std::size_t f) {
    const std::uint32_t centre = first_face + static_cast<std::uint32_t>(f);
    const std::uint32_t begin = s.face_offsets[f], end = s.face_offsets[f + 1];
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::uint32_t previous = k == begin ? end - 1 : k - 1;
      std::uint32_t* quad = mesh.face_vertices.data() + 4 * std::size_t{k};
      quad[0] = s.face_vertices[k];
      quad[1] = s.face_edges[k];
      quad[2] = centre;
      quad[3] = s.face_edges[previous];
    }
  });

  // f vertices: their e vertices and child faces, in corner order.
  for_vertices(parent_faces, [&](std::size_t f) {
    const std::uint32_t v = first_face + static_cast<std::uint32_t>(f);
    const std::uint32_t begin = s.face_offsets[f], size = face_size(static_cast<std::uint32_t>(f));
    for (std::uint32_t k = 0; k < size; ++k) {
      mesh.neighbours[mesh.neighbour_offsets[v] + k] = s.face_edges[begin + k];
      mesh.vertex_faces[mesh.vertex_face_offsets[v] + k] = begin + k;
    }
  });
  // e vertices: the edge's ends, then its f vertices ascending; the child
  // faces at corner k (edge k) and at the next corner (whose edge k-1 it is).
  for_vertices(parent_edges, [&](std::size_t e) {
    const std::uint32_t v = first_edge + static_cast<std::uint32_t>(e);
    const std::uint32_t a = s.edge_vertices[2 * e], b = s.edge_vertices[2 * e + 1];
    const std::uint32_t f0 = s.edge_faces[2 * e], f1 = s.edge_faces[2 * e + 1];
    std::uint32_t* row = mesh.neighbours.data() + mesh.neighbour_offsets[v];
    row[0] = a;
    row[1] = b;
    row[2] = std::min(f0, f1);
    if (f0 != f1) row[3] = std::max(f0, f1);
    else {
      mesh.boundary_neighbours[2 * std::size_t{v}] = a;
      mesh.boundary_neighbours[2 * std::size_t{v} + 1] = b;
      boundary_edge_count[v] = 2;
    }
    std::uint32_t faces[4];
    std::uint32_t count = 0;
    for (const std::uint32_t centre : {f0, f1}) {
      if (count > 0 && f0 == f1) break;
      const std::uint32_t f = centre - first_face, begin = s.face_offsets[f], end = s.face_offsets[f + 1];
      for (std::uint32_t k = begin; k < end; ++k)
        if (s.face_edges[k] == v) {
          faces[count++] = k;
          faces[count++] = k + 1 == end ? begin : k + 1;
          break;
        }
    }
    for (std::uint32_t i = 1; i < count; ++i)  // at most 4: insertion sort
      for (std::uint32_t j = i; j > 0 && faces[j - 1] > faces[j]; --j) std::swap(faces[j - 1], faces[j]);
    std::copy(faces, faces + count, mesh.vertex_faces.data() + mesh.vertex_face_offsets[v]);
  });
  // v vertices: their e vertices by parent edge, boundary ones also as
  // boundary neighbours; their child faces ascending. In order.
  {
    std::vector<std::uint32_t> fill(mesh.neighbour_offsets.begin(), mesh.neighbour_offsets.begin() + parents);
    for (std::uint32_t e = 0; e < parent_edges; ++e) {
      const std::uint32_t middle = first_edge + e;
      const bool boundary = is_boundary(e);
      for (const std::uint32_t end : {s.edge_vertices[2 * e], s.edge_vertices[2 * e + 1]}) {
        mesh.neighbours[fill[end]++] = middle;
        if (!boundary) continue;
        if (boundary_edge_count[end] < 2) mesh.boundary_neighbours[2 * std::size_t{end} + boundary_edge_count[end]] = middle;
        boundary_edge_count[end] = static_cast<std::uint8_t>(std::min(255, boundary_edge_count[end] + 1));
      }
    }
    fill.assign(mesh.vertex_face_offsets.begin(), mesh.vertex_face_offsets.begin() + parents);
    for (std::uint32_t k = 0; k < child_faces; ++k) {
      const std::uint32_t corner = s.face_vertices[k];
      mesh.vertex_faces[fill[corner]++] = k;
    }
  }
}

// A boundary vertex this close to two box faces lies on the box edge between
// them.
constexpr double kOnBoxEdgeCells = 1e-6;

// The box face, of those that p lies on (within kOnBoxEdgeCells), in which a
// boundary vertex on a box edge is held. Refinement puts such vertices there
// when a base boundary edge joins two sharp vertices on the same box edge,
// while the isosurface's boundary curve between them bulges into one of the
// two faces; held on the other face, they could only stay on the edge. A face
// qualifies when, from
// p inward across the edge within it, f - iso changes sign within two cells;
// of several, the one the surface runs along, judged by `toward_interior`
// (the vertex's neighbours' centroid minus p) having the smallest component
// across that face; `fallback` when none qualifies.
int face_of_boundary_curve(const TrilinearGrid& field, const Box& box, double cell, double iso, const Vec3& p,
                           const Vec3& toward_interior, int fallback) {
  constexpr double kStep = 0.05, kReach = 2.0;  // cells
  const double at_p = field.value(p) - iso;
  if (!(at_p != 0)) return fallback;  // on the isosurface, or NaN
  const auto on = [&](int face) { return std::abs(p[face >> 1] - box.plane(face)) <= kOnBoxEdgeCells * cell; };
  int best = fallback;
  double best_across = std::numeric_limits<double>::infinity();
  for (int face = 0; face < 6; ++face) {
    if (!on(face) || std::abs(toward_interior[face >> 1]) >= best_across) continue;
    bool crossing = false;
    for (int other = 0; other < 6 && !crossing; ++other) {
      if ((other >> 1) == (face >> 1) || !on(other)) continue;
      Vec3 inward;
      inward[other >> 1] = (other & 1) ? -cell : cell;
      double t;
      crossing = detail::find_root_along_line([&](double s) { return field.value(p + s * inward) - iso; }, at_p, kStep,
                                              kReach, kStep, kStep, t);
    }
    if (crossing) {
      best = face;
      best_across = std::abs(toward_interior[face >> 1]);
    }
  }
  return best;
}

// The base's edges as (a, b) pairs and boundary flags: from the first
// refinement step, or without one by pairing half-edges.
void base_edges(const SubdivisionHierarchy& hierarchy, std::vector<std::uint32_t>& edge_ends,
                std::vector<std::uint8_t>& edge_boundary) {
  const PolygonMesh& base = hierarchy.base();
  if (hierarchy.levels() >= 1) {
    const RefinementStep& s = hierarchy.step(1);
    edge_ends = s.edge_vertices;
    for (std::uint32_t e = 0; e < s.parent_edge_count; ++e)
      edge_boundary.push_back(s.edge_faces[2 * e] == s.edge_faces[2 * e + 1]);
  } else {
    // No refinement step to read: pair up half-edges by sorting.
    struct HalfEdge {
      std::uint32_t low, high, from;
    };
    std::vector<HalfEdge> half_edges;
    for (std::size_t f = 0; f < base.face_count(); ++f) {
      const std::uint32_t* face = base.face_begin(f);
      const std::uint32_t size = base.face_size(f);
      for (std::uint32_t k = 0; k < size; ++k) {
        const std::uint32_t a = face[k], b = face[k + 1 == size ? 0 : k + 1];
        half_edges.push_back({std::min(a, b), std::max(a, b), a});
      }
    }
    std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
      return x.low != y.low ? x.low < y.low : x.high < y.high;
    });
    for (std::size_t k = 0; k < half_edges.size();) {
      std::size_t m = k + 1;
      while (m < half_edges.size() && half_edges[m].low == half_edges[k].low && half_edges[m].high == half_edges[k].high) ++m;
      edge_ends.insert(edge_ends.end(), {half_edges[k].low, half_edges[k].high});
      edge_boundary.push_back(m - k == 1);
      k = m;
    }
  }
}

// Level 0's connectivity: the base's faces, then the generic compressed rows
// from its edges. `boundary_edge_count` as in build_refined_connectivity().
void build_base_connectivity(const SubdivisionHierarchy& hierarchy, WrapLevelMesh& mesh,
                             std::vector<std::uint8_t>& boundary_edge_count) {
  const std::size_t n = mesh.vertex_count;
  std::vector<std::uint32_t> edge_ends;
  std::vector<std::uint8_t> edge_boundary;
  mesh.face_offsets = hierarchy.base().face_offsets;
  mesh.face_vertices = hierarchy.base().face_vertices;
  base_edges(hierarchy, edge_ends, edge_boundary);

  // Neighbours and boundary neighbours.
  const std::size_t edge_count = edge_boundary.size();
  mesh.neighbour_offsets.assign(n + 1, 0);
  for (std::size_t e = 0; e < edge_count; ++e) {
    ++mesh.neighbour_offsets[edge_ends[2 * e] + 1];
    ++mesh.neighbour_offsets[edge_ends[2 * e + 1] + 1];
  }
  std::partial_sum(mesh.neighbour_offsets.begin(), mesh.neighbour_offsets.end(), mesh.neighbour_offsets.begin());
  mesh.neighbours.resize(mesh.neighbour_offsets[n]);
  mesh.boundary_neighbours.assign(2 * n, kNone);
  boundary_edge_count.assign(n, 0);
  {
    std::vector<std::uint32_t> fill(mesh.neighbour_offsets.begin(), mesh.neighbour_offsets.end() - 1);
    for (std::size_t e = 0; e < edge_count; ++e) {
      const std::uint32_t a = edge_ends[2 * e], b = edge_ends[2 * e + 1];
      mesh.neighbours[fill[a]++] = b;
      mesh.neighbours[fill[b]++] = a;
      if (!edge_boundary[e]) continue;
      for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, a}}) {
        if (boundary_edge_count[from] < 2) mesh.boundary_neighbours[2 * from + boundary_edge_count[from]] = to;
        boundary_edge_count[from] = static_cast<std::uint8_t>(std::min(255, boundary_edge_count[from] + 1));
      }
    }
  }
  std::vector<std::uint32_t>().swap(edge_ends);

  // Faces per vertex.
  mesh.vertex_face_offsets.assign(n + 1, 0);
  for (std::uint32_t v : mesh.face_vertices) ++mesh.vertex_face_offsets[v + 1];
  std::partial_sum(mesh.vertex_face_offsets.begin(), mesh.vertex_face_offsets.end(), mesh.vertex_face_offsets.begin());
  mesh.vertex_faces.resize(mesh.vertex_face_offsets[n]);
  {
    std::vector<std::uint32_t> fill(mesh.vertex_face_offsets.begin(), mesh.vertex_face_offsets.end() - 1);
    for (std::size_t f = 0; f + 1 < mesh.face_offsets.size(); ++f)
      for (std::uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k)
        mesh.vertex_faces[fill[mesh.face_vertices[k]]++] = static_cast<std::uint32_t>(f);
  }
}

// Each vertex's role, and the box face a boundary vertex is held on (see
// make_wrap_level_mesh()).
void assign_roles(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& positions,
                  const Volume& box_volume, double iso, const std::vector<std::uint8_t>& boundary_edge_count,
                  WrapLevelMesh& mesh) {
  const std::size_t n = mesh.vertex_count;
  const std::vector<std::uint8_t> sharp = hierarchy.sharp_flags(mesh.level);
  const Box box(box_volume);
  // Only read with an isovalue (the box alone may come without samples).
  const std::optional<TrilinearGrid> field =
      std::isfinite(iso) ? std::optional<TrilinearGrid>(std::in_place, box_volume) : std::nullopt;
  const double cell = box_volume.cell_size();
  mesh.role.assign(n, WrapRole::Free);
  mesh.box_face.assign(n, -1);
  for_vertices(n, [&](std::size_t v) {
    if (sharp[v] || boundary_edge_count[v] >= 3) {
      mesh.role[v] = WrapRole::Fixed;
    } else if (boundary_edge_count[v] == 2) {
      mesh.role[v] = WrapRole::Boundary;
      int nearest = -1, on_faces = 0;
      double nearest_distance = cell;  // held only when within one cell of a face
      for (int face = 0; face < 6; ++face) {
        const double d = std::abs(positions[v][face >> 1] - box.plane(face));
        on_faces += d <= kOnBoxEdgeCells * cell ? 1 : 0;
        if (d <= nearest_distance) {
          nearest = face;
          nearest_distance = d;
        }
      }
      if (on_faces >= 2 && field) {
        Vec3 centroid;
        for (std::uint32_t k = mesh.neighbour_offsets[v]; k < mesh.neighbour_offsets[v + 1]; ++k)
          centroid += positions[mesh.neighbours[k]];
        const double count = double(mesh.neighbour_offsets[v + 1] - mesh.neighbour_offsets[v]);
        nearest = face_of_boundary_curve(*field, box, cell, iso, positions[v], (1.0 / count) * centroid - positions[v],
                                         nearest);
      }
      mesh.box_face[v] = static_cast<std::int8_t>(nearest);
    }
  });
}

}  // namespace

void fill_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, int level, const std::vector<Vec3>& positions,
                          const Volume& box_volume, double iso, WrapLevelMesh& mesh) {
  if (level < 0 || level > hierarchy.levels())
    throw Error(ErrorKind::InvalidArgument, "level " + std::to_string(level) + " is not in the hierarchy");
  mesh.level = level;
  const std::size_t n = hierarchy.vertex_count(level);
  mesh.vertex_count = n;
  if (positions.size() < n) throw Error(ErrorKind::InvalidArgument, "too few positions for the level");

  std::vector<std::uint8_t> boundary_edge_count;
  if (level >= 1)
    build_refined_connectivity(hierarchy.step(level), mesh, boundary_edge_count);
  else
    build_base_connectivity(hierarchy, mesh, boundary_edge_count);
  assign_roles(hierarchy, positions, box_volume, iso, boundary_edge_count, mesh);
}

void reserve_finest_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, WrapLevelMesh& mesh) {
  const int levels = hierarchy.levels();
  if (levels < 1) return;
  const RefinementStep& s = hierarchy.step(levels);
  const std::size_t n = hierarchy.vertex_count(levels), faces = s.face_offsets.back();
  const std::size_t edges = 2 * std::size_t{s.parent_edge_count} + faces;  // split edges and one per corner
  mesh.neighbour_offsets.reserve(n + 1);
  mesh.vertex_face_offsets.reserve(n + 1);
  mesh.face_offsets.reserve(faces + 1);
  reserve_on_huge_pages(mesh.neighbours, 2 * edges);
  reserve_on_huge_pages(mesh.vertex_faces, 4 * faces);
  reserve_on_huge_pages(mesh.face_vertices, 4 * faces);
  mesh.boundary_neighbours.reserve(2 * n);
  mesh.role.reserve(n);
  mesh.box_face.reserve(n);
}

}  // namespace isowave::wrap

namespace isowave {

WrapLevelMesh make_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, int level,
                                   const std::vector<Vec3>& positions, const Volume& box_volume, double iso) {
  WrapLevelMesh mesh;
  wrap::fill_wrap_level_mesh(hierarchy, level, positions, box_volume, iso, mesh);
  return mesh;
}

void constrain_to_box(const WrapLevelMesh& mesh, const Volume& box_volume, std::vector<Vec3>& positions) {
  const wrap::Box box(box_volume);
  wrap::for_vertices(mesh.vertex_count, [&](std::size_t v) {
    if (mesh.role[v] != WrapRole::Fixed) positions[v] = wrap::place(mesh, box, v, positions[v]);
  });
}

}  // namespace isowave
