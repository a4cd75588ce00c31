#include "isowave/fit/shrink_wrap.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/fit/trilinear.h"
#include "isowave/transform/wavelet_transform.h"
#include "coverage_pull.h"
#include "fitted_field.h"
#include "root_search.h"

namespace isowave {
namespace {

constexpr std::uint32_t kNone = WrapLevelMesh::kNone;

template <class Body>
void for_vertices(std::size_t n, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v) body(v);
  });
}

// Runs body(begin, end, partial) over fixed blocks of items in parallel and
// returns the blocks' partial results in order: summing them in that order
// gives statistics that do not depend on the thread count, without a
// per-item array.
constexpr std::size_t kBlock = 4096;
// How many items ahead the gathering loops prefetch.
constexpr std::size_t kPrefetchDistance = 8;
template <class Partial, class Body>
std::vector<Partial> for_blocks(std::size_t n, const Body& body) {
  std::vector<Partial> partials((n + kBlock - 1) / kBlock);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, partials.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) body(b * kBlock, std::min(n, (b + 1) * kBlock), partials[b]);
  });
  return partials;
}

struct Box {
  Vec3 low, high;
  explicit Box(const Volume& volume) : low(volume_box_min(volume)), high(volume_box_max(volume)) {}
  Vec3 clamp(const Vec3& p) const {
    return {std::clamp(p.x, low.x, high.x), std::clamp(p.y, low.y, high.y), std::clamp(p.z, low.z, high.z)};
  }
  double plane(int face) const { return (face & 1) ? high[face >> 1] : low[face >> 1]; }
  // The range of t for which p + t d stays in the box (p inside).
  void clip(const Vec3& p, const Vec3& d, double& t_low, double& t_high) const {
    t_low = -1e300;
    t_high = 1e300;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0) continue;
      double t0 = (low[a] - p[a]) / d[a], t1 = (high[a] - p[a]) / d[a];
      if (t0 > t1) std::swap(t0, t1);
      t_low = std::max(t_low, std::min(t0, 0.0));
      t_high = std::min(t_high, std::max(t1, 0.0));
    }
  }
};

// Keeps the vertex on its box face and inside the box.
inline Vec3 place(const WrapLevelMesh& mesh, const Box& box, std::size_t v, Vec3 p) {
  const int face = mesh.box_face[v];
  if (face >= 0) p[face >> 1] = box.plane(face);
  return box.clamp(p);
}

// A polygon's Newell vector: twice its area vector.
inline Vec3 newell_vector(const std::uint32_t* face, std::uint32_t size, const std::vector<Vec3>& p) {
  Vec3 n;
  for (std::uint32_t k = 0; k < size; ++k) {
    const Vec3& a = p[face[k]];
    const Vec3& b = p[face[k + 1 == size ? 0 : k + 1]];
    n += cross(a, b);
  }
  return n;
}

// Unit normal of a polygon by Newell's method (zero if degenerate).
inline Vec3 face_normal(const std::uint32_t* face, std::uint32_t size, const std::vector<Vec3>& p) {
  return normalized(newell_vector(face, size, p));
}

// The direction a vertex may move in: box-held vertices only within their face.
inline Vec3 allowed_direction(const WrapLevelMesh& mesh, std::size_t v, Vec3 d) {
  const int face = mesh.box_face[v];
  if (face >= 0) d[face >> 1] = 0.0;
  return normalized(d);
}

}  // namespace

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

}  // namespace

namespace {

// A boundary vertex this close to two box faces lies on the box edge between
// them.
constexpr double kOnBoxEdgeCells = 1e-6;

// The box face, of those that p lies on (within kOnBoxEdgeCells), in which a
// boundary vertex on a box edge is held. Refinement puts such vertices there
// when a base boundary edge joins two sharp vertices on the same box edge,
// while the isosurface's boundary curve between them bulges into one of the
// two faces (mixing at 96^3: into x = 95 by up to 0.7 cell); held on the
// other face, they could only stay on the edge. A face qualifies when, from
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

// make_wrap_level_mesh() into `mesh`, reusing its buffers where they have
// room: the shrink-wrap sizes them for the finest level once, since fresh
// pages are expensive (zeroed by the kernel and, in a virtual machine, often
// backed by the host on first touch: on the 2-core test VM several seconds
// per gigabyte).
void fill_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, int level, const std::vector<Vec3>& positions,
                          const Volume& box_volume, double iso, WrapLevelMesh& mesh) {
  if (level < 0 || level > hierarchy.levels())
    throw Error(ErrorKind::InvalidArgument, "level " + std::to_string(level) + " is not in the hierarchy");
  mesh.level = level;
  const std::size_t n = hierarchy.vertex_count(level);
  mesh.vertex_count = n;
  if (positions.size() < n) throw Error(ErrorKind::InvalidArgument, "too few positions for the level");

  std::vector<std::uint8_t> boundary_edge_count;
  if (level >= 1) {
    build_refined_connectivity(hierarchy.step(level), mesh, boundary_edge_count);
  } else {
    // Level 0: edges as (a, b, boundary) from the first refinement step, or by
    // pairing half-edges; then the generic compressed rows.
    std::vector<std::uint32_t> edge_ends;
    std::vector<std::uint8_t> edge_boundary;
    {
      const PolygonMesh& base = hierarchy.base();
      mesh.face_offsets = base.face_offsets;
      mesh.face_vertices = base.face_vertices;
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

  // Roles and box faces.
  const std::vector<std::uint8_t> sharp = hierarchy.sharp_flags(level);
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

// Room in `mesh` for the finest level of the hierarchy, the large arrays on
// huge pages faulted in on all threads.
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

}  // namespace

WrapLevelMesh make_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, int level,
                                   const std::vector<Vec3>& positions, const Volume& box_volume, double iso) {
  WrapLevelMesh mesh;
  fill_wrap_level_mesh(hierarchy, level, positions, box_volume, iso, mesh);
  return mesh;
}

void constrain_to_box(const WrapLevelMesh& mesh, const Volume& box_volume, std::vector<Vec3>& positions) {
  const Box box(box_volume);
  for_vertices(mesh.vertex_count, [&](std::size_t v) {
    if (mesh.role[v] != WrapRole::Fixed) positions[v] = place(mesh, box, v, positions[v]);
  });
}

namespace {

// Unit face normals in single precision: the vertex loops gather them at
// scattered places, and half the bytes per normal is worth more there than
// digits beyond the 7th in a search direction.
struct FaceNormal {
  float x, y, z;
};
using FaceNormals = HugePageVector<FaceNormal>;

void compute_face_normals(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, FaceNormals& face_normals) {
  const std::size_t faces = mesh.face_count();
  face_normals.resize(faces);
  for_vertices(faces, [&](std::size_t f) {
    const Vec3 n = face_normal(mesh.face_vertices.data() + mesh.face_offsets[f],
                               mesh.face_offsets[f + 1] - mesh.face_offsets[f], positions);
    face_normals[f] = {static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z)};
  });
}

// Unit average of the normals of the faces around v (zero if undefined).
Vec3 vertex_normal(const WrapLevelMesh& mesh, const FaceNormals& face_normals, std::size_t v) {
  double x = 0, y = 0, z = 0;
  for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
    const FaceNormal& n = face_normals[mesh.vertex_faces[k]];
    x += n.x;
    y += n.y;
    z += n.z;
  }
  return normalized(Vec3{x, y, z});
}

// Where the relaxation pulls vertex v: the centroid of its two neighbours
// along its boundary curve for a vertex held on one, else of all its
// neighbours; false for a vertex without neighbours.
bool relaxation_centroid(const WrapLevelMesh& mesh, std::size_t v, const std::vector<Vec3>& positions, Vec3& centroid) {
  const std::uint32_t b0 = mesh.boundary_neighbours[2 * v], b1 = mesh.boundary_neighbours[2 * v + 1];
  if (mesh.role[v] == WrapRole::Boundary && b0 != kNone && b1 != kNone) {
    centroid = 0.5 * (positions[b0] + positions[b1]);
    return true;
  }
  const std::uint32_t begin = mesh.neighbour_offsets[v], end = mesh.neighbour_offsets[v + 1];
  if (begin == end) return false;
  centroid = Vec3{};
  for (std::uint32_t k = begin; k < end; ++k) centroid += positions[mesh.neighbours[k]];
  centroid *= 1.0 / double(end - begin);
  return true;
}

// relax() with, optionally, a flag per vertex: a flagged free vertex moves
// only within the plane normal to its vertex normal (the normal part of the
// move, which on a coarse closed mesh is mostly a shrink, is left to the
// attraction).
void relax_with(const WrapLevelMesh& mesh, const Volume& box_volume, double weight, const std::vector<Vec3>& in,
                std::vector<Vec3>& out, const std::uint8_t* tangent_only) {
  assert(in.size() >= mesh.vertex_count && &in != &out);
  out.resize(std::max(out.size(), mesh.vertex_count));
  const Box box(box_volume);
  for_vertices(mesh.vertex_count, [&](std::size_t v) {
    const Vec3& p = in[v];
    out[v] = p;
    Vec3 centroid;
    // A vertex held on a box face does not relax: along its boundary curve
    // the relaxation only shrinks the curve, which the attraction within the
    // face does not restore where the curve is narrower than a cell (a speck
    // on the face collapsed to one point).
    if (mesh.role[v] == WrapRole::Fixed || mesh.box_face[v] >= 0 || !relaxation_centroid(mesh, v, in, centroid)) return;
    Vec3 relaxed = (1.0 - weight) * p + weight * centroid;
    if (tangent_only && tangent_only[v] && mesh.role[v] == WrapRole::Free) {
      // The unit average of the normals of its faces (as in the attraction).
      Vec3 sum;
      for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
        const std::uint32_t f = mesh.vertex_faces[k];
        sum += face_normal(mesh.face_vertices.data() + mesh.face_offsets[f], mesh.face_offsets[f + 1] - mesh.face_offsets[f], in);
      }
      const Vec3 n = normalized(sum);
      relaxed -= dot(relaxed - p, n) * n;
    }
    const Vec3 moved = place(mesh, box, v, relaxed);
    if (is_finite(moved)) out[v] = moved;
  });
}

}  // namespace

void relax(const WrapLevelMesh& mesh, const Volume& box_volume, double weight, const std::vector<Vec3>& in,
           std::vector<Vec3>& out) {
  relax_with(mesh, box_volume, weight, in, out, nullptr);
}

std::vector<Vec3> vertex_normals(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions) {
  FaceNormals face_normals;
  compute_face_normals(mesh, positions, face_normals);
  std::vector<Vec3> normals(mesh.vertex_count);
  for_vertices(mesh.vertex_count, [&](std::size_t v) { normals[v] = vertex_normal(mesh, face_normals, v); });
  return normals;
}

namespace {

// A line search for a zero crossing of G(t) = D(p + t d), D the distance
// field, on one side of p: the last sample (distance s >= 0 from p and its
// value) and the number of samples taken, so that a search stopped at one
// limit can go on to a farther one.
struct CrossingSearch {
  double s = 0, g = 0;
  int samples = 0;
};

// Continues `search` along direction `sign` (+1 or -1 times d) up to s <=
// limit, to the first zero crossing that G crosses upward in t (field
// gradient agreeing with d); returns its distance s >= 0, or negative if none.
// Steps by the distance value (no surface is nearer than |D|), at least
// min_step.
template <class G>
double continue_crossing_search(const G& g_of_t, CrossingSearch& search, double sign, double limit, double min_step,
                                double tolerance) {
  // A line grazing the surface would otherwise take limit / min_step samples.
  constexpr int kMaxSamples = 24;
  while (search.samples < kMaxSamples && search.s < limit) {
    const double step = std::max(0.9 * std::abs(search.g), min_step);
    const double s = std::min(search.s + step, limit);
    const double g = g_of_t(sign * s);
    ++search.samples;
    if (detail::root_side(g) != detail::root_side(search.g)) {
      const bool agrees = sign > 0 ? (search.g < 0 && g >= 0) : (search.g >= 0 && g < 0);
      if (agrees) {
        const double t = detail::refine_bracket(g_of_t, sign * search.s, search.g, sign * s, g, tolerance, tolerance);
        return std::abs(t);
      }
    }
    search.s = s;
    search.g = g;
  }
  return -1;
}

struct AttractionPartial {
  std::size_t movable = 0, attracted = 0, out_of_reach = 0, no_direction = 0;
  double move_sum = 0, move_max = 0;  // cells
};

// attract() with the face-normal buffer supplied by the caller, which reuses
// it across rounds (hundreds of megabytes at the finest level).
AttractionStatistics attract_with(const WrapLevelMesh& mesh, const SignedDistanceField& distance,
                                  const AttractionOptions& options, const std::vector<Vec3>& in,
                                  std::vector<Vec3>& out, FaceNormals& face_normals) {
  assert(in.size() >= mesh.vertex_count && &in != &out);
  out.resize(std::max(out.size(), mesh.vertex_count));
  const Volume& field = distance.distance;
  const TrilinearGrid grid(field);
  const Box box(field);
  const double cell = field.cell_size();
  const double min_step = 0.2 * cell, tolerance = 1e-3 * cell;
  // The reach is never shorter than this; the searches go this far before
  // the vertex's edge lengths are needed.
  const double near = options.min_reach_cells * cell;
  compute_face_normals(mesh, in, face_normals);

  const auto attract_vertex = [&](std::size_t v, AttractionPartial& partial) {
    const Vec3& p = in[v];
    out[v] = p;
    if (mesh.role[v] == WrapRole::Fixed) return;
    ++partial.movable;
    Vec3 d = vertex_normal(mesh, face_normals, v);
    if (mesh.box_face[v] >= 0) d = allowed_direction(mesh, v, d);
    if (squared_norm(d) == 0) {
      ++partial.no_direction;
      return;
    }
    double reach = -1;  // computed when a search goes past `near`
    const auto full_reach = [&]() {
      if (reach < 0) {
        double edge_sum = 0;
        const std::uint32_t begin = mesh.neighbour_offsets[v], end = mesh.neighbour_offsets[v + 1];
        for (std::uint32_t k = begin; k < end; ++k) edge_sum += norm(in[mesh.neighbours[k]] - p);
        const double mean_edge = end > begin ? edge_sum / double(end - begin) : 0.0;
        reach = std::max(options.reach_edges * mean_edge, near);
      }
      return reach;
    };
    double t_low, t_high;
    box.clip(p, d, t_low, t_high);
    const Vec3 pg = grid.grid_point(p), dg = grid.grid_direction(d);
    const auto g_of_t = [&](double t) { return grid.value_at(pg + t * dg); };
    const TrilinearSample at_p = grid.sample_at(pg);
    const double g0 = at_p.value;
    // Searches one side up to `box_limit` (and the reach): first to `near`,
    // then, if nothing was found, on to the full reach.
    const auto search_side = [&](CrossingSearch& search, double sign, double box_limit) {
      double found = continue_crossing_search(g_of_t, search, sign, std::min(near, box_limit), min_step, tolerance);
      if (found < 0 && box_limit > near && full_reach() > near)
        found = continue_crossing_search(g_of_t, search, sign, std::min(reach, box_limit), min_step, tolerance);
      return found;
    };
    double best = -1, best_sign = 1;
    if (g0 == 0) {
      best = 0;
    } else {
      // The likelier side first (inside: forward), then the other one only
      // as far as the crossing already found.
      const double first_sign = g0 < 0 ? 1.0 : -1.0;
      const double first_box = first_sign > 0 ? t_high : -t_low, second_box = first_sign > 0 ? -t_low : t_high;
      const double first_step = std::max(0.9 * std::abs(g0), min_step);
      // Near the surface (the common case after the first rounds) one Newton
      // step along the line usually lands on the crossing: accepted when the
      // gradient agrees with d, the step stays within the search's first
      // step (where the search would only have compared the signs at its
      // ends) and the value there is within the tolerance, or it brackets
      // the crossing for the refinement.
      const double slope = dot(at_p.gradient, d);
      if (slope > 0) {
        const double newton = -g0 / slope;  // signed like first_sign
        if (std::abs(newton) <= std::min(near, first_box)) {
          const double g1 = g_of_t(newton);
          if (std::abs(g1) <= tolerance)
            best = std::abs(newton);
          else if (detail::root_side(g1) != detail::root_side(g0))
            best = std::abs(detail::refine_bracket(g_of_t, 0.0, g0, newton, g1, tolerance, tolerance));
        }
      }
      best_sign = first_sign;
      if (best < 0) {
        CrossingSearch first{0, g0, 0};
        best = search_side(first, first_sign, first_box);
      }
      CrossingSearch second{0, g0, 0};
      double other = -1;
      if (best < 0) {
        other = search_side(second, -first_sign, second_box);
      } else {
        // A first sample on the other side can only bracket a crossing that
        // disagrees (G starts on the wrong side there), so a search that
        // would take just one sample is skipped.
        const double limit = std::min(best, second_box);
        if (limit > first_step)
          other = continue_crossing_search(g_of_t, second, -first_sign, limit, min_step, tolerance);
      }
      if (other >= 0 && (best < 0 || other < best)) {
        best = other;
        best_sign = -first_sign;
      }
    }
    if (best < 0) {
      ++partial.out_of_reach;
      return;
    }
    const Vec3 target = place(mesh, box, v, p + (best_sign * best) * d);
    if (!is_finite(target)) {
      ++partial.no_direction;
      return;
    }
    out[v] = target;
    ++partial.attracted;
    const double moved = best / cell;
    partial.move_sum += moved;
    partial.move_max = std::max(partial.move_max, moved);
  };
  const std::vector<AttractionPartial> partials =
      for_blocks<AttractionPartial>(mesh.vertex_count, [&](std::size_t begin, std::size_t end, AttractionPartial& partial) {
        for (std::size_t v = begin; v < end; ++v) {
          // The samples and face normals of a vertex a few ahead: both are
          // gathered from arrays far larger than the cache.
          if (v + kPrefetchDistance < end) {
            const std::size_t ahead = v + kPrefetchDistance;
            grid.prefetch_at(grid.grid_point(in[ahead]));
            for (std::uint32_t k = mesh.vertex_face_offsets[ahead]; k < mesh.vertex_face_offsets[ahead + 1]; ++k)
              __builtin_prefetch(&face_normals[mesh.vertex_faces[k]]);
          }
          attract_vertex(v, partial);
        }
      });

  AttractionStatistics stats;
  double move_sum = 0;
  for (const AttractionPartial& partial : partials) {
    stats.movable += partial.movable;
    stats.attracted += partial.attracted;
    stats.out_of_reach += partial.out_of_reach;
    stats.no_direction += partial.no_direction;
    move_sum += partial.move_sum;
    stats.max_move_cells = std::max(stats.max_move_cells, partial.move_max);
  }
  stats.mean_move_cells = stats.attracted ? move_sum / double(stats.attracted) : 0.0;
  return stats;
}

}  // namespace

AttractionStatistics attract(const WrapLevelMesh& mesh, const SignedDistanceField& distance,
                             const AttractionOptions& options, const std::vector<Vec3>& in, std::vector<Vec3>& out) {
  FaceNormals face_normals;
  return attract_with(mesh, distance, options, in, out, face_normals);
}

namespace {

// Moves p along the field gradient (within the vertex's box face, if held;
// with `parallel_axis` >= 0 normal to that axis) to where the trilinear field
// equals iso, at most `range` away. False if there is no gradient or no root
// within range.
bool project_onto_isosurface(const WrapLevelMesh& mesh, const Box& box, const TrilinearGrid& field, double cell,
                             double iso, double range, std::size_t v, const Vec3& p, Vec3& target,
                             int parallel_axis = -1) {
  const Vec3 pg = field.grid_point(p);
  const TrilinearSample s = field.sample_at(pg);
  const double h0 = s.value - iso;
  if (!std::isfinite(h0)) return false;
  if (h0 == 0) {
    target = p;
    return true;
  }
  Vec3 u = s.gradient;
  if (parallel_axis >= 0) u[parallel_axis] = 0.0;
  u = allowed_direction(mesh, v, u);
  const double slope = dot(s.gradient, u);
  if (!(slope > 0)) return false;
  double t_low, t_high;
  box.clip(p, u, t_low, t_high);
  const Vec3 ug = field.grid_direction(u);
  const auto h = [&](double t) { return field.value_at(pg + std::clamp(t, t_low, t_high) * ug) - iso; };
  double t = 0;
  const double tolerance = 1e-4 * cell;
  // Newton steps along the line (one or two samples near the surface), then
  // the bracketed search if they do not settle. Newton converges
  // quadratically (the trilinear field is a cubic along the line), so a
  // correction under 1e-2 cells leaves an error near 1e-4 cells: taken
  // without another sample to confirm it.
  const double settled = 1e-2 * cell;
  bool found = false;
  double newton = -h0 / slope;
  for (int step = 0; step < 3 && std::abs(newton) <= range; ++step) {
    const TrilinearSample sample = field.sample_at(pg + std::clamp(newton, t_low, t_high) * ug);
    const double along = dot(sample.gradient, u);
    if (!(along > 0) || !std::isfinite(sample.value)) break;
    const double correction = (sample.value - iso) / along;
    newton -= correction;
    if (std::abs(correction) <= settled) {
      found = std::abs(newton) <= range && newton >= t_low && newton <= t_high;
      break;
    }
  }
  if (found) t = newton;
  else if (!detail::find_root_along_line(h, h0, -h0 / slope, range, 0.25 * cell, tolerance, t)) return false;
  target = place(mesh, box, v, p + std::clamp(t, t_low, t_high) * u);
  return is_finite(target);
}

// Face f's Newell normal (twice its area vector) and the field gradient at
// its centroid, its corners at position(vertex).
template <class Position>
inline void face_normal_and_gradient(const WrapLevelMesh& mesh, const TrilinearGrid& field, std::size_t f,
                                     const Position& position, Vec3& newell, Vec3& gradient) {
  const std::uint32_t begin = mesh.face_offsets[f], size = mesh.face_offsets[f + 1] - begin;
  const std::uint32_t* corners = mesh.face_vertices.data() + begin;
  Vec3 centroid;
  newell = Vec3{};
  for (std::uint32_t k = 0; k < size; ++k) {
    const Vec3 a = position(corners[k]);
    newell += cross(a, position(corners[k + 1 == size ? 0 : k + 1]));
    centroid += a;
  }
  centroid *= 1.0 / double(size);
  gradient = field.sample(centroid).gradient;
}

// 1 if face f's normal disagrees with the field gradient at its centroid
// (normals toward lower values unless flipped: expected_sign -1, else +1),
// its corners at position(vertex).
template <class Position>
inline std::uint8_t face_tangled_at(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                                    std::size_t f, const Position& position) {
  Vec3 newell, gradient;
  face_normal_and_gradient(mesh, field, f, position, newell, gradient);
  return !(expected_sign * dot(newell, gradient) > 0);
}

inline std::uint8_t face_tangled(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                                 const std::vector<Vec3>& positions, std::size_t f) {
  return face_tangled_at(mesh, field, expected_sign, f, [&](std::uint32_t v) -> const Vec3& { return positions[v]; });
}

// How many of vertex v's faces are tangled (face_tangled_at) with v at `at`
// and the other corners where `positions` has them.
int tangled_faces_around(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                         const std::vector<Vec3>& positions, std::uint32_t v, const Vec3& at) {
  const auto position = [&](std::uint32_t u) -> const Vec3& { return u == v ? at : positions[u]; };
  int count = 0;
  for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
    count += face_tangled_at(mesh, field, expected_sign, mesh.vertex_faces[k], position);
  return count;
}

// The centroid's samples are near those of the first corner.
inline void prefetch_face(const WrapLevelMesh& mesh, const TrilinearGrid& field, const std::vector<Vec3>& positions,
                          std::size_t f) {
  field.prefetch_at(field.grid_point(positions[mesh.face_vertices[mesh.face_offsets[f]]]));
}

// Sets tangled[f] to face_tangled() for every face and returns their number.
std::size_t find_tangled_faces(const WrapLevelMesh& mesh, const TrilinearGrid& field, bool flip,
                               const std::vector<Vec3>& positions, HugePageVector<std::uint8_t>& tangled) {
  const double expected_sign = flip ? 1.0 : -1.0;
  if (tangled.capacity() < mesh.face_count()) reserve_fresh_on_huge_pages(tangled, mesh.face_count());
  tangled.resize(mesh.face_count());
  const std::vector<std::size_t> counts =
      for_blocks<std::size_t>(mesh.face_count(), [&](std::size_t first, std::size_t last, std::size_t& count) {
        for (std::size_t f = first; f < last; ++f) {
          if (f + kPrefetchDistance < last) prefetch_face(mesh, field, positions, f + kPrefetchDistance);
          tangled[f] = face_tangled(mesh, field, expected_sign, positions, f);
          count += tangled[f];
        }
      });
  std::size_t total = 0;
  for (std::size_t count : counts) total += count;
  return total;
}

// Rounds of retrying failed corrections from the neighbours' centroid: on the
// engine CT (base 1/16, 3 levels) the fifth fixed none.
constexpr int kCorrectionRetryRounds = 5;
// The last search of the correction reaches this many times its range.
constexpr double kWideSearchRanges = 3.0;
// How far a stranded vertex may move to the extracted surface (see
// CorrectionStatistics::from_extracted_surface), in cells: the embryo's lie
// up to 9.8 cells from it.
constexpr double kStrandedReachCells = 16.0;

struct CorrectionPartial {
  std::size_t movable = 0, corrected = 0, nearest = 0, along_box = 0;
  double move_sum = 0, move_max = 0;
  std::vector<std::uint32_t> failed;  // no root found: left where they were
};

// A point of the zero set of `distance` reached from p by steps along its
// gradient (kept in the box, within `range` of p); false if they do not
// settle. Newton's steps, or with `unit_steps` the distance itself along
// the unit gradient wherever the gradient is shorter than 1: the field is a
// distance, and where its gradient is short (near the medial axis between
// two sheets, where the corrections that need this sit) Newton's step
// overshoots (miranda: zeros 1.2 cells away found 2-3 cells off).
bool zero_along_gradient(const TrilinearGrid& distance, const Box& box, double cell, double range, const Vec3& p,
                         bool unit_steps, Vec3& x) {
  x = p;
  for (int step = 0; step < 20; ++step) {
    const TrilinearSample s = distance.sample(x);
    const double length = norm(s.gradient);
    if (!(length > 0) || !std::isfinite(s.value)) return false;
    const Vec3 move = (s.value / (length * (unit_steps ? std::max(length, 1.0) : length))) * s.gradient;
    x = box.clamp(x - move);
    if (!(norm(x - p) <= range)) return false;
    if (norm(move) <= 1e-4 * cell) return true;
  }
  return false;
}

// Zeros of `distance` near p from both step rules (see
// zero_along_gradient), nearer first; returns how many (0 to 2).
int nearest_zeros(const TrilinearGrid& distance, const Box& box, double cell, double range, const Vec3& p,
                  Vec3 zeros[2]) {
  int count = 0;
  Vec3 x;
  for (const bool unit_steps : {true, false})
    if (zero_along_gradient(distance, box, cell, range, p, unit_steps, x)) zeros[count++] = x;
  if (count == 2 && squared_norm(zeros[1] - p) < squared_norm(zeros[0] - p)) std::swap(zeros[0], zeros[1]);
  return count;
}

// The axis of the box face within one cell of p (the nearest), or -1.
int near_box_axis(const Box& box, double cell, const Vec3& p) {
  int axis = -1;
  double nearest = cell;
  for (int a = 0; a < 3; ++a)
    for (const double plane : {box.low[a], box.high[a]})
      if (std::abs(p[a] - plane) < nearest) {
        nearest = std::abs(p[a] - plane);
        axis = a;
      }
  return axis;
}

// A root of f - iso along a direction from p.
struct Root {
  double distance;
  Vec3 at;
};

// The first root of f - iso from p along each of `count` unit directions
// (within the box and `range`), each probed every quarter cell and its
// bracket refined; stored in `roots` nearest first, returns their number.
int roots_along(const TrilinearGrid& field, const Box& box, double cell, double iso, double range, const Vec3& p,
                const Vec3* directions, int count, Root* roots) {
  const double h0 = field.value(p) - iso;
  if (!std::isfinite(h0)) return 0;
  const double step = 0.25 * cell, tolerance = 1e-4 * cell;
  int found = 0;
  for (int k = 0; k < count; ++k) {
    const Vec3& d = directions[k];
    double t_low, t_high, t;
    box.clip(p, d, t_low, t_high);
    const auto h = [&](double s) { return field.value(p + s * d) - iso; };
    if (detail::find_root_along_line(h, h0, step, std::min(range, t_high), step, tolerance, t))
      roots[found++] = {t, p + t * d};
  }
  std::sort(roots, roots + found, [](const Root& a, const Root& b) { return a.distance < b.distance; });
  return found;
}

constexpr int kPlaneDirections = 16;

// The kPlaneDirections unit directions of the plane normal to `axis`.
void plane_directions(int axis, Vec3 directions[kPlaneDirections]) {
  constexpr double kPi = 3.14159265358979323846;
  for (int k = 0; k < kPlaneDirections; ++k) {
    const double angle = 2.0 * kPi * k / kPlaneDirections;
    directions[k] = Vec3{};
    directions[k][(axis + 1) % 3] = std::cos(angle);
    directions[k][(axis + 2) % 3] = std::sin(angle);
  }
}

// The nearest root of f - iso within the plane through p normal to `axis`
// (a box face's; the target stays on the face), within `range`
// (roots_along the plane's directions). For points pressed onto a box face
// where the field's gradient is normal to it, so that the search along its
// part within the face has nowhere to go (engine CT: the cut through the
// material on the z = 0 face, whose gradient points into the box).
bool nearest_root_in_plane(const TrilinearGrid& field, const Box& box, double cell, double iso, double range,
                           const Vec3& p, int axis, Vec3& target) {
  Vec3 directions[kPlaneDirections];
  plane_directions(axis, directions);
  Root roots[kPlaneDirections];
  if (roots_along(field, box, cell, iso, range, p, directions, kPlaneDirections, roots) == 0) return false;
  target = roots[0].at;
  return true;
}

// The 26 unit directions to a cube's neighbours.
struct CubeDirections {
  Vec3 directions[26];
  CubeDirections() {
    int k = 0;
    for (int z = -1; z <= 1; ++z)
      for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x)
          if (x || y || z) {
            const Vec3 d{double(x), double(y), double(z)};
            directions[k++] = (1.0 / norm(d)) * d;
          }
  }
};

// The correction of one movable vertex v (see correct_with), in place and
// counted in `partial`; false if it found no root and left v where it was.
bool correct_vertex(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell, double iso,
                    double range, const TrilinearGrid* nearest, std::size_t v, std::vector<Vec3>& positions,
                    CorrectionPartial& partial) {
  ++partial.movable;
  const Vec3 p = positions[v];
  Vec3 target, starts[2];
  if (!project_onto_isosurface(mesh, box, field, cell, iso, range, v, p, target)) {
    const bool free = mesh.role[v] == WrapRole::Free && mesh.box_face[v] < 0;
    // The distance field's zeros a little farther (see
    // ShrinkWrapOptions::correction_from_nearest_point).
    const int zeros = free && nearest ? nearest_zeros(*nearest, box, cell, 1.5 * range, p, starts) : 0;
    int from = 0;
    while (from < zeros && !project_onto_isosurface(mesh, box, field, cell, iso, range, v, starts[from], target)) ++from;
    if (from < zeros) {
      ++partial.nearest;
    } else {
      // Within the plane of a box face: the vertex's own, or for a free one
      // the nearest face's within a cell.
      const int axis = free ? near_box_axis(box, cell, p) : mesh.box_face[v] >= 0 ? mesh.box_face[v] >> 1 : -1;
      if (axis < 0 || !((free && project_onto_isosurface(mesh, box, field, cell, iso, range, v, p, target, axis)) ||
                        nearest_root_in_plane(field, box, cell, iso, range, p, axis, target))) {
        partial.failed.push_back(static_cast<std::uint32_t>(v));
        return false;
      }
      ++partial.along_box;
    }
  }
  positions[v] = target;
  ++partial.corrected;
  const double moved = norm(target - p) / cell;
  partial.move_sum += moved;
  partial.move_max = std::max(partial.move_max, moved);
  return true;
}

// The faces of `surface` near `points` (a first corner within `reach` plus
// two cells of one: the extracted triangles are under a cell across, so
// this holds every face within `reach`), each with its own corners. Keeps
// the bins of the stranded vertices' search small: on miranda the 20 of them
// take 0.1 M of its 4.2 M triangles.
PolygonMesh faces_near(const PolygonMesh& surface, const Box& box, double cell, double reach,
                       const std::vector<Vec3>& points) {
  // Marked blocks of 8 x 8 x 8 cells.
  const double block = 8 * cell;
  std::int64_t dims[3];
  for (int a = 0; a < 3; ++a)
    dims[a] = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil((box.high[a] - box.low[a]) / block)) + 1);
  const auto block_along = [&](int a, double x) {
    return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor((x - box.low[a]) / block)), 0, dims[a] - 1);
  };
  const auto block_of = [&](const Vec3& p) {
    return static_cast<std::size_t>(block_along(0, p.x) +
                                    dims[0] * (block_along(1, p.y) + dims[1] * block_along(2, p.z)));
  };
  std::vector<std::uint8_t> marked(static_cast<std::size_t>(dims[0] * dims[1] * dims[2]), 0);
  const double margin = reach + 2 * cell;
  for (const Vec3& p : points)
    for (std::int64_t z = block_along(2, p.z - margin); z <= block_along(2, p.z + margin); ++z)
      for (std::int64_t y = block_along(1, p.y - margin); y <= block_along(1, p.y + margin); ++y)
        for (std::int64_t x = block_along(0, p.x - margin); x <= block_along(0, p.x + margin); ++x)
          marked[static_cast<std::size_t>(x + dims[0] * (y + dims[1] * z))] = 1;
  const std::vector<std::vector<std::uint32_t>> chosen = for_blocks<std::vector<std::uint32_t>>(
      surface.face_count(), [&](std::size_t first, std::size_t last, std::vector<std::uint32_t>& faces) {
        for (std::size_t f = first; f < last; ++f)
          if (marked[block_of(surface.positions[surface.face_begin(f)[0]])])
            faces.push_back(static_cast<std::uint32_t>(f));
      });
  PolygonMesh near;
  std::vector<std::uint32_t> corners;
  for (const std::vector<std::uint32_t>& faces : chosen)
    for (const std::uint32_t f : faces) {
      corners.clear();
      for (std::size_t k = 0; k < surface.face_size(f); ++k) {
        corners.push_back(static_cast<std::uint32_t>(near.positions.size()));
        near.positions.push_back(surface.positions[surface.face_begin(f)[k]]);
      }
      near.add_face(corners.data(), corners.size());
    }
  return near;
}

// correct_to_isosurface(); with `nearest` (the signed-distance field), a free
// vertex whose gradient line has no root within range starts again from a
// nearby point of the distance field's zero set (see
// ShrinkWrapOptions::correction_from_nearest_point). A free vertex still without
// a root searches within the plane parallel to the nearest box face within a
// cell (see CorrectionStatistics::along_box_face). With `surface` and
// `distance` (the extracted surface and its signed-distance field), a vertex
// left a cell or more from it starts again from its nearest point
// (CorrectionStatistics::from_extracted_surface).
CorrectionStatistics correct_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                  double iso, double max_move_cells, std::vector<Vec3>& positions,
                                  const TrilinearGrid* nearest = nullptr, double wide_search_sign = 0,
                                  const PolygonMesh* surface = nullptr, const TrilinearGrid* distance = nullptr) {
  assert(positions.size() >= mesh.vertex_count);
  const double range = max_move_cells * cell;
  const std::vector<CorrectionPartial> partials = for_blocks<CorrectionPartial>(
      mesh.vertex_count, [&](std::size_t begin, std::size_t end, CorrectionPartial& partial) {
        for (std::size_t v = begin; v < end; ++v) {
          if (v + kPrefetchDistance < end) field.prefetch_at(field.grid_point(positions[v + kPrefetchDistance]));
          if (mesh.role[v] != WrapRole::Fixed)
            correct_vertex(mesh, field, box, cell, iso, range, nearest, v, positions, partial);
        }
      });
  CorrectionStatistics stats;
  double sum = 0;
  std::vector<std::uint32_t> failed;
  for (const CorrectionPartial& partial : partials) {
    stats.movable += partial.movable;
    stats.corrected += partial.corrected;
    stats.from_nearest_point += partial.nearest;
    stats.along_box_face += partial.along_box;
    sum += partial.move_sum;
    stats.max_move_cells = std::max(stats.max_move_cells, partial.move_max);
    failed.insert(failed.end(), partial.failed.begin(), partial.failed.end());
  }
  std::vector<Vec3> target;
  std::vector<std::uint8_t> found;
  // Moves each failed vertex with found[i] to target[i], counted also in
  // `counter`; the rest stay failed. False if none moved.
  const auto move_found = [&](std::size_t& counter) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < failed.size(); ++i) {
      if (!found[i]) {
        failed[kept++] = failed[i];
        continue;
      }
      const double moved = norm(target[i] - positions[failed[i]]) / cell;  // from where the fit left it
      positions[failed[i]] = target[i];
      sum += moved;
      stats.max_move_cells = std::max(stats.max_move_cells, moved);
      ++stats.corrected;
      ++counter;
    }
    const bool any = kept < failed.size();
    failed.resize(kept);
    return any;
  };
  // A vertex without a root tries again from its neighbours' centroid, most
  // of whose corners found the isosurface; Jacobi rounds while they help.
  for (int round = 0; round < kCorrectionRetryRounds && !failed.empty(); ++round) {
    target.resize(failed.size());
    found.assign(failed.size(), 0);
    for_vertices(failed.size(), [&](std::size_t i) {
      const std::uint32_t v = failed[i];
      Vec3 centroid;
      found[i] = relaxation_centroid(mesh, v, positions, centroid) &&
                 project_onto_isosurface(mesh, box, field, cell, iso, range, v, place(mesh, box, v, centroid), target[i]);
    });
    if (!move_found(stats.from_neighbours)) break;
  }
  // Last, with wide_search_sign (the expected sign of face normals against
  // the gradient, see face_tangled), the roots within kWideSearchRanges
  // ranges along the 26 directions to a cube's neighbours (within its face's
  // plane for a vertex held on a box face): the nearest at which no more of
  // the vertex's faces are tangled than before. Each vertex is judged with
  // the others where they were (Jacobi). A last resort for the few a fit
  // leaves off the surface (up to 624 samples each, about 15 microseconds):
  // for at most 1% of the vertices (at least 10,000), the first by index.
  if (wide_search_sign != 0 && !failed.empty()) {
    const CubeDirections cube;
    const std::size_t searched = std::min(failed.size(), std::max<std::size_t>(10000, mesh.vertex_count / 100));
    target.resize(searched);
    found.assign(failed.size(), 0);
    for_vertices(searched, [&](std::size_t i) {
      const std::uint32_t v = failed[i];
      Vec3 in_plane[kPlaneDirections];
      const Vec3* directions = cube.directions;
      int count = 26;
      if (mesh.box_face[v] >= 0) {
        plane_directions(mesh.box_face[v] >> 1, in_plane);
        directions = in_plane;
        count = kPlaneDirections;
      }
      Root roots[26];
      const int found_roots =
          roots_along(field, box, cell, iso, kWideSearchRanges * range, positions[v], directions, count, roots);
      const int before = tangled_faces_around(mesh, field, wide_search_sign, positions, v, positions[v]);
      for (int r = 0; r < found_roots && !found[i]; ++r) {
        const Vec3& at = roots[r].at;
        if (is_finite(at) && tangled_faces_around(mesh, field, wide_search_sign, positions, v, at) <= before) {
          target[i] = at;
          found[i] = 1;
        }
      }
    });
    move_found(stats.from_wide_search);
  }
  // Last, the stranded vertices: those a cell or more from the extracted
  // surface by its distance field, which no search along the field finds
  // (beyond the band, or where the field is flat), start from the nearest
  // point of that surface within kStrandedReachCells.
  if (surface && distance && surface->face_count() > 0 && !failed.empty()) {
    std::vector<std::uint8_t> far(failed.size(), 0);
    std::vector<Vec3> stranded;
    for (std::size_t i = 0; i < failed.size(); ++i)
      if (std::abs(distance->value(positions[failed[i]])) >= cell) {
        far[i] = 1;
        stranded.push_back(positions[failed[i]]);
      }
    const double reach = kStrandedReachCells * cell;
    const PolygonMesh near = stranded.empty() ? PolygonMesh{} : faces_near(*surface, box, cell, reach, stranded);
    if (near.face_count() > 0) {  // none: every stranded vertex is beyond reach
      const BinnedSurfaceDistance surface_distance(near);
      found.assign(failed.size(), 0);
      target.resize(failed.size());
      for_vertices(failed.size(), [&](std::size_t i) {
        if (!far[i]) return;
        const std::uint32_t v = failed[i];
        const Vec3 q = surface_distance.closest_point(positions[v]);
        found[i] = norm(q - positions[v]) <= reach &&
                   project_onto_isosurface(mesh, box, field, cell, iso, range, v, place(mesh, box, v, q), target[i]);
      });
      move_found(stats.from_extracted_surface);
    }
  }
  stats.failed = failed.size();
  stats.mean_move_cells = stats.corrected ? sum / double(stats.corrected) : 0.0;
  return stats;
}

// Puts the points the coverage pull moved on level L onto the isosurface of
// `field` (as correct_with, `nearest` likewise); a point without a root
// there, or around which more faces are tangled (face_tangled) than at its
// old place, goes back where it was. Returns how many went back.
std::size_t settle_pulled_points(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                 double iso, bool flip, double max_move_cells, const TrilinearGrid* nearest,
                                 const std::vector<PulledPoint>& pulled, std::vector<Vec3>& positions) {
  const double expected_sign = flip ? 1.0 : -1.0;
  std::vector<std::uint8_t> back(pulled.size(), 0);
  for_blocks<char>(pulled.size(), [&](std::size_t first, std::size_t last, char&) {
    CorrectionPartial partial;
    for (std::size_t i = first; i < last; ++i)
      back[i] = !correct_vertex(mesh, field, box, cell, iso, max_move_cells * cell, nearest, pulled[i].vertex,
                                positions, partial);
  });
  // Judged with every other pulled point in its new place, then applied.
  for_vertices(pulled.size(), [&](std::size_t i) {
    if (back[i]) return;
    const std::uint32_t v = pulled[i].vertex;
    const int now = tangled_faces_around(mesh, field, expected_sign, positions, v, positions[v]);
    back[i] = now > 0 && now > tangled_faces_around(mesh, field, expected_sign, positions, v, pulled[i].from);
  });
  std::size_t count = 0;
  for (std::size_t i = 0; i < pulled.size(); ++i)
    if (back[i]) {
      positions[pulled[i].vertex] = pulled[i].from;
      ++count;
    }
  return count;
}

// Sets a flag that other threads may set at the same time (always to 1).
inline void raise_flag(std::uint8_t& flag) { __atomic_store_n(&flag, std::uint8_t{1}, __ATOMIC_RELAXED); }

// The indices of the set flags, ascending (the same for any thread count).
void collect_flagged(const HugePageVector<std::uint8_t>& flags, HugePageVector<std::uint32_t>& list) {
  const std::size_t n = flags.size();
  std::vector<std::size_t> starts = for_blocks<std::size_t>(n, [&](std::size_t first, std::size_t last, std::size_t& count) {
    for (std::size_t i = first; i < last; ++i) count += flags[i] != 0;
  });
  std::size_t total = 0;
  for (std::size_t& start : starts) total += std::exchange(start, total);
  list.resize(total);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, starts.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) {
      std::size_t out = starts[b];
      for (std::size_t i = b * kBlock, last = std::min(n, (b + 1) * kBlock); i < last; ++i)
        if (flags[i]) list[out++] = static_cast<std::uint32_t>(i);
    }
  });
}

void clear_flags(HugePageVector<std::uint8_t>& flags, std::size_t n) {
  if (flags.capacity() < n) reserve_fresh_on_huge_pages(flags, n);
  flags.resize(n);
  for_blocks<char>(n, [&](std::size_t first, std::size_t last, char&) {
    std::fill(flags.begin() + static_cast<std::ptrdiff_t>(first), flags.begin() + static_cast<std::ptrdiff_t>(last), 0);
  });
}

// untangle() with a buffer for the moved vertices' positions supplied by the
// caller (the shrink-wrap lends its second position buffer). Each round works
// on lists of the corners of tangled faces (a sixth of the level on
// miranda) rather than on whole-level passes: the new positions are computed into
// `moved` and swapped into place, and only the faces around them are
// checked again; a vertex around which that check finds more tangled faces
// than before goes back, and a dropped round swaps the old positions back.
// face_state per face: bit 0 a moved corner, bit 1 tangled before the round,
// bit 2 a corner that went back.
UntangleStatistics untangle_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                 double iso, bool flip, int rounds, double max_move_cells,
                                 std::vector<Vec3>& positions, std::vector<Vec3>& moved) {
  assert(positions.size() >= mesh.vertex_count && &positions != &moved);
  const double range = max_move_cells * cell;
  const double expected_sign = flip ? 1.0 : -1.0;
  UntangleStatistics stats;
  HugePageVector<std::uint8_t> tangled;
  stats.tangled_before = find_tangled_faces(mesh, field, flip, positions, tangled);
  stats.tangled_after = stats.tangled_before;
  HugePageVector<std::uint8_t> corner, face_state;
  HugePageVector<std::uint32_t> list;
  const std::size_t faces = mesh.face_count();
  for (int round = 0; round < rounds && stats.tangled_after > 0; ++round) {
    // The corners of tangled faces.
    clear_flags(corner, mesh.vertex_count);
    for_vertices(faces, [&](std::size_t f) {
      if (!tangled[f]) return;
      for (std::uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k)
        raise_flag(corner[mesh.face_vertices[k]]);
    });
    collect_flagged(corner, list);
    const std::size_t count = list.size();
    moved.resize(std::max(moved.size(), count));
    // New positions from the old ones (Jacobi).
    for_vertices(count, [&](std::size_t i) {
      // The smoothed point's samples are near the vertex's own.
      if (i + kPrefetchDistance < count) field.prefetch_at(field.grid_point(positions[list[i + kPrefetchDistance]]));
      const std::size_t v = list[i];
      moved[i] = positions[v];
      Vec3 centroid;
      if (mesh.role[v] == WrapRole::Fixed || !relaxation_centroid(mesh, v, positions, centroid)) return;
      const Vec3 smoothed = place(mesh, box, v, centroid);
      Vec3 target;
      if (project_onto_isosurface(mesh, box, field, cell, iso, range, v, smoothed, target)) moved[i] = target;
    });
    // Now `moved` keeps the old positions; mark the faces around the
    // vertices that moved (fixed ones, and those without a root, did not).
    clear_flags(face_state, faces);
    for_vertices(count, [&](std::size_t i) {
      const std::size_t v = list[i];
      std::swap(positions[v], moved[i]);
      if (positions[v] == moved[i]) return;
      for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
        raise_flag(face_state[mesh.vertex_faces[k]]);
    });
    // Only faces with a moved corner can change. `tangled` takes their new
    // flags at once: a dropped round ends the repair, so it is not read again.
    for_blocks<char>(faces, [&](std::size_t first, std::size_t last, char&) {
      for (std::size_t f = first; f < last; ++f) {
        if (f + kPrefetchDistance < last && face_state[f + kPrefetchDistance])
          prefetch_face(mesh, field, positions, f + kPrefetchDistance);
        if (!face_state[f]) continue;
        face_state[f] = static_cast<std::uint8_t>(1 | (tangled[f] << 1));
        tangled[f] = face_tangled(mesh, field, expected_sign, positions, f);
      }
    });
    // A vertex with more tangled faces around it than before goes back (its
    // old position is in `moved`, which keeps it for a dropped round).
    for_vertices(count, [&](std::size_t i) {
      const std::size_t v = list[i];
      if (positions[v] == moved[i]) return;
      int before = 0, after = 0;
      for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
        const std::uint32_t f = mesh.vertex_faces[k];
        before += __atomic_load_n(&face_state[f], __ATOMIC_RELAXED) >> 1 & 1;
        after += tangled[f];
      }
      if (after <= before) return;
      positions[v] = moved[i];
      for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
        __atomic_fetch_or(&face_state[mesh.vertex_faces[k]], std::uint8_t{4}, __ATOMIC_RELAXED);
    });
    struct Change {
      std::size_t was = 0, now = 0;  // tangled faces among the checked ones, before and after
    };
    const std::vector<Change> changes = for_blocks<Change>(faces, [&](std::size_t first, std::size_t last, Change& change) {
      for (std::size_t f = first; f < last; ++f) {
        const std::uint8_t state = face_state[f];
        if (!state) continue;
        if (state & 4) tangled[f] = face_tangled(mesh, field, expected_sign, positions, f);
        change.was += state >> 1 & 1;
        change.now += tangled[f];
      }
    });
    Change total;
    for (const Change& change : changes) {
      total.was += change.was;
      total.now += change.now;
    }
    const std::size_t tangled_now = stats.tangled_after - total.was + total.now;
    if (tangled_now >= stats.tangled_after) {  // a round that does not help is dropped
      for_vertices(count, [&](std::size_t i) { positions[list[i]] = moved[i]; });
      break;
    }
    stats.tangled_after = tangled_now;
    ++stats.rounds;
  }
  return stats;
}

// The unfold's cost of the faces around v with v at `at` (the others where
// `positions` has them): kTangledFaceCost per tangled face (face_tangled_at)
// plus, for each, how far its normal turns past the field gradient (minus
// the cosine of their angle, 0 to 1). The second part lets a vertex make a
// fold shallower where no single move removes one of its faces, which a
// later move then can (mixing at 96^3, with an early sequential form of
// the unfold: 180 faces left tangled without it, 59 with it).
constexpr double kTangledFaceCost = 10.0;

// Added to `cost`; returns as soon as the sum reaches `enough` (a trial place
// that cannot win).
double unfold_cost(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                   const std::vector<Vec3>& positions, std::uint32_t v, const Vec3& at, double cost = 0,
                   double enough = std::numeric_limits<double>::infinity()) {
  const auto position = [&](std::uint32_t u) -> const Vec3& { return u == v ? at : positions[u]; };
  for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
    Vec3 newell, gradient;
    face_normal_and_gradient(mesh, field, mesh.vertex_faces[k], position, newell, gradient);
    const double agreement = expected_sign * dot(newell, gradient);
    if (agreement > 0) continue;  // as face_tangled_at()
    const double lengths = norm(newell) * norm(gradient);
    cost += kTangledFaceCost + (lengths > 0 ? -agreement / lengths : 1.0);
    if (cost >= enough) return cost;
  }
  return cost;
}

// The unfold's move of one vertex (see unfold()): the cheapest of its
// trial places, or false to stay.
bool unfold_vertex(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell, double iso,
                   double expected_sign, double range, const std::vector<Vec3>& positions, std::uint32_t v,
                   Vec3& moved_to) {
  const Vec3 p = positions[v];
  const double stay = unfold_cost(mesh, field, expected_sign, positions, v, p);
  if (stay < kTangledFaceCost) return false;  // no tangled face around v
  double best = stay;
  const auto consider = [&](const Vec3& trial) {
    Vec3 target;
    if (!project_onto_isosurface(mesh, box, field, cell, iso, range, v, place(mesh, box, v, trial), target)) return;
    // Moves are charged (squared, in cells) so that of two places nearly as
    // good the nearer wins: each move is detail the wavelets must code.
    const double move_cost = squared_norm(target - p) / (cell * cell);
    if (move_cost >= best - 1e-9) return;
    const double cost = unfold_cost(mesh, field, expected_sign, positions, v, target, move_cost, best - 1e-9);
    if (cost < best - 1e-9) {
      best = cost;
      moved_to = target;
    }
  };
  // The places: the neighbours' centroid and p mirrored through it, and
  // toward each neighbour half-way and nine tenths of the way (the mirrored
  // and nine-tenths places took mixing at 96^3 from 96 to 75 tangled faces,
  // the aneurism from 926 to 688, for 0.04 s more there).
  Vec3 centroid;
  if (relaxation_centroid(mesh, v, positions, centroid)) {
    consider(centroid);
    consider(2.0 * centroid - p);
  }
  const std::uint32_t b0 = mesh.boundary_neighbours[2 * v], b1 = mesh.boundary_neighbours[2 * v + 1];
  if (mesh.role[v] == WrapRole::Boundary && b0 != kNone && b1 != kNone) {  // along its boundary curve only
    consider(0.5 * (p + positions[b0]));
    consider(0.5 * (p + positions[b1]));
  } else {
    for (std::uint32_t k = mesh.neighbour_offsets[v]; k < mesh.neighbour_offsets[v + 1]; ++k) {
      const Vec3& q = positions[mesh.neighbours[k]];
      consider(0.5 * (p + q));
      consider(q + 0.1 * (p - q));
    }
    for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
      const std::uint32_t f = mesh.vertex_faces[k];
      Vec3 face_centroid;
      for (std::uint32_t j = mesh.face_offsets[f]; j < mesh.face_offsets[f + 1]; ++j)
        face_centroid += positions[mesh.face_vertices[j]];
      consider((1.0 / double(mesh.face_offsets[f + 1] - mesh.face_offsets[f])) * face_centroid);
    }
  }
  return best < stay;
}

UnfoldStatistics unfold_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                             double iso, bool flip, int rounds, double max_move_cells, std::vector<Vec3>& positions) {
  assert(positions.size() >= mesh.vertex_count);
  const double range = max_move_cells * cell;
  const double expected_sign = flip ? 1.0 : -1.0;
  UnfoldStatistics stats;
  HugePageVector<std::uint8_t> tangled;
  stats.tangled_before = stats.tangled_after = find_tangled_faces(mesh, field, flip, positions, tangled);
  if (stats.tangled_before == 0 || rounds == 0) return stats;
  // After the first scan every round works on lists: the tangled faces, their
  // corners, and the faces around the corners that moved (engine CT, 1.1 M
  // faces: ten rounds of whole-level scans took 0.57 s).
  HugePageVector<std::uint32_t> faces;  // the tangled ones, ascending
  collect_flagged(tangled, faces);
  constexpr std::uint16_t kNoColor = 0xffff;
  std::vector<std::uint16_t> color(mesh.vertex_count, kNoColor);
  std::vector<std::uint32_t> corners, by_color, color_first, changed, merged;
  std::vector<std::uint8_t> used, moved;
  // A corner that found no better place is tried again only once a vertex
  // of its faces has moved: `stale` marks the others (most of them after
  // the first rounds).
  std::vector<std::uint8_t> stale(mesh.vertex_count, 0);
  for (int round = 0; round < rounds && !faces.empty(); ++round) {
    // The movable corners of the tangled faces that may move, ascending.
    corners.clear();
    for (const std::uint32_t f : faces)
      for (std::uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k)
        if (mesh.role[mesh.face_vertices[k]] != WrapRole::Fixed && !stale[mesh.face_vertices[k]])
          corners.push_back(mesh.face_vertices[k]);
    std::sort(corners.begin(), corners.end());
    corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
    // Greedy colours, in that order: two corners that share a face differ,
    // so the corners of one colour move at once without reading one
    // another's places, and the result is the same for any thread count.
    std::uint16_t colors = 0;
    for (const std::uint32_t v : corners) {
      used.assign(std::size_t{colors} + 1, 0);
      for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
        const std::uint32_t f = mesh.vertex_faces[k];
        for (std::uint32_t j = mesh.face_offsets[f]; j < mesh.face_offsets[f + 1]; ++j)
          if (color[mesh.face_vertices[j]] != kNoColor) used[color[mesh.face_vertices[j]]] = 1;
      }
      std::uint16_t c = 0;
      while (used[c]) ++c;
      color[v] = c;
      colors = std::max<std::uint16_t>(colors, static_cast<std::uint16_t>(c + 1));
    }
    color_first.assign(std::size_t{colors} + 1, 0);
    for (const std::uint32_t v : corners) ++color_first[color[v] + 1];
    for (std::uint16_t c = 0; c < colors; ++c) color_first[c + 1] += color_first[c];
    by_color.resize(corners.size());
    {
      std::vector<std::uint32_t> next(color_first.begin(), color_first.end() - 1);
      for (const std::uint32_t v : corners) by_color[next[color[v]]++] = v;
    }
    for (const std::uint32_t v : corners) color[v] = kNoColor;
    moved.assign(by_color.size(), 0);
    for (std::uint16_t c = 0; c < colors; ++c)
      for_vertices(color_first[c + 1] - color_first[c], [&](std::size_t i) {
        const std::size_t at = color_first[c] + i;
        Vec3 target;
        if (!unfold_vertex(mesh, field, box, cell, iso, expected_sign, range, positions, by_color[at], target)) return;
        positions[by_color[at]] = target;
        moved[at] = 1;
      });
    // Only the faces around the moved corners can change.
    changed.clear();
    for (std::size_t i = 0; i < by_color.size(); ++i) {
      if (!moved[i]) {
        stale[by_color[i]] = 1;
        continue;
      }
      ++stats.moved;
      const std::uint32_t v = by_color[i];
      for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
        changed.push_back(mesh.vertex_faces[k]);
    }
    if (changed.empty()) break;
    ++stats.rounds;
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    for_vertices(changed.size(), [&](std::size_t i) {
      tangled[changed[i]] = face_tangled(mesh, field, expected_sign, positions, changed[i]);
    });
    for (const std::uint32_t f : changed)
      for (std::uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k) stale[mesh.face_vertices[k]] = 0;
    merged.clear();
    std::set_union(faces.begin(), faces.end(), changed.begin(), changed.end(), std::back_inserter(merged));
    faces.clear();
    for (const std::uint32_t f : merged)
      if (tangled[f]) faces.push_back(f);
    stats.tangled_after = faces.size();
  }
  return stats;
}

}  // namespace

CorrectionStatistics correct_to_isosurface(const WrapLevelMesh& mesh, const Volume& field, double iso,
                                           double max_move_cells, std::vector<Vec3>& positions, bool wide_search,
                                           bool flip, const PolygonMesh* surface, const Volume* surface_distance) {
  assert(!surface_distance || surface_distance->dims == field.dims);
  std::optional<TrilinearGrid> distance;
  if (surface_distance) distance.emplace(*surface_distance);
  const detail::FittedField fitted(field, iso);
  return correct_with(mesh, fitted.grid(), Box(field), field.cell_size(), iso, max_move_cells, positions, nullptr,
                      wide_search ? (flip ? 1.0 : -1.0) : 0.0, surface, distance ? &*distance : nullptr);
}

UntangleStatistics untangle(const WrapLevelMesh& mesh, const Volume& field, double iso, bool flip, int rounds,
                            double max_move_cells, std::vector<Vec3>& positions) {
  std::vector<Vec3> moved;
  const detail::FittedField fitted(field, iso);
  return untangle_with(mesh, fitted.grid(), Box(field), field.cell_size(), iso, flip, rounds, max_move_cells,
                       positions, moved);
}

UnfoldStatistics unfold(const WrapLevelMesh& mesh, const Volume& field, double iso, bool flip, int rounds,
                        double max_move_cells, std::vector<Vec3>& positions) {
  const detail::FittedField fitted(field, iso);
  return unfold_with(mesh, fitted.grid(), Box(field), field.cell_size(), iso, flip, rounds, max_move_cells,
                     positions);
}

namespace {

// Closed components of the base mesh with few vertices (see
// ShrinkWrapOptions::small_component_vertices): droplets a few cells across
// or less, on which a tetrahedron's valence-3 corners give vertex normals
// that point anywhere but at the surface.
struct SmallComponents {
  std::vector<std::vector<std::uint32_t>> base_faces;  // per component
  std::vector<double> inside_sign;                     // sign of field - iso inside
  std::vector<double> base_radius;                     // of the base vertices around their centroid
  std::vector<std::vector<std::uint32_t>> vertices;    // on the current level, ascending

  bool empty() const { return base_faces.empty(); }

  // Vertices of level `level`: the corners of the faces descending from the
  // components' base faces.
  void set_level(const SubdivisionHierarchy& hierarchy, int level, const WrapLevelMesh& mesh) {
    vertices.assign(base_faces.size(), {});
    for (std::size_t c = 0; c < base_faces.size(); ++c) {
      std::vector<std::uint32_t>& list = vertices[c];
      for (const std::uint32_t f : base_faces[c]) {
        const auto [first, last] = hierarchy.descendant_faces(f, level);
        for (std::size_t g = first; g < last; ++g)
          for (std::uint32_t k = mesh.face_offsets[g]; k < mesh.face_offsets[g + 1]; ++k)
            list.push_back(mesh.face_vertices[k]);
      }
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
  }
};

// The closed components of the base (no box-held, boundary or sharp vertex)
// with at most max_vertices vertices, all within max_radius of their
// centroid, and a nonzero signed volume.
SmallComponents find_small_components(const SubdivisionHierarchy& hierarchy, const WrapLevelMesh& mesh,
                                      const std::vector<Vec3>& positions, std::size_t max_vertices,
                                      double max_radius, bool flip) {
  const PolygonMesh& base = hierarchy.base();
  std::size_t n = 0;
  const std::vector<std::uint32_t> face_component = face_components(base, &n);
  std::vector<std::uint32_t> component(base.vertex_count(), kNone);  // per vertex; kNone if in no face
  for (std::size_t f = 0; f < base.face_count(); ++f)
    for (std::uint32_t k = 0; k < base.face_size(f); ++k) component[base.face_begin(f)[k]] = face_component[f];
  std::vector<std::uint32_t> size(n, 0);
  std::vector<std::uint8_t> open(n, 0);
  std::vector<Vec3> centroid(n);
  for (std::uint32_t v = 0; v < base.vertex_count(); ++v) {
    const std::uint32_t r = component[v];
    if (r == kNone) continue;
    ++size[r];
    centroid[r] += positions[v];
    if (mesh.role[v] != WrapRole::Free || mesh.box_face[v] >= 0 || mesh.boundary_neighbours[2 * std::size_t{v}] != kNone)
      open[r] = 1;
  }
  std::vector<double> radius(n, 0.0);
  for (std::uint32_t v = 0; v < base.vertex_count(); ++v) {
    const std::uint32_t r = component[v];
    if (r != kNone) radius[r] = std::max(radius[r], norm(positions[v] - centroid[r] * (1.0 / double(size[r]))));
  }
  std::vector<double> volume(n, 0.0);
  std::vector<std::int32_t> index(n, -1);
  SmallComponents small;
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t r = face_component[f];
    if (open[r] || size[r] > max_vertices || !(radius[r] <= max_radius)) continue;
    if (index[r] < 0) {
      index[r] = static_cast<std::int32_t>(small.base_faces.size());
      small.base_faces.emplace_back();
    }
    small.base_faces[static_cast<std::size_t>(index[r])].push_back(static_cast<std::uint32_t>(f));
    const std::uint32_t* face = base.face_begin(f);
    const std::uint32_t count = base.face_size(f);
    const Vec3 c = centroid[r] * (1.0 / double(size[r]));
    Vec3 newell, middle;
    for (std::uint32_t k = 0; k < count; ++k) {
      newell += cross(positions[face[k]] - c, positions[face[k + 1 == count ? 0 : k + 1]] - c);
      middle += positions[face[k]] - c;
    }
    volume[r] += dot(newell, middle) / (6.0 * double(count));
  }
  small.inside_sign.assign(small.base_faces.size(), 0.0);
  small.base_radius.assign(small.base_faces.size(), 0.0);
  for (std::uint32_t r = 0; r < n; ++r) {
    if (index[r] < 0) continue;
    small.base_radius[static_cast<std::size_t>(index[r])] = radius[r];
    if (volume[r] != 0)  // outward faces (positive volume) have the lower values outside
      small.inside_sign[static_cast<std::size_t>(index[r])] = (volume[r] > 0) != flip ? 1.0 : -1.0;
  }
  return small;
}

// Attraction (and correction) of the small components' free vertices along
// the ray from their component's centroid (of `source`) through the vertex
// (in `source`) to the first crossing of the trilinear field's isosurface,
// written to `target`. A component whose centroid is not inside, and a vertex
// without a crossing within max(3 times the base component's radius, 0.02
// cells), are left as they are in `target`. The base radius, not the current
// one: with the current one, a component that is no droplet (the inside
// reaching far) let a vertex go three times as far as the farthest one, on
// every round and level (miranda: vertices flung up to 167 cells, the base
// row of Table 1 from 79% to 98% of a cell).
void fit_small_components(const WrapLevelMesh& mesh, const SmallComponents& small, const TrilinearGrid& field,
                          const Box& box, double cell, double iso, const std::vector<Vec3>& source,
                          std::vector<Vec3>& target) {
  // Samples along each ray, then bisection down to 1e-5 cells (the
  // correction's own precision is about 1e-4): on miranda the droplets hold
  // 1.3% of the fine vertices, and every sample is a trilinear lookup.
  constexpr int kSamples = 32;
  const double precision = 1e-5 * cell;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, small.vertices.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c < r.end(); ++c) {
      const std::vector<std::uint32_t>& list = small.vertices[c];
      if (list.empty() || small.inside_sign[c] == 0) continue;
      Vec3 centre;
      for (const std::uint32_t v : list) centre += source[v];
      centre *= 1.0 / double(list.size());
      const double sign = small.inside_sign[c];
      const auto inside = [&](const Vec3& x) { return sign * (field.sample(x).value - iso) > 0; };
      if (!is_finite(centre) || !inside(centre)) continue;
      const double limit = std::max(3.0 * small.base_radius[c], 0.02 * cell);
      for (const std::uint32_t v : list) {
        if (mesh.role[v] != WrapRole::Free) continue;
        const Vec3 offset = source[v] - centre;
        const double length = norm(offset);
        if (!(length > 0)) continue;
        const Vec3 u = offset * (1.0 / length);
        double a = 0, b = -1;
        for (int i = 1; i <= kSamples; ++i) {
          const double t = limit * double(i) / kSamples;
          if (!inside(centre + t * u)) {
            b = t;
            break;
          }
          a = t;
        }
        if (b < 0) continue;
        while (b - a > precision) {
          const double m = 0.5 * (a + b);
          (inside(centre + m * u) ? a : b) = m;
        }
        const Vec3 x = place(mesh, box, v, centre + (0.5 * (a + b)) * u);
        if (is_finite(x)) target[v] = x;
      }
    }
  });
}

// Throws Error(InvalidArgument) naming the first of positions[0 .. count)
// more than a cell outside the volume's box. A base from another volume
// (other spacing or origin) would be pressed onto the box and fitted to
// nothing; one from this volume's isosurface lies inside its box.
void require_inside_box(const std::vector<Vec3>& positions, std::size_t count, const Volume& field) {
  const Vec3 low = volume_box_min(field), high = volume_box_max(field);
  const double cell = field.cell_size();
  for (std::size_t v = 0; v < count; ++v) {
    const Vec3& p = positions[v];
    const double outside = norm(component_max(Vec3{}, component_max(low - p, p - high)));
    if (!(outside > cell)) continue;
    std::ostringstream message;
    message << "base vertex " << v << " at (" << p.x << ", " << p.y << ", " << p.z << ") lies " << outside / cell
            << " cells outside the volume's box (" << low.x << ", " << low.y << ", " << low.z << ") .. (" << high.x
            << ", " << high.y << ", " << high.z << "): is the base mesh from this volume (same spacing and origin)?";
    throw Error(ErrorKind::InvalidArgument, message.str());
  }
}

// Throws Error(InvalidArgument) naming the first vertex on a boundary edge
// of the base (level 0's `mesh`) more than a cell from every face of the
// volume's box. An extracted isosurface has boundaries only on those faces
// (NaN samples count as outside, so the surface closes around them), and
// simplification keeps its boundary vertices there; a base with a hole
// elsewhere would be fitted with the hole left open.
void require_boundary_on_box(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, const Volume& field) {
  const Vec3 low = volume_box_min(field), high = volume_box_max(field);
  const double cell = field.cell_size();
  for (std::size_t v = 0; v < mesh.vertex_count; ++v) {
    if (mesh.boundary_neighbours[2 * v] == WrapLevelMesh::kNone) continue;
    const Vec3& p = positions[v];
    double to_box = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) to_box = std::min({to_box, std::abs(p[a] - low[a]), std::abs(high[a] - p[a])});
    if (to_box <= cell) continue;
    std::ostringstream message;
    message << "base vertex " << v << " at (" << p.x << ", " << p.y << ", " << p.z << ") lies on a boundary of the base"
            << " mesh " << to_box / cell << " cells from the volume's box, where an isosurface extracted from this"
            << " volume has none: is the base mesh from this volume, and closed where its isosurface is?";
    throw Error(ErrorKind::InvalidArgument, message.str());
  }
}

// Throws Error(InvalidArgument) when most base vertices have a normal (the
// sum of their faces' area vectors) pointing against the field's
// orientation (toward higher values, or lower ones with flip): a base
// extracted with the other --flip, on which the fit folds nearly every face
// (a sphere: 95% of the fine faces tangled, points up to 7.5 cells off the
// isosurface). Bases of the same field disagree at far fewer vertices
// (miranda 15.6%, mixing at 96^3 1.8%, engine CT 0.1%).
void require_oriented_as_the_field(const PolygonMesh& base, const std::vector<Vec3>& positions, const Volume& field,
                                   bool flip) {
  std::vector<Vec3> normals(base.vertex_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t* face = base.face_begin(f);
    const std::uint32_t size = base.face_size(f);
    const Vec3 newell = newell_vector(face, size, positions);
    for (std::uint32_t k = 0; k < size; ++k) normals[face[k]] += newell;
  }
  const TrilinearGrid grid(field);
  const double expected_sign = flip ? 1.0 : -1.0;
  std::size_t counted = 0, against = 0;
  for (std::size_t v = 0; v < base.vertex_count(); ++v) {
    const double agreement = expected_sign * dot(normals[v], grid.sample(positions[v]).gradient);
    if (!(agreement != 0)) continue;  // no normal, no gradient, or NaN
    ++counted;
    against += agreement < 0 ? 1 : 0;
  }
  if (2 * against > counted)
    throw Error(ErrorKind::InvalidArgument,
                "the base mesh faces the other way: at " + std::to_string(against) + " of " + std::to_string(counted) +
                    " vertices its normals point toward " + (flip ? "lower" : "higher") +
                    " field values (was it extracted with the other --flip?)");
}

// Mean length of the level's edges (each counted from both ends), world
// units; from the edges of every stride-th vertex, so that at most about
// 2^18 vertices are read (the whole of miranda's level 3 took 0.1 s).
double mean_edge_length(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions) {
  struct Sum {
    double length = 0;
    std::size_t count = 0;
  };
  const std::size_t stride = std::max<std::size_t>(1, mesh.vertex_count >> 18);
  const std::size_t sampled = (mesh.vertex_count + stride - 1) / stride;
  Sum total;
  for (const Sum& part : for_blocks<Sum>(sampled, [&](std::size_t first, std::size_t last, Sum& sum) {
         for (std::size_t i = first; i < last; ++i) {
           const std::size_t v = i * stride;
           for (std::uint32_t k = mesh.neighbour_offsets[v]; k < mesh.neighbour_offsets[v + 1]; ++k)
             sum.length += norm(positions[mesh.neighbours[k]] - positions[v]);
           sum.count += mesh.neighbour_offsets[v + 1] - mesh.neighbour_offsets[v];
         }
       })) {
    total.length += part.length;
    total.count += part.count;
  }
  return total.count ? total.length / double(total.count) : 0.0;
}

}  // namespace

ShrinkWrapResult shrink_wrap(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_positions,
                             const SignedDistanceField& distance, const Volume& field,
                             const ShrinkWrapOptions& options, ProgressSink& progress) {
  const std::size_t base_count = hierarchy.vertex_count(0);
  if (base_positions.size() < base_count)
    throw Error(ErrorKind::InvalidArgument, "shrink-wrap needs " + std::to_string(base_count) +
                                                " base positions, got " + std::to_string(base_positions.size()));
  for (std::size_t v = 0; v < base_count; ++v)
    if (!is_finite(base_positions[v]))
      throw Error(ErrorKind::InvalidArgument, "base vertex " + std::to_string(v) + " has a non-finite position");
  if (distance.distance.dims != field.dims || !(distance.distance.spacing == field.spacing) ||
      !(distance.distance.origin == field.origin) || distance.distance.values.size() != field.sample_count())
    throw Error(ErrorKind::InvalidArgument, "the signed-distance field and the scalar field have different grids");
  if (field.dims[0] < 2 || field.dims[1] < 2 || field.dims[2] < 2)
    throw Error(ErrorKind::InvalidArgument, "shrink-wrap needs at least 2 samples along each axis");
  require_inside_box(base_positions, base_count, field);
  require_oriented_as_the_field(hierarchy.base(), base_positions, field, distance.flip);
  if (options.iterations < 0 || options.iterations > 100 || options.final_level_iterations < 0 ||
      options.final_level_iterations > 100)
    throw Error(ErrorKind::InvalidArgument, "shrink-wrap iterations must be in 0..100");
  if (options.untangle_rounds < 0 || options.untangle_rounds > 100 || options.coarse_untangle_rounds < 0 ||
      options.coarse_untangle_rounds > 100)
    throw Error(ErrorKind::InvalidArgument, "untangle rounds must be in 0..100");
  if (options.unfold_rounds < 0 || options.unfold_rounds > 100 || !(options.unfold_max_tangled_fraction >= 0) ||
      !(options.unfold_max_tangled_fraction <= 1))
    throw Error(ErrorKind::InvalidArgument, "unfold rounds must be in 0..100 and its tangled limit in [0, 1]");
  if (!(options.relaxation_weight > 0 && options.relaxation_weight <= 1))
    throw Error(ErrorKind::InvalidArgument, "relaxation weight must be in (0, 1]");
  if (!(options.attraction.reach_edges > 0) || !(options.attraction.min_reach_cells >= 0) ||
      !std::isfinite(options.attraction.reach_edges) || !std::isfinite(options.attraction.min_reach_cells))
    throw Error(ErrorKind::InvalidArgument, "attraction reach must be positive and finite");
  if (!(options.pull_covered_cells > 0) || !(options.pull_reach_cells >= options.pull_covered_cells) ||
      !std::isfinite(options.pull_reach_cells) || !(options.final_pull_reach_cells >= options.pull_covered_cells) ||
      !std::isfinite(options.final_pull_reach_cells) || !(options.pull_max_edge_cells >= 0) ||
      !std::isfinite(options.pull_max_edge_cells))
    throw Error(ErrorKind::InvalidArgument, "coverage pull: need 0 < covered <= reach, finite, and edge limit >= 0");
  if (!(options.correction_max_cells > 0) || !std::isfinite(options.correction_max_cells))
    throw Error(ErrorKind::InvalidArgument, "correction distance must be positive and finite");
  if (!(options.small_component_cells >= 0) || !std::isfinite(options.small_component_cells))
    throw Error(ErrorKind::InvalidArgument, "small component size must be non-negative and finite");

  progress.begin_stage("shrink-wrap");
  ShrinkWrapResult result;
  const int levels = hierarchy.levels();
  // Both position buffers are sized for the finest level once, on huge pages.
  std::vector<Vec3>& data = result.positions;
  std::vector<Vec3> scratch;
  const std::size_t fine_count = hierarchy.vertex_count(levels);
  reserve_on_huge_pages(data, fine_count);
  reserve_on_huge_pages(scratch, fine_count);
  data.assign(base_positions.begin(), base_positions.begin() + static_cast<std::ptrdiff_t>(base_count));
  FaceNormals face_normals;
  reserve_on_huge_pages(face_normals, levels > 0 ? std::size_t{hierarchy.step(levels).face_offsets.back()} : 0);
  WrapLevelMesh mesh;
  reserve_finest_wrap_level_mesh(hierarchy, mesh);
  SmallComponents small;
  std::vector<std::uint8_t> tangent_only;
  // The field without the closed components extraction dropped and with
  // its non-finite samples filled, for every search along it (see
  // mirror_enclosed_samples, fill_non_finite_samples); on huge pages, as the
  // searches sample it at scattered places (a few milliseconds to fill,
  // most of the TLB misses saved).
  HugePageVector<float> field_values;
  reserve_fresh_on_huge_pages(field_values, field.values.size());
  field_values.resize(field.values.size());
  mirror_enclosed_samples(field, distance, field_values.data());  // as many as the distance field flipped
  fill_non_finite_samples(field, distance.iso, field_values.data());
  const TrilinearGrid scalar_grid(field, field_values.data());
  const Box box(field);
  const double cell = field.cell_size();
  std::unique_ptr<CoveragePull> pull;
  if (options.coverage_pull && options.surface && !options.surface->positions.empty())
    pull = std::make_unique<CoveragePull>(options.surface->positions, field, options.pull_covered_cells * cell);
  double work_done = 0, work_total = 0;
  for (int level = 0; level <= levels; ++level) work_total += double(hierarchy.vertex_count(level));

  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  for (int level = 0; level <= levels; ++level) {
    const auto start = Clock::now();
    if (level > 0) subdivide_level(hierarchy, level, data);
    fill_wrap_level_mesh(hierarchy, level, data, field, distance.iso, mesh);
    if (level == 0) require_boundary_on_box(mesh, data, field);
    constrain_to_box(mesh, field, data);
    WrapLevelStatistics stats;
    stats.level = level;
    stats.vertices = mesh.vertex_count;
    struct RoleCounts {
      std::size_t boundary = 0, fixed = 0;
    };
    for (const RoleCounts& counts :
         for_blocks<RoleCounts>(mesh.vertex_count, [&](std::size_t first, std::size_t last, RoleCounts& counts) {
           for (std::size_t v = first; v < last; ++v) {
             counts.boundary += mesh.box_face[v] >= 0 ? 1 : 0;
             counts.fixed += mesh.role[v] == WrapRole::Fixed ? 1 : 0;
           }
         })) {
      stats.boundary_vertices += counts.boundary;
      stats.fixed_vertices += counts.fixed;
    }
    if (options.small_component_vertices > 0) {
      if (level == 0)
        small = find_small_components(hierarchy, mesh, data, options.small_component_vertices,
                                      options.small_component_cells * cell, distance.flip);
      if (!small.empty()) small.set_level(hierarchy, level, mesh);
    }
    stats.seconds_setup = seconds_since(start);
    const int rounds = level < levels ? options.iterations : options.final_level_iterations;
    // The small components relax within their tangent planes (levels < L).
    const bool tangential = !small.empty() && level < levels;
    if (tangential) {
      tangent_only.assign(mesh.vertex_count, 0);
      for (const std::vector<std::uint32_t>& list : small.vertices)
        for (const std::uint32_t v : list) tangent_only[v] = 1;
    }
    if (pull) stats.mean_edge_cells = mean_edge_length(mesh, data) / cell;
    const bool pulls = pull && stats.mean_edge_cells <= options.pull_max_edge_cells;
    // On level L the pull waits for the correction and the untangling, whose
    // smoothing would otherwise take back part of what it covered.
    const bool pull_last = pulls && level == levels && options.final_correction;
    scratch.resize(mesh.vertex_count);
    for (int round = 0; round < rounds; ++round) {
      auto phase = Clock::now();
      relax_with(mesh, field, options.relaxation_weight, data, scratch, tangential ? tangent_only.data() : nullptr);
      stats.seconds_relaxation += seconds_since(phase);
      phase = Clock::now();
      stats.last_attraction = attract_with(mesh, distance, options.attraction, scratch, data, face_normals);
      if (!small.empty()) fit_small_components(mesh, small, scalar_grid, box, cell, distance.iso, scratch, data);
      stats.seconds_attraction += seconds_since(phase);
      if (pulls && !pull_last && round + 1 == rounds) {
        // On the attracted points of the level's last round: measured on
        // relaxed or merely subdivided points, the pull took the surface
        // those had shrunk away from for left out. Pulling after every round
        // cost 1.5 s more on miranda for a little more coverage (with an
        // earlier form of the pull, 3.7% against 4.6% of the extracted
        // vertices over 2 cells).
        phase = Clock::now();
        const CoveragePullStatistics pulled = pull->apply(mesh, data, options.pull_reach_cells * cell);
        stats.uncovered_samples = pulled.uncovered_samples;
        stats.pulled_vertices = pulled.pulled_vertices;
        stats.seconds_pull += seconds_since(phase);
      }
    }
    if (level == levels && (options.final_correction || options.untangle_rounds > 0)) {
      auto phase = Clock::now();
      const TrilinearGrid& field_grid = scalar_grid;
      const TrilinearGrid distance_grid(distance.distance);
      if (options.final_correction) {
        for (const std::vector<std::uint32_t>& list : small.vertices)
          for (const std::uint32_t v : list) scratch[v] = data[v];
        result.correction =
            correct_with(mesh, field_grid, box, cell, distance.iso, options.correction_max_cells, data,
                         options.correction_from_nearest_point ? &distance_grid : nullptr,
                         distance.flip ? 1.0 : -1.0, options.surface, &distance_grid);
        if (!small.empty()) fit_small_components(mesh, small, field_grid, box, cell, distance.iso, scratch, data);
        stats.seconds_correction = seconds_since(phase);
      }
      phase = Clock::now();
      if (options.untangle_rounds > 0) {
        result.untangle = untangle_with(mesh, field_grid, box, cell, distance.iso, distance.flip,
                                        options.untangle_rounds, options.correction_max_cells, data, scratch);
        stats.seconds_untangle = seconds_since(phase);
      }
      if (pull_last) {
        phase = Clock::now();
        std::vector<PulledPoint> pulled_points;
        const CoveragePullStatistics pulled =
            pull->apply(mesh, data, options.final_pull_reach_cells * cell, &pulled_points);
        stats.uncovered_samples = pulled.uncovered_samples;
        stats.pulled_vertices = pulled.pulled_vertices;
        stats.pulled_back = settle_pulled_points(mesh, field_grid, box, cell, distance.iso, distance.flip,
                                                 options.correction_max_cells,
                                                 options.correction_from_nearest_point ? &distance_grid : nullptr,
                                                 pulled_points, data);
        stats.seconds_pull += seconds_since(phase);
      }
      // Judged by untangle()'s count when it ran: the pull changes few
      // faces, and counting them again cost 0.2 s on miranda, where the
      // unfold does not run. Without it, counted here (else the limit would
      // never hold back the unfold: 14.5 s on miranda).
      if (options.untangle_rounds > 0) {
        result.tangled_faces = result.untangle.tangled_after;
      } else {
        HugePageVector<std::uint8_t> tangled;
        result.tangled_faces = find_tangled_faces(mesh, field_grid, distance.flip, data, tangled);
      }
      const bool too_tangled =
          double(result.tangled_faces) > options.unfold_max_tangled_fraction * double(mesh.face_count());
      if (options.unfold_rounds > 0 && too_tangled) {
        result.unfold.tangled_before = result.unfold.tangled_after = result.tangled_faces;
        result.unfold.skipped = true;
      } else if (options.unfold_rounds > 0) {
        phase = Clock::now();
        result.unfold = unfold_with(mesh, field_grid, box, cell, distance.iso, distance.flip, options.unfold_rounds,
                                    options.correction_max_cells, data);
        result.tangled_faces = result.unfold.tangled_after;
        stats.seconds_unfold = seconds_since(phase);
      }
    }
    if (level < levels && options.coarse_untangle_rounds > 0) {
      // Against the distance field, whose gradient the vertex normals agree
      // with (hence flip, iso 0); scratch is free after the rounds.
      const auto phase = Clock::now();
      untangle_with(mesh, TrilinearGrid(distance.distance), box, cell, 0.0, true, options.coarse_untangle_rounds,
                    options.correction_max_cells, data, scratch);
      stats.seconds_untangle = seconds_since(phase);
    }
    if (options.keep_levels && level < levels)
      result.level_positions.emplace_back(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(mesh.vertex_count));
    stats.seconds = seconds_since(start);
    result.levels.push_back(stats);
    work_done += double(mesh.vertex_count);
    progress.update(work_done / work_total);
  }
  data.resize(hierarchy.vertex_count(levels));
  progress.end_stage();
  return result;
}

}  // namespace isowave
