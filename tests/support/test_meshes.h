#pragma once
// Generated meshes for tests (always available) and access to the shared real
// data in ../shared/data (tests that need it skip when it is absent).
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/volume.h"

namespace isowave::test {

// nx * ny quads over [0, nx] x [0, ny] in the z = 0 plane; wrapping in u
// and/or v makes a cylinder or a torus (embedded in 3D, radii 3 and 1).
PolygonMesh quad_grid(int nx, int ny, bool wrap_u = false, bool wrap_v = false);
PolygonMesh cube();                // 8 vertices, 6 quads: every vertex valence 3
PolygonMesh octahedron();          // 6 vertices, 8 triangles
PolygonMesh pentagonal_prism();    // 2 pentagons, 5 quads
PolygonMesh mixed_disk();          // triangles, quads, a pentagon and a hexagon, one boundary loop
// Quad surface of a 1-voxel-thick slab of (2 g + 1) x 3 voxels with g holes:
// closed, genus g, extraordinary vertices of valence 3, 5 and 6.
PolygonMesh genus_slab(int genus);

struct NamedMesh {
  std::string name;
  PolygonMesh mesh;
};
// The always-available corpus: closed, with boundary, genus > 0, polygonal.
std::vector<NamedMesh> generated_corpus();

// `count` vectors of independent standard normal components (seeded).
std::vector<Vec3> random_vectors(std::size_t count, std::uint32_t seed);

// Moves every vertex by a uniform random offset in [-amount, amount]^3.
void jitter(PolygonMesh& mesh, double amount, std::uint32_t seed);
// The positions of a mesh's sharp vertices, sorted.
std::vector<std::array<double, 3>> sharp_positions(const PolygonMesh& mesh);

// Query points around `mesh` for distance tests: about 500 of its vertices
// (distance 0) and as many jittered off them by up to `near`, 500 uniform
// points in its bounding box grown by its size on every side, and three
// points a thousand sizes away.
std::vector<Vec3> points_around(const PolygonMesh& mesh, double near, std::uint32_t seed);
// Three small triangles far apart (a grid's bin count is capped) and a long
// sliver across them.
PolygonMesh far_apart_and_stretched();

// ../shared/data relative to the repository, or "" if absent.
// A volume of unit spacing at the origin whose sample (i, j, k) is value(i, j, k).
Volume sampled_volume(std::array<std::size_t, 3> dims, const std::function<double(double, double, double)>& value);

std::string shared_data_dir();
// Full path of a file under shared/data, or "" if absent.
std::string shared_data_file(const std::string& relative);

}  // namespace isowave::test

// Skips the current test with a message when a shared data file is missing;
// otherwise sets `path` to it.
#define ISOWAVE_REQUIRE_SHARED_FILE(path, relative)                                              \
  const std::string path = ::isowave::test::shared_data_file(relative);                          \
  if (path.empty()) GTEST_SKIP() << "shared data file " << (relative) << " not found (../shared/data absent)"
