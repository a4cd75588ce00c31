#include "isowave/fit/wrap_steps.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <vector>

#include "isowave/fit/trilinear.h"
#include "root_search.h"
#include "wrap_kernels.h"
#include "wrap_passes.h"

namespace isowave::wrap {

void compute_face_normals(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, FaceNormals& face_normals) {
  const std::size_t faces = mesh.face_count();
  face_normals.resize(faces);
  for_vertices(faces, [&](std::size_t f) {
    const Vec3 n = face_normal(mesh.face_vertices.data() + mesh.face_offsets[f],
                               mesh.face_offsets[f + 1] - mesh.face_offsets[f], positions);
    face_normals[f] = {static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z)};
  });
}

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

void relax_with(const WrapLevelMesh& mesh, const Volume& box_volume, double weight, const std::vector<Vec3>& in,
                std::vector<Vec3>& out, const std::uint8_t* tangent_only) {
  assert(in.size() >= mesh.vertex_count && &in != &out);
  out.resize(std::max(out.size(), mesh.vertex_count));
  const Box box(box_volume);
  for_vertices(mesh.vertex_count, [&](std::size_t v) {
    const Vec3& p = in[v];
    out[v] = p;
    Vec3 centroid;
    // A vertex held on a box face does not relax: along its boundary curve the relaxation only shrinks
    // the curve, which the attraction within the face does not restore where it is narrower than a cell.
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

// One attraction round's setup and its search per vertex (see attract()).
struct Attraction {
  const WrapLevelMesh& mesh;
  const AttractionOptions& options;
  const std::vector<Vec3>& in;
  std::vector<Vec3>& out;
  const FaceNormals& face_normals;
  const TrilinearGrid grid;  // of the distance field
  const Box box;
  const double cell;
  const double min_step, tolerance;
  // The reach is never shorter than this; the searches go this far before
  // the vertex's edge lengths are needed.
  const double near;

  // Moves vertex v (writes out[v]) and counts it in `partial`.
  void vertex(std::size_t v, AttractionPartial& partial) const {
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
    double best_sign = 1;
    const double best = crossing(v, p, d, best_sign);
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
  }

  // The samples and face normals of vertex v: both are gathered from arrays
  // far larger than the cache.
  void prefetch(std::size_t v) const {
    grid.prefetch_at(grid.grid_point(in[v]));
    for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
      __builtin_prefetch(&face_normals[mesh.vertex_faces[k]]);
  }

  // The distance from p along +-d (its sign in best_sign) to the nearest
  // crossing that agrees with d, within reach and the box; negative if none.
  double crossing(std::size_t v, const Vec3& p, const Vec3& d, double& best_sign) const {
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
    double best = -1;
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
    return best;
  }
};

}  // namespace

AttractionStatistics attract_with(const WrapLevelMesh& mesh, const SignedDistanceField& distance,
                                  const AttractionOptions& options, const std::vector<Vec3>& in,
                                  std::vector<Vec3>& out, FaceNormals& face_normals) {
  assert(in.size() >= mesh.vertex_count && &in != &out);
  out.resize(std::max(out.size(), mesh.vertex_count));
  compute_face_normals(mesh, in, face_normals);
  const Volume& field = distance.distance;
  const double cell = field.cell_size();
  const Attraction attraction{mesh, options, in, out, face_normals, TrilinearGrid(field), Box(field), cell, 0.2 * cell,
                              1e-3 * cell, options.min_reach_cells * cell};
  const std::vector<AttractionPartial> partials =
      for_blocks<AttractionPartial>(mesh.vertex_count, [&](std::size_t begin, std::size_t end, AttractionPartial& partial) {
        for (std::size_t v = begin; v < end; ++v) {
          if (v + kPrefetchDistance < end) attraction.prefetch(v + kPrefetchDistance);
          attraction.vertex(v, partial);
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

}  // namespace isowave::wrap

namespace isowave {

void relax(const WrapLevelMesh& mesh, const Volume& box_volume, double weight, const std::vector<Vec3>& in,
           std::vector<Vec3>& out) {
  wrap::relax_with(mesh, box_volume, weight, in, out, nullptr);
}

AttractionStatistics attract(const WrapLevelMesh& mesh, const SignedDistanceField& distance,
                             const AttractionOptions& options, const std::vector<Vec3>& in, std::vector<Vec3>& out) {
  wrap::FaceNormals face_normals;
  return wrap::attract_with(mesh, distance, options, in, out, face_normals);
}

}  // namespace isowave
