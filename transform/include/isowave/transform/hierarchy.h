#pragma once
// The subdivision hierarchy over a polygonal base mesh (Bertram et al. 2000,
// Sec. 3.3): L levels of Catmull-Clark connectivity, level 1 and finer all
// quads. The hierarchy keeps, per refinement step, only the flat index arrays
// the averaging operators need. It builds them itself, in parallel, numbered
// exactly as OpenSubdiv's Far::TopologyRefiner numbers uniform refinement
// (refinement_steps.h; a test compares every array with OpenSubdiv's).
//
// Vertex numbering (OpenSubdiv's uniform refinement order): level l holds the
// v vertices (children of level l-1 vertices, same indices) first, then the f
// vertices (children of faces), then the e vertices (children of edges). So a
// coarser level is a prefix of a finer one, and one array of
// vertex_count(L) entries holds every level in place: base control points,
// then level-1 f and e details, then level 2, and so on.
//
// Sharp features (Sec. 3.4, and where the paper is silent): boundary edges are
// sharp; a vertex flagged sharp, or with three or more incident sharp edges (a
// corner), is sharp and never moves; a vertex with exactly two incident sharp
// edges follows the curve (crease) rules; a vertex with one (a dart) follows
// the smooth rules; an e vertex on a sharp edge or on an edge with a sharp
// endpoint skips rules 1 and 5. Children of sharp vertices stay sharp.
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "isowave/core/mesh.h"

namespace isowave {

enum class VertexRule : std::uint8_t { Smooth = 0, Crease = 1, Sharp = 2 };

// Everything the lifting steps of one refinement (level l-1 to level l) read.
// All indices are vertex indices of level l: with V, F, E the parent's vertex,
// face and edge counts, the v vertices are [0, V), the f vertices [V, V+F) and
// the e vertices [V+F, V+F+E). Arrays are flat (structure of arrays) so the
// lifting loops stream through contiguous memory and split cleanly across
// threads.
struct RefinementStep {
  std::uint32_t parent_vertex_count = 0;
  std::uint32_t parent_face_count = 0;
  std::uint32_t parent_edge_count = 0;

  // Per parent edge: its two v vertices, and the f vertices of its two faces
  // (a boundary edge lists its one face twice).
  std::vector<std::uint32_t> edge_vertices;
  std::vector<std::uint32_t> edge_faces;
  // Per parent edge: 1 if its e vertex follows the smooth rules 1 and 5.
  std::vector<std::uint8_t> edge_smooth;

  // Per parent face (rows face_offsets[f] .. face_offsets[f+1]): its corner v
  // vertices and its edges' e vertices, edge k joining corners k and k+1.
  std::vector<std::uint32_t> face_offsets;
  std::vector<std::uint32_t> face_vertices;
  std::vector<std::uint32_t> face_edges;

  // Per parent vertex: the e vertices of incident edges and the f vertices of
  // incident faces.
  std::vector<std::uint32_t> vertex_edge_offsets;
  std::vector<std::uint32_t> vertex_edges;
  std::vector<std::uint32_t> vertex_face_offsets;
  std::vector<std::uint32_t> vertex_faces;
  std::vector<VertexRule> vertex_rule;
  // Crease vertices and the e vertices of their two sharp edges.
  std::vector<std::uint32_t> crease_vertices;
  std::vector<std::uint32_t> crease_edges;

  std::uint32_t child_vertex_count() const { return parent_vertex_count + parent_face_count + parent_edge_count; }
  std::uint32_t first_face_vertex() const { return parent_vertex_count; }
  std::uint32_t first_edge_vertex() const { return parent_vertex_count + parent_face_count; }
  std::size_t memory_bytes() const;
};

// Element counts of one level of the uniform refinement, in double so that
// sizes beyond any index type can be tested before anything is built.
struct LevelCounts {
  double vertices = 0, faces = 0, edges = 0, corners = 0;
};
// counts[0] = `base`, counts[l] after l refinements: V' = V + F + E,
// F' = corners, E' = 2 E + corners, corners' = 4 F' (every child face a quad).
std::vector<LevelCounts> refinement_counts(const LevelCounts& base, int levels);
// The counts of a base mesh with `edges` edges (all the refinement needs of
// its topology).
LevelCounts level_counts(const PolygonMesh& base, std::size_t edges);
// Fine control point count of `levels` refinements of `base`, from the
// counting rules alone (no refinement; O(base size)).
std::size_t fine_vertex_count(const PolygonMesh& base, int levels);

class SubdivisionHierarchy {
 public:
  static constexpr int kMaxLevels = 10;

  // `base` gives the topology and the sharp flags (positions are not used).
  // Throws Error(Topology) unless base is a consistently oriented 2-manifold
  // (see require_manifold), Error(InvalidArgument) unless 0 <= levels <=
  // kMaxLevels and the finest level fits 32-bit indices.
  // Cost: O(fine vertices) time and memory.
  SubdivisionHierarchy(const PolygonMesh& base, int levels);

  int levels() const { return static_cast<int>(steps_.size()); }
  // Vertices of level `level` in [0, levels()]; level 0 is the base mesh.
  std::size_t vertex_count(int level) const { return vertex_counts_[static_cast<std::size_t>(level)]; }
  std::size_t fine_vertex_count() const { return vertex_counts_.back(); }
  // Level at which the vertex (or coefficient) with this index first appears.
  int level_of_index(std::size_t index) const;
  // The faces of level `level` that descend from base face `base_face`: the
  // range [first, second). Level-1 faces are numbered by base corner, each
  // finer level by 4 per parent face, so every patch is contiguous.
  std::pair<std::size_t, std::size_t> descendant_faces(std::size_t base_face, int level) const;

  // Refinement from level-1 to level, for level in [1, levels()].
  const RefinementStep& step(int level) const { return steps_[static_cast<std::size_t>(level - 1)]; }

  // Base mesh topology and sharp flags as given.
  const PolygonMesh& base() const { return base_; }

  // Per-vertex sharp flags of a level (children of sharp vertices).
  std::vector<std::uint8_t> sharp_flags(int level) const;

  // The control mesh of a level with the given positions (at least
  // vertex_count(level) of them; extra ones are ignored), sharp flags included.
  // Level 0 returns the base faces; finer levels are all quads.
  PolygonMesh control_mesh(int level, const std::vector<Vec3>& positions) const;
  // The same, taking over the positions' array instead of copying it.
  PolygonMesh control_mesh(int level, std::vector<Vec3>&& positions) const;

  // Bytes held by the hierarchy (index arrays and the base mesh copy).
  std::size_t memory_bytes() const;

 private:
  PolygonMesh base_;
  std::vector<std::size_t> vertex_counts_;
  std::vector<RefinementStep> steps_;
};

// Visits the fine (level-L) control points of base face `base_face`: the
// corners, e vertices and f vertices of its level-(L-1) descendants' finest
// refinement (shared points more than once), or its corners when L = 0.
// Stops when `visit(index)` returns false; returns whether it went through.
template <class Visit>
bool for_each_fine_point(const SubdivisionHierarchy& hierarchy, std::size_t base_face, Visit&& visit) {
  const int levels = hierarchy.levels();
  const PolygonMesh& base = hierarchy.base();
  if (levels == 0) {
    for (std::uint32_t k = base.face_offsets[base_face]; k < base.face_offsets[base_face + 1]; ++k)
      if (!visit(std::size_t{base.face_vertices[k]})) return false;
    return true;
  }
  const RefinementStep& s = hierarchy.step(levels);
  const auto [first, end] = hierarchy.descendant_faces(base_face, levels - 1);
  for (std::size_t p = first; p < end; ++p) {
    if (!visit(std::size_t{s.first_face_vertex()} + p)) return false;
    for (std::uint32_t k = s.face_offsets[p]; k < s.face_offsets[p + 1]; ++k)
      if (!visit(std::size_t{s.face_vertices[k]}) || !visit(std::size_t{s.face_edges[k]})) return false;
  }
  return true;
}

}  // namespace isowave
