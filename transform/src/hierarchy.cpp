#include "isowave/transform/hierarchy.h"

#include <algorithm>
#include <cassert>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/transform/refinement_steps.h"

namespace isowave {

namespace {

template <class T>
std::size_t vector_bytes(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

}  // namespace

std::vector<LevelCounts> refinement_counts(const LevelCounts& base, int levels) {
  std::vector<LevelCounts> counts{base};
  for (int l = 0; l < levels; ++l) {
    const LevelCounts& parent = counts.back();
    counts.push_back({parent.vertices + parent.faces + parent.edges, parent.corners, 2 * parent.edges + parent.corners,
                      4 * parent.corners});
  }
  return counts;
}

LevelCounts level_counts(const PolygonMesh& base, std::size_t edges) {
  return {double(base.vertex_count()), double(base.face_count()), double(edges), double(base.face_vertices.size())};
}

std::size_t fine_vertex_count(const PolygonMesh& base, int levels) {
  const LevelCounts counts = level_counts(base, summarize_topology(base).edges);
  return static_cast<std::size_t>(refinement_counts(counts, levels).back().vertices);
}

std::pair<std::size_t, std::size_t> SubdivisionHierarchy::descendant_faces(std::size_t base_face, int level) const {
  assert(base_face < base_.face_count() && level >= 0 && level <= levels());
  if (level == 0) return {base_face, base_face + 1};
  const int shift = 2 * (level - 1);
  return {std::size_t{base_.face_offsets[base_face]} << shift, std::size_t{base_.face_offsets[base_face + 1]} << shift};
}

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

  vertex_counts_.push_back(base.vertex_count());
  if (levels == 0) return;
  // Checks the finest level's size before refining.
  steps_ = detail::build_refinement_steps(base_, levels);
  for (const RefinementStep& s : steps_) vertex_counts_.push_back(s.child_vertex_count());
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
  const std::size_t n = vertex_count(level);
  std::vector<Vec3> own;
  reserve_fresh_on_huge_pages(own, n);
  own.assign(positions.begin(), positions.begin() + static_cast<std::ptrdiff_t>(std::min(n, positions.size())));
  return control_mesh(level, std::move(own));
}

PolygonMesh SubdivisionHierarchy::control_mesh(int level, std::vector<Vec3>&& positions) const {
  PolygonMesh mesh;
  mesh.positions = std::move(positions);
  mesh.positions.resize(vertex_count(level));
  if (base_.sharp_count() > 0) mesh.sharp = sharp_flags(level);
  if (level == 0) {
    mesh.face_offsets = base_.face_offsets;
    mesh.face_vertices = base_.face_vertices;
    return mesh;
  }
  // Each parent face with n corners splits into n quads: corner k, the e
  // vertex of edge k, the f vertex, the e vertex of edge k-1 (orientation kept).
  const RefinementStep& s = step(level);
  const std::uint32_t quads = s.face_offsets.back();
  reserve_fresh_on_huge_pages(mesh.face_offsets, std::size_t{quads} + 1);
  mesh.face_offsets.resize(std::size_t{quads} + 1);
  reserve_fresh_on_huge_pages(mesh.face_vertices, 4 * std::size_t{quads});
  mesh.face_vertices.resize(4 * std::size_t{quads});
  const auto fill = [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t f = begin; f < end; ++f) {
      const std::uint32_t row = s.face_offsets[f], row_end = s.face_offsets[f + 1];
      for (std::uint32_t k = row; k < row_end; ++k) {
        const std::uint32_t previous = k == row ? row_end - 1 : k - 1;
        std::uint32_t* quad = &mesh.face_vertices[4 * std::size_t{k}];
        quad[0] = s.face_vertices[k];
        quad[1] = s.face_edges[k];
        quad[2] = s.first_face_vertex() + f;
        quad[3] = s.face_edges[previous];
        mesh.face_offsets[k] = 4 * k;
      }
    }
  };
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, s.parent_face_count, 16384),
                    [&](const tbb::blocked_range<std::uint32_t>& r) { fill(r.begin(), r.end()); });
  mesh.face_offsets[quads] = 4 * quads;
  return mesh;
}

std::size_t SubdivisionHierarchy::memory_bytes() const {
  std::size_t bytes = sizeof(*this) + vector_bytes(base_.positions) + vector_bytes(base_.face_offsets) +
                      vector_bytes(base_.face_vertices) + vector_bytes(base_.sharp) + vector_bytes(vertex_counts_);
  for (const RefinementStep& s : steps_) bytes += s.memory_bytes();
  return bytes;
}

}  // namespace isowave
