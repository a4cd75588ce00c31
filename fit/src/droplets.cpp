#include "droplets.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/mesh_topology.h"

namespace isowave::wrap {

void Droplets::set_level(const SubdivisionHierarchy& hierarchy, int level, const WrapLevelMesh& mesh) {
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

Droplets find_droplets(const SubdivisionHierarchy& hierarchy, const WrapLevelMesh& mesh,
                       const std::vector<Vec3>& positions, std::size_t max_vertices, double max_radius,
                       Orientation orientation) {
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
  Droplets droplets;
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t r = face_component[f];
    if (open[r] || size[r] > max_vertices || !(radius[r] <= max_radius)) continue;
    if (index[r] < 0) {
      index[r] = static_cast<std::int32_t>(droplets.base_faces.size());
      droplets.base_faces.emplace_back();
    }
    droplets.base_faces[static_cast<std::size_t>(index[r])].push_back(static_cast<std::uint32_t>(f));
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
  droplets.inside_sign.assign(droplets.base_faces.size(), 0.0);
  droplets.base_radius.assign(droplets.base_faces.size(), 0.0);
  for (std::uint32_t r = 0; r < n; ++r) {
    if (index[r] < 0) continue;
    droplets.base_radius[static_cast<std::size_t>(index[r])] = radius[r];
    if (volume[r] != 0)  // outward faces (positive volume) have the lower values outside
      droplets.inside_sign[static_cast<std::size_t>(index[r])] =
          (volume[r] > 0) != (orientation == Orientation::TowardHigher) ? 1.0 : -1.0;
  }
  return droplets;
}

void fit_droplets(const WrapLevelMesh& mesh, const Droplets& droplets, const TrilinearGrid& field, const Box& box,
                  double cell, double iso, const std::vector<Vec3>& source, std::vector<Vec3>& target) {
  // Samples along each ray, then bisection down to 1e-5 cells (the
  // correction's own precision is about 1e-4).
  constexpr int kSamples = 32;
  const double precision = 1e-5 * cell;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, droplets.vertices.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c < r.end(); ++c) {
      const std::vector<std::uint32_t>& list = droplets.vertices[c];
      if (list.empty() || droplets.inside_sign[c] == 0) continue;
      Vec3 centre;
      for (const std::uint32_t v : list) centre += source[v];
      centre *= 1.0 / double(list.size());
      const double sign = droplets.inside_sign[c];
      const auto inside = [&](const Vec3& x) { return sign * (field.sample(x).value - iso) > 0; };
      if (!is_finite(centre) || !inside(centre)) continue;
      const double limit = std::max(3.0 * droplets.base_radius[c], 0.02 * cell);
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

}  // namespace isowave::wrap
