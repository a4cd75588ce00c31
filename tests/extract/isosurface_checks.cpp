// Checks shared by the isosurface tests (see isosurface_checks.h).
#include "isosurface_checks.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace isowave::test {

// Box face planes a world position lies on (bit 2 axis + side).
int box_faces_of(const Volume& volume, const Vec3& p) {
  int faces = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double low = volume.origin[axis];
    const double high = low + volume.spacing[axis] * static_cast<double>(volume.dims[axis] - 1);
    const double tolerance = 1e-9 * (1 + std::abs(high));
    if (std::abs(p[axis] - low) <= tolerance) faces |= 1 << (2 * axis);
    if (std::abs(p[axis] - high) <= tolerance) faces |= 1 << (2 * axis + 1);
  }
  return faces;
}

// Boundary edges (edges of exactly one face), counted here from scratch.
std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary_edges(const PolygonMesh& mesh) {
  std::vector<std::uint64_t> keys;
  keys.reserve(mesh.face_vertices.size());
  for (std::size_t f = 0; f < mesh.face_count(); ++f)
    for (std::uint32_t i = 0; i < mesh.face_size(f); ++i) {
      const std::uint32_t a = mesh.face_begin(f)[i], b = mesh.face_begin(f)[(i + 1) % mesh.face_size(f)];
      keys.push_back((std::uint64_t{std::min(a, b)} << 32) | std::max(a, b));
    }
  std::sort(keys.begin(), keys.end());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> result;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    if (j - i == 1) result.emplace_back(static_cast<std::uint32_t>(keys[i] >> 32), static_cast<std::uint32_t>(keys[i]));
    i = j;
  }
  return result;
}

// Every boundary edge has both endpoints on one common face of the volume box.
void expect_boundary_on_box(const Volume& volume, const PolygonMesh& mesh, const std::string& name) {
  std::size_t off_box = 0;
  for (const auto& [a, b] : boundary_edges(mesh))
    if ((box_faces_of(volume, mesh.positions[a]) & box_faces_of(volume, mesh.positions[b])) == 0) ++off_box;
  EXPECT_EQ(off_box, 0u) << name << ": boundary edges not on a face of the volume box";
}

// Area-weighted agreement of triangle normals with -gradient of the
// trilinear interpolant at the triangle's centroid: the fraction of area
// (where the gradient is not zero) whose normal points toward lower values.
double fraction_toward_lower(const Volume& volume, const PolygonMesh& mesh) {
  double agree = 0, total = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* t = mesh.face_begin(f);
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const Vec3 area_normal = cross(b - a, c - a) * 0.5;
    const Vec3 centre = (a + b + c) * (1.0 / 3.0);
    double index[3], local[3];
    std::size_t cell[3];
    for (int axis = 0; axis < 3; ++axis) {
      index[axis] = (centre[axis] - volume.origin[axis]) / volume.spacing[axis];
      cell[axis] = std::min<std::size_t>(static_cast<std::size_t>(std::max(0.0, std::floor(index[axis]))),
                                         volume.dims[axis] - 2);
      local[axis] = index[axis] - static_cast<double>(cell[axis]);
    }
    double corner[2][2][2];
    bool finite = true;
    for (int dz = 0; dz < 2; ++dz)
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          corner[dz][dy][dx] = volume.at(cell[0] + dx, cell[1] + dy, cell[2] + dz);
          finite = finite && std::isfinite(corner[dz][dy][dx]);
        }
    if (!finite) continue;
    const auto lerp = [](double p, double q, double s) { return p + s * (q - p); };
    const double u = local[0], v = local[1], w = local[2];
    // Partial derivatives of the trilinear interpolant (in index units).
    const double gx = lerp(lerp(corner[0][0][1] - corner[0][0][0], corner[0][1][1] - corner[0][1][0], v),
                           lerp(corner[1][0][1] - corner[1][0][0], corner[1][1][1] - corner[1][1][0], v), w);
    const double gy = lerp(lerp(corner[0][1][0] - corner[0][0][0], corner[0][1][1] - corner[0][0][1], u),
                           lerp(corner[1][1][0] - corner[1][0][0], corner[1][1][1] - corner[1][0][1], u), w);
    const double gz = lerp(lerp(corner[1][0][0] - corner[0][0][0], corner[1][0][1] - corner[0][0][1], u),
                           lerp(corner[1][1][0] - corner[0][1][0], corner[1][1][1] - corner[0][1][1], u), v);
    const Vec3 gradient{gx / volume.spacing.x, gy / volume.spacing.y, gz / volume.spacing.z};
    const double alignment = dot(area_normal, gradient);
    if (alignment == 0) continue;
    const double area = norm(area_normal);
    total += area;
    if (alignment < 0) agree += area;
  }
  return total > 0 ? agree / total : 0;
}

}  // namespace isowave::test
