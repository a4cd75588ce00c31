// The transpose of one level of lifted synthesis (wavelet_transform.h).
//
// Each lifting step y <- self*y + w_f avg_f + w_e avg_e + w_v avg_v changes
// only its target type; its transpose adds, to every source entry, the
// targets' values that read it, each times w / (the target's neighbour count),
// and then scales the targets by `self`. Synthesis runs the six steps in
// order, so its transpose runs the transposed steps in reverse order. Every
// source gathers from its own neighbour list, so no two threads write one
// entry and the sums have a fixed order.
#include <string>

#include "isowave/transform/lifting_rules.h"
#include "isowave/transform/wavelet_transform.h"
#include "level_checks.h"

namespace isowave {
namespace {

using lifting::Rule;
using lifting::Step;
using lifting::VertexType;

inline double count(const std::vector<std::uint32_t>& offsets, std::uint32_t i) {
  return static_cast<double>(offsets[i + 1] - offsets[i]);
}

// Whether the e vertex of `edge` takes part in `step`.
inline bool edge_active(const RefinementStep& s, const Step& step, std::uint32_t edge) {
  return !step.skipped_on_sharp_edges || s.edge_smooth[edge];
}

// g[target + i] += weight * (the sum of g over the active e vertices that
// list i holds, edges[offsets[i]] .. edges[offsets[i + 1] - 1]), for i < count.
void gather_active_edges(const RefinementStep& s, const Step& step, std::uint32_t count,
                         const std::vector<std::uint32_t>& offsets, const std::vector<std::uint32_t>& edges,
                         double weight, std::uint32_t target, Vec3* g) {
  const std::uint32_t first_e = s.first_edge_vertex();
  detail::for_lifting_range(count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t i = begin; i < end; ++i) {
      Vec3 sum;
      for (std::uint32_t k = offsets[i]; k < offsets[i + 1]; ++k) {
        const std::uint32_t edge = edges[k] - first_e;
        if (edge_active(s, step, edge)) sum += g[first_e + edge];
      }
      g[target + i] += weight * sum;
    }
  });
}

// Transposed step with e targets: faces and vertices gather from their edges.
void transpose_e_step(const RefinementStep& s, Vec3* g, const Step& step) {
  const Rule& r = step.smooth;
  const std::uint32_t first_e = s.first_edge_vertex(), first_f = s.first_face_vertex();
  if (r.f != 0) gather_active_edges(s, step, s.parent_face_count, s.face_offsets, s.face_edges, 0.5 * r.f, first_f, g);
  if (r.v != 0)
    gather_active_edges(s, step, s.parent_vertex_count, s.vertex_edge_offsets, s.vertex_edges, 0.5 * r.v, 0, g);
  detail::for_lifting_range(s.parent_edge_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t e = begin; e < end; ++e)
      if (edge_active(s, step, e)) g[first_e + e] = r.self * g[first_e + e];
  });
}

// Transposed step with f targets: vertices and edges gather from their faces.
void transpose_f_step(const RefinementStep& s, Vec3* g, const Step& step) {
  const Rule& r = step.smooth;
  const std::uint32_t first_e = s.first_edge_vertex(), first_f = s.first_face_vertex();
  const auto per_corner = [&](std::uint32_t face_vertex) {
    return g[face_vertex] * (1.0 / count(s.face_offsets, face_vertex - first_f));
  };
  if (r.v != 0)
    detail::for_lifting_range(s.parent_vertex_count, [&](std::uint32_t begin, std::uint32_t end) {
      for (std::uint32_t v = begin; v < end; ++v) {
        Vec3 sum;
        for (std::uint32_t k = s.vertex_face_offsets[v]; k < s.vertex_face_offsets[v + 1]; ++k)
          sum += per_corner(s.vertex_faces[k]);
        g[v] += r.v * sum;
      }
    });
  if (r.e != 0)
    detail::for_lifting_range(s.parent_edge_count, [&](std::uint32_t begin, std::uint32_t end) {
      for (std::uint32_t e = begin; e < end; ++e) {
        const std::uint32_t f0 = s.edge_faces[2 * e], f1 = s.edge_faces[2 * e + 1];
        Vec3 sum = per_corner(f0);
        if (f1 != f0) sum += per_corner(f1);  // a boundary edge lists its face twice
        g[first_e + e] += r.e * sum;
      }
    });
  detail::for_lifting_range(s.parent_face_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t f = begin; f < end; ++f) g[first_f + f] = r.self * g[first_f + f];
  });
}

// Transposed step with v targets: faces and edges gather from their smooth
// corners; the crease vertices' two edges take their share in one serial pass.
void transpose_v_step(const RefinementStep& s, Vec3* g, const Step& step) {
  const Rule& r = step.smooth;
  const std::uint32_t first_e = s.first_edge_vertex(), first_f = s.first_face_vertex();
  const auto smooth = [&](std::uint32_t v) { return s.vertex_rule[v] == VertexRule::Smooth; };
  if (r.f != 0)
    detail::for_lifting_range(s.parent_face_count, [&](std::uint32_t begin, std::uint32_t end) {
      for (std::uint32_t f = begin; f < end; ++f) {
        Vec3 sum;
        for (std::uint32_t k = s.face_offsets[f]; k < s.face_offsets[f + 1]; ++k) {
          const std::uint32_t v = s.face_vertices[k];
          if (smooth(v)) sum += g[v] * (1.0 / count(s.vertex_face_offsets, v));
        }
        g[first_f + f] += r.f * sum;
      }
    });
  if (r.e != 0)
    detail::for_lifting_range(s.parent_edge_count, [&](std::uint32_t begin, std::uint32_t end) {
      for (std::uint32_t e = begin; e < end; ++e) {
        Vec3 sum;
        for (int side = 0; side < 2; ++side) {
          const std::uint32_t v = s.edge_vertices[2 * e + static_cast<std::uint32_t>(side)];
          if (smooth(v)) sum += g[v] * (1.0 / count(s.vertex_edge_offsets, v));
        }
        g[first_e + e] += r.e * sum;
      }
    });
  const Rule& c = step.crease;
  for (std::size_t k = 0; k < s.crease_vertices.size(); ++k) {
    const Vec3 share = (0.5 * c.e) * g[s.crease_vertices[k]];
    g[s.crease_edges[2 * k]] += share;
    g[s.crease_edges[2 * k + 1]] += share;
  }
  detail::for_lifting_range(s.parent_vertex_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t v = begin; v < end; ++v)
      if (smooth(v)) g[v] = r.self * g[v];
  });
  for (const std::uint32_t v : s.crease_vertices) g[v] = c.self * g[v];
}

}  // namespace

void synthesize_level_transpose(const SubdivisionHierarchy& hierarchy, int level, std::vector<Vec3>& data) {
  detail::require_level(hierarchy, level);
  detail::require_size(hierarchy, data, level);
  const RefinementStep& s = hierarchy.step(level);
  for (auto step = lifting::kSynthesisSteps.rbegin(); step != lifting::kSynthesisSteps.rend(); ++step) {
    switch (step->target) {
      case VertexType::E: transpose_e_step(s, data.data(), *step); break;
      case VertexType::F: transpose_f_step(s, data.data(), *step); break;
      case VertexType::V: transpose_v_step(s, data.data(), *step); break;
    }
  }
}

}  // namespace isowave
