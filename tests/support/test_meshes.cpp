#include "support/test_meshes.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

namespace isowave::test {

PolygonMesh quad_grid(int nx, int ny, bool wrap_u, bool wrap_v) {
  PolygonMesh mesh;
  const int cols = wrap_u ? nx : nx + 1;
  const int rows = wrap_v ? ny : ny + 1;
  const double pi = std::acos(-1.0);
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) {
      if (!wrap_u && !wrap_v) {
        mesh.positions.push_back({double(i), double(j), 0.0});
      } else if (wrap_u && !wrap_v) {
        const double a = 2 * pi * i / nx;
        mesh.positions.push_back({std::cos(a), std::sin(a), double(j) / nx * 2 * pi});
      } else if (!wrap_u && wrap_v) {
        const double a = 2 * pi * j / ny;
        mesh.positions.push_back({double(i) / ny * 2 * pi, std::cos(a), std::sin(a)});
      } else {
        const double a = 2 * pi * i / nx, b = 2 * pi * j / ny;
        mesh.positions.push_back({(3 + std::cos(b)) * std::cos(a), (3 + std::cos(b)) * std::sin(a), std::sin(b)});
      }
    }
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>((j % rows) * cols + (i % cols)); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) mesh.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  return mesh;
}

PolygonMesh cube() {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  mesh.add_face({0, 3, 2, 1});
  mesh.add_face({4, 5, 6, 7});
  mesh.add_face({0, 1, 5, 4});
  mesh.add_face({1, 2, 6, 5});
  mesh.add_face({2, 3, 7, 6});
  mesh.add_face({3, 0, 4, 7});
  return mesh;
}

PolygonMesh octahedron() {
  PolygonMesh mesh;
  mesh.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  mesh.add_face({0, 2, 4});
  mesh.add_face({2, 1, 4});
  mesh.add_face({1, 3, 4});
  mesh.add_face({3, 0, 4});
  mesh.add_face({2, 0, 5});
  mesh.add_face({1, 2, 5});
  mesh.add_face({3, 1, 5});
  mesh.add_face({0, 3, 5});
  return mesh;
}

PolygonMesh pentagonal_prism() {
  PolygonMesh mesh;
  const double pi = std::acos(-1.0);
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < 5; ++k) mesh.positions.push_back({std::cos(2 * pi * k / 5), std::sin(2 * pi * k / 5), double(z)});
  mesh.add_face({4, 3, 2, 1, 0});
  mesh.add_face({5, 6, 7, 8, 9});
  for (std::uint32_t k = 0; k < 5; ++k) mesh.add_face({k, (k + 1) % 5, 5 + (k + 1) % 5, 5 + k});
  return mesh;
}

PolygonMesh mixed_disk() {
  // A 4 x 3 vertex patch with faces of 3, 4, 5 and 6 sides.
  PolygonMesh mesh;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 4; ++i) mesh.positions.push_back({double(i), double(j), 0.1 * ((i * 7 + j * 3) % 5)});
  // Extra vertices on the outer boundary make a pentagon and a hexagon.
  mesh.positions.push_back({1.5, -0.5, 0.0});   // 12: below edge (1,2) of row 0
  mesh.positions.push_back({3.5, 1.0, 0.2});    // 13: right of edge (7,11)
  mesh.add_face({0, 1, 5});                      // triangle
  mesh.add_face({0, 5, 4});                      // triangle
  mesh.add_face({1, 12, 2, 6, 5});               // pentagon
  mesh.add_face({2, 3, 7, 6});                   // quad
  mesh.add_face({4, 5, 6, 10, 9, 8});            // hexagon
  mesh.add_face({6, 7, 13, 11, 10});             // pentagon
  return mesh;
}

PolygonMesh genus_slab(int genus) {
  const int nx = 2 * genus + 1, ny = 3;
  std::vector<std::vector<bool>> solid(nx, std::vector<bool>(ny, true));
  for (int g = 0; g < genus; ++g) solid[2 * g + 1][1] = false;
  PolygonMesh mesh;
  std::map<std::tuple<int, int, int>, std::uint32_t> ids;
  const auto vertex = [&](int x, int y, int z) {
    const auto key = std::make_tuple(x, y, z);
    const auto it = ids.find(key);
    if (it != ids.end()) return it->second;
    const auto id = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.push_back({double(x), double(y), double(z)});
    ids[key] = id;
    return id;
  };
  const auto is_solid = [&](int x, int y) { return x >= 0 && y >= 0 && x < nx && y < ny && solid[x][y]; };
  for (int x = 0; x < nx; ++x)
    for (int y = 0; y < ny; ++y) {
      if (!solid[x][y]) continue;
      // Faces oriented outward (counter-clockwise seen from outside).
      mesh.add_face({vertex(x, y, 0), vertex(x, y + 1, 0), vertex(x + 1, y + 1, 0), vertex(x + 1, y, 0)});
      mesh.add_face({vertex(x, y, 1), vertex(x + 1, y, 1), vertex(x + 1, y + 1, 1), vertex(x, y + 1, 1)});
      if (!is_solid(x - 1, y)) mesh.add_face({vertex(x, y, 0), vertex(x, y, 1), vertex(x, y + 1, 1), vertex(x, y + 1, 0)});
      if (!is_solid(x + 1, y))
        mesh.add_face({vertex(x + 1, y, 0), vertex(x + 1, y + 1, 0), vertex(x + 1, y + 1, 1), vertex(x + 1, y, 1)});
      if (!is_solid(x, y - 1)) mesh.add_face({vertex(x, y, 0), vertex(x + 1, y, 0), vertex(x + 1, y, 1), vertex(x, y, 1)});
      if (!is_solid(x, y + 1))
        mesh.add_face({vertex(x, y + 1, 0), vertex(x, y + 1, 1), vertex(x + 1, y + 1, 1), vertex(x + 1, y + 1, 0)});
    }
  return mesh;
}

std::vector<Vec3> random_vectors(std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Vec3> v(count);
  for (Vec3& p : v) p = {n(rng), n(rng), n(rng)};
  return v;
}

std::vector<NamedMesh> generated_corpus() {
  std::vector<NamedMesh> corpus;
  corpus.push_back({"cube", cube()});
  corpus.push_back({"octahedron", octahedron()});
  corpus.push_back({"pentagonal_prism", pentagonal_prism()});
  corpus.push_back({"mixed_disk", mixed_disk()});
  corpus.push_back({"grid_with_boundary", quad_grid(5, 4)});
  corpus.push_back({"cylinder", quad_grid(8, 3, true, false)});
  corpus.push_back({"torus", quad_grid(8, 6, true, true)});
  corpus.push_back({"genus2_slab", genus_slab(2)});
  corpus.push_back({"genus3_slab", genus_slab(3)});
  PolygonMesh sharp_cube = cube();
  sharp_cube.sharp = {1, 0, 0, 0, 0, 0, 1, 0};
  corpus.push_back({"cube_with_sharp_vertices", sharp_cube});
  PolygonMesh sharp_disk = mixed_disk();
  sharp_disk.sharp.assign(sharp_disk.vertex_count(), 0);
  sharp_disk.sharp[0] = sharp_disk.sharp[5] = 1;  // a boundary corner and an interior sharp vertex
  corpus.push_back({"mixed_disk_with_sharp_vertices", sharp_disk});
  PolygonMesh two_components = cube();
  const PolygonMesh second = octahedron();
  const auto offset = static_cast<std::uint32_t>(two_components.vertex_count());
  for (const Vec3& p : second.positions) two_components.positions.push_back(p + Vec3{3, 0, 0});
  for (std::size_t f = 0; f < second.face_count(); ++f) {
    std::vector<std::uint32_t> face(second.face_begin(f), second.face_begin(f) + second.face_size(f));
    for (std::uint32_t& v : face) v += offset;
    two_components.add_face(face.data(), face.size());
  }
  corpus.push_back({"two_components", two_components});
  return corpus;
}

std::vector<std::array<double, 3>> sharp_positions(const PolygonMesh& mesh) {
  std::vector<std::array<double, 3>> positions;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.is_sharp(v)) positions.push_back({mesh.positions[v].x, mesh.positions[v].y, mesh.positions[v].z});
  std::sort(positions.begin(), positions.end());
  return positions;
}

void jitter(PolygonMesh& mesh, double amount, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> offset(-amount, amount);
  for (Vec3& p : mesh.positions) p += Vec3{offset(rng), offset(rng), offset(rng)};
}

std::vector<Vec3> points_around(const PolygonMesh& mesh, double near, std::uint32_t seed) {
  Vec3 low = mesh.positions[0], high = low;
  for (const Vec3& p : mesh.positions) {
    low = component_min(low, p);
    high = component_max(high, p);
  }
  const Vec3 size = high - low;
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0), offset(-near, near);
  std::vector<Vec3> points;
  for (std::size_t v = 0; v < mesh.positions.size(); v += 1 + mesh.positions.size() / 500) {
    points.push_back(mesh.positions[v]);
    points.push_back(mesh.positions[v] + Vec3{offset(random), offset(random), offset(random)});
  }
  for (int i = 0; i < 500; ++i)
    points.push_back(low - size + Vec3{3 * size.x * unit(random), 3 * size.y * unit(random), 3 * size.z * unit(random)});
  const double far = 1000 * std::max({size.x, size.y, size.z, 1.0});
  points.push_back(low - Vec3{far, 0, 0});
  points.push_back(high + Vec3{far, far, far});
  points.push_back(Vec3{low.x, high.y + far, 0.5 * (low.z + high.z)});
  return points;
}

PolygonMesh far_apart_and_stretched() {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0},     {0.01, 0, 0}, {0, 0.01, 0},    {500, 300, 100}, {500.01, 300, 100},
                    {500, 300.01, 100}, {0, 0, 1}, {500, 300, 101}, {250, 150, 50}};
  mesh.add_face({0, 1, 2});
  mesh.add_face({3, 4, 5});
  mesh.add_face({6, 7, 8});
  return mesh;
}

Volume sampled_volume(std::array<std::size_t, 3> dims, const std::function<double(double, double, double)>& value) {
  Volume volume;
  volume.dims = dims;
  volume.values.resize(volume.sample_count());
  for (std::size_t k = 0; k < dims[2]; ++k)
    for (std::size_t j = 0; j < dims[1]; ++j)
      for (std::size_t i = 0; i < dims[0]; ++i)
        volume.values[volume.index(i, j, k)] = static_cast<float>(value(double(i), double(j), double(k)));
  return volume;
}

std::string shared_data_dir() {
  const std::string dir = ISOWAVE_SHARED_DATA_DIR;
  std::ifstream probe(dir + "/README.md");
  return probe ? dir : std::string();
}

std::string shared_data_file(const std::string& relative) {
  const std::string dir = shared_data_dir();
  if (dir.empty()) return {};
  const std::string path = dir + "/" + relative;
  std::ifstream probe(path);
  return probe ? path : std::string();
}

}  // namespace isowave::test
