#include "simplify_test_meshes.h"

#include <cmath>
#include <map>
#include <utility>

namespace isowave::test {

PolygonMesh fan_triangulate(const PolygonMesh& mesh) {
  PolygonMesh result;
  result.positions = mesh.positions;
  result.sharp = mesh.sharp;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < mesh.face_size(f); ++k) result.add_face({face[0], face[k], face[k + 1]});
  }
  return result;
}

PolygonMesh icosphere(int levels) {
  PolygonMesh mesh = octahedron();
  for (int level = 0; level < levels; ++level) {
    PolygonMesh finer;
    finer.positions = mesh.positions;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto found = midpoints.find(key);
      if (found != midpoints.end()) return found->second;
      const std::uint32_t index = static_cast<std::uint32_t>(finer.positions.size());
      finer.positions.push_back((mesh.positions[a] + mesh.positions[b]) * 0.5);
      midpoints.emplace(key, index);
      return index;
    };
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      const std::uint32_t* t = mesh.face_begin(f);
      const std::uint32_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      finer.add_face({t[0], ab, ca});
      finer.add_face({t[1], bc, ab});
      finer.add_face({t[2], ca, bc});
      finer.add_face({ab, bc, ca});
    }
    mesh = std::move(finer);
  }
  for (Vec3& p : mesh.positions) p = normalized(p);
  return mesh;
}

PolygonMesh tetrahedron() {
  PolygonMesh mesh;
  mesh.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  mesh.add_face({0, 1, 2});
  mesh.add_face({0, 2, 3});
  mesh.add_face({0, 3, 1});
  mesh.add_face({1, 3, 2});
  return mesh;
}

PolygonMesh wheel(std::uint32_t spokes) {
  PolygonMesh mesh;
  mesh.positions.push_back({0, 0, 0});
  for (int radius = 1; radius <= 2; ++radius)
    for (std::uint32_t k = 0; k < spokes; ++k) {
      const double angle = 2 * M_PI * (k + 0.5 * (radius - 1)) / spokes;
      mesh.positions.push_back({radius * std::cos(angle), radius * std::sin(angle), 0});
    }
  for (std::uint32_t k = 0; k < spokes; ++k) {
    const std::uint32_t ring = 1 + k, ring_next = 1 + (k + 1) % spokes;
    const std::uint32_t outer = 1 + spokes + k, outer_next = 1 + spokes + (k + 1) % spokes;
    mesh.add_face({0, ring, ring_next});
    mesh.add_face({ring, outer, ring_next});
    mesh.add_face({ring_next, outer, outer_next});
  }
  return mesh;
}

}  // namespace isowave::test
