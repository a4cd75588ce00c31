#include "local_frames.h"

#include <cmath>

#include "isowave/transform/wavelet_transform.h"

namespace isowave::detail {

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

// Adds the quad's vector area (half the cross product of its diagonals) to
// its four corners.
inline void add_quad(const std::vector<Vec3>& p, std::vector<Vec3>& sums, std::uint32_t a, std::uint32_t b,
                     std::uint32_t c, std::uint32_t d) {
  const Vec3 area = cross(p[c] - p[a], p[d] - p[b]);
  sums[a] += area;
  sums[b] += area;
  sums[c] += area;
  sums[d] += area;
}

}  // namespace

std::vector<Vec3> frame_normals(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_points) {
  const int levels = hierarchy.levels();
  const std::vector<Vec3> p = levels > 0 ? subdivide(hierarchy, base_points) : base_points;
  std::vector<Vec3> sums(hierarchy.fine_vertex_count());
  if (levels == 0) {
    const PolygonMesh& base = hierarchy.base();
    for (std::size_t f = 0; f < base.face_count(); ++f) {
      const std::uint32_t* v = base.face_begin(f);
      const std::uint32_t n = base.face_size(f);
      Vec3 area;  // Newell's vector area of the polygon
      for (std::uint32_t k = 0; k < n; ++k) area += cross(p[v[k]], p[v[(k + 1) % n]]);
      for (std::uint32_t k = 0; k < n; ++k) sums[v[k]] += area;
    }
  } else {
    // The finest quads: in each parent face, corner k makes (v_k, e_k, f, e_{k-1}).
    const RefinementStep& step = hierarchy.step(levels);
    for (std::uint32_t face = 0; face < step.parent_face_count; ++face) {
      const std::uint32_t first = step.face_offsets[face], n = step.face_offsets[face + 1] - first;
      const std::uint32_t f = step.first_face_vertex() + face;
      for (std::uint32_t k = 0; k < n; ++k)
        add_quad(p, sums, step.face_vertices[first + k], step.face_edges[first + k], f,
                 step.face_edges[first + (k + n - 1) % n]);
    }
  }
  for (Vec3& s : sums) {
    const double length = std::sqrt(squared_norm(s));
    s = length > 0 ? s * (1.0 / length) : Vec3{};
  }
  return sums;
}

}  // namespace isowave::detail
