#include "local_frames.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/huge_page_vector.h"

#include "isowave/transform/wavelet_transform.h"

namespace isowave::detail {

constexpr std::size_t kFrameGrain = 1 << 14;

Frame frame_of(const Vec3& normal) {
  if (!(squared_norm(normal) > 0)) return {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
  int least = 0;
  for (int axis = 1; axis < 3; ++axis)
    if (std::abs(normal[axis]) < std::abs(normal[least])) least = axis;
  Vec3 a;
  a[least] = 1;
  const Vec3 t = normalized(cross(normal, a));
  return {normal, t, cross(normal, t)};
}

namespace {

// Vector area (twice) of the polygon of face `face`'s e vertices, as a fan
// around its f vertex: sum over k of (e_k - f) x (e_{k+1} - f).
Vec3 face_area(const RefinementStep& step, const std::vector<Vec3>& p, std::uint32_t face) {
  const std::uint32_t first = step.face_offsets[face], n = step.face_offsets[face + 1] - first;
  const Vec3& f = p[step.first_face_vertex() + face];
  Vec3 area;
  for (std::uint32_t k = 0; k < n; ++k)
    area += cross(p[step.face_edges[first + k]] - f, p[step.face_edges[first + (k + 1) % n]] - f);
  return area;
}

// L = 0: Newell's vector area of each base face, summed at its corners.
std::vector<Vec3> base_normal_sums(const PolygonMesh& base, const std::vector<Vec3>& p) {
  std::vector<Vec3> sums(base.vertex_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t* v = base.face_begin(f);
    const std::uint32_t n = base.face_size(f);
    Vec3 area;
    for (std::uint32_t k = 0; k < n; ++k) area += cross(p[v[k]], p[v[(k + 1) % n]]);
    for (std::uint32_t k = 0; k < n; ++k) sums[v[k]] += area;
  }
  return sums;
}

// L >= 1, gathered per vertex (each sum in a fixed order, so threads do not
// change it): an f vertex takes its face's area, an e vertex those of the
// faces on both sides of its edge, a v vertex those of the faces around it.
std::vector<Vec3> fine_normal_sums(const RefinementStep& step, const std::vector<Vec3>& p) {
  std::vector<Vec3> sums;
  reserve_fresh_on_huge_pages(sums, p.size());
  sums.resize(p.size());
  const std::uint32_t f_first = step.first_face_vertex(), e_first = step.first_edge_vertex();
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, step.parent_face_count, kFrameGrain), [&](const auto& r) {
    for (std::uint32_t face = r.begin(); face < r.end(); ++face) sums[f_first + face] = face_area(step, p, face);
  });
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, step.parent_edge_count, kFrameGrain), [&](const auto& r) {
    for (std::uint32_t edge = r.begin(); edge < r.end(); ++edge)
      sums[e_first + edge] = sums[step.edge_faces[2 * edge]] + sums[step.edge_faces[2 * edge + 1]];
  });
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, step.parent_vertex_count, kFrameGrain), [&](const auto& r) {
    for (std::uint32_t v = r.begin(); v < r.end(); ++v) {
      Vec3 sum;
      for (std::uint32_t k = step.vertex_face_offsets[v]; k < step.vertex_face_offsets[v + 1]; ++k)
        sum += sums[step.vertex_faces[k]];
      sums[v] = sum;
    }
  });
  return sums;
}

}  // namespace

std::vector<Vec3> frame_normals(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_points) {
  const int levels = hierarchy.levels();
  std::vector<Vec3> sums;
  if (levels == 0) {
    sums = base_normal_sums(hierarchy.base(), base_points);
  } else {
    std::vector<Vec3> p;  // S^L(base_points), synthesized in place with zero details
    reserve_fresh_on_huge_pages(p, hierarchy.fine_vertex_count());
    p.resize(hierarchy.fine_vertex_count());
    std::copy(base_points.begin(), base_points.begin() + static_cast<std::ptrdiff_t>(hierarchy.vertex_count(0)), p.begin());
    synthesize(hierarchy, p);
    sums = fine_normal_sums(hierarchy.step(levels), p);
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sums.size(), kFrameGrain), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const double length = std::sqrt(squared_norm(sums[i]));
      sums[i] = length > 0 ? sums[i] * (1.0 / length) : Vec3{};
    }
  });
  return sums;
}

}  // namespace isowave::detail
