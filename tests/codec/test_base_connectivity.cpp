// The base mesh connectivity coder: exact round trips of canonical meshes of
// every kind (polygons, boundaries, components, genus, sharp flags, random
// meshes), canonical_order() as a fixed point that keeps the mesh, and hostile
// streams (every truncation, random corruption, lying counts) that decode to a
// manifold mesh or throw Error(Format).
#include <algorithm>
#include <array>
#include <chrono>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "base_connectivity.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/mesh_topology.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

using detail::canonical_order;
using detail::connectivity_counts;
using detail::ConnectivityCounts;
using detail::decode_connectivity;
using detail::encode_connectivity;
using detail::is_canonical;

std::string encode(const PolygonMesh& canonical) {
  std::string bytes;
  detail::RangeEncoder rc(bytes);
  encode_connectivity(rc, canonical);
  rc.finish();
  return bytes;
}

PolygonMesh decode(const std::string& bytes, const ConnectivityCounts& counts) {
  detail::RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  return decode_connectivity(rc, counts);
}

void expect_same_connectivity(const PolygonMesh& expected, const PolygonMesh& actual) {
  EXPECT_EQ(actual.vertex_count(), expected.vertex_count());
  EXPECT_EQ(actual.face_offsets, expected.face_offsets);
  EXPECT_EQ(actual.face_vertices, expected.face_vertices);
  EXPECT_EQ(actual.sharp, expected.sharp);
}

// Each face as its corners' positions, rotated to start at the smallest:
// the mesh's faces independent of any numbering.
std::vector<std::vector<std::array<double, 3>>> faces_by_position(const PolygonMesh& mesh) {
  std::vector<std::vector<std::array<double, 3>>> faces;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    std::vector<std::array<double, 3>> face;
    for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) {
      const Vec3& p = mesh.positions[mesh.face_begin(f)[k]];
      face.push_back({p.x, p.y, p.z});
    }
    std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
    faces.push_back(face);
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

// The same mesh with vertices and faces in random order and every face
// rotated by a random amount.
PolygonMesh shuffled(const PolygonMesh& mesh, std::mt19937& rng) {
  std::vector<std::uint32_t> vertex_order(mesh.vertex_count()), face_order(mesh.face_count());
  for (std::uint32_t i = 0; i < vertex_order.size(); ++i) vertex_order[i] = i;
  for (std::uint32_t i = 0; i < face_order.size(); ++i) face_order[i] = i;
  std::shuffle(vertex_order.begin(), vertex_order.end(), rng);
  std::shuffle(face_order.begin(), face_order.end(), rng);
  PolygonMesh out;
  out.positions.resize(mesh.vertex_count());
  if (!mesh.sharp.empty()) out.sharp.resize(mesh.vertex_count());
  for (std::uint32_t v = 0; v < vertex_order.size(); ++v) {
    out.positions[vertex_order[v]] = mesh.positions[v];
    if (!mesh.sharp.empty()) out.sharp[vertex_order[v]] = mesh.sharp[v];
  }
  for (std::uint32_t f : face_order) {
    std::vector<std::uint32_t> face;
    for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) face.push_back(vertex_order[mesh.face_begin(f)[k]]);
    std::rotate(face.begin(), face.begin() + static_cast<long>(rng() % face.size()), face.end());
    out.add_face(face.data(), face.size());
  }
  return out;
}

// A random polygonal manifold: a quad grid, cylinder or torus with some quad
// pairs merged into hexagons, some quads split into triangles, some faces
// removed (holes), sometimes a second component, random sharp flags, all in
// random order. Retries until require_manifold() accepts it.
PolygonMesh random_mesh(std::mt19937& rng) {
  for (;;) {
    const int nx = 3 + static_cast<int>(rng() % 9), ny = 3 + static_cast<int>(rng() % 9);
    const bool wrap_u = rng() % 2, wrap_v = rng() % 2;
    const PolygonMesh grid = test::quad_grid(nx, ny, wrap_u, wrap_v);
    const int cols = wrap_u ? nx : nx + 1, rows = wrap_v ? ny : ny + 1;
    const auto id = [&](int i, int j) { return static_cast<std::uint32_t>((j % rows) * cols + (i % cols)); };
    PolygonMesh mesh;
    mesh.positions = grid.positions;
    std::vector<bool> taken(static_cast<std::size_t>(nx * ny), false);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (taken[static_cast<std::size_t>(j * nx + i)]) continue;
        const unsigned roll = rng() % 20;
        if (roll == 0) continue;  // a hole
        if (roll < 3 && i + 1 < nx && !taken[static_cast<std::size_t>(j * nx + i + 1)]) {
          taken[static_cast<std::size_t>(j * nx + i + 1)] = true;
          mesh.add_face({id(i, j), id(i + 1, j), id(i + 2, j), id(i + 2, j + 1), id(i + 1, j + 1), id(i, j + 1)});
        } else if (roll < 6) {
          mesh.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
          mesh.add_face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        } else {
          mesh.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
        }
      }
    if (mesh.face_count() == 0) continue;
    remove_unreferenced_vertices(mesh);
    if (rng() % 3 == 0) {  // a second component: a pentagonal prism far away
      const PolygonMesh prism = test::pentagonal_prism();
      const auto offset = static_cast<std::uint32_t>(mesh.vertex_count());
      for (const Vec3& p : prism.positions) mesh.positions.push_back(p + Vec3{100, 0, 0});
      for (std::size_t f = 0; f < prism.face_count(); ++f) {
        std::vector<std::uint32_t> face(prism.face_begin(f), prism.face_begin(f) + prism.face_size(f));
        for (std::uint32_t& v : face) v += offset;
        mesh.add_face(face.data(), face.size());
      }
    }
    if (rng() % 2) {
      mesh.sharp.assign(mesh.vertex_count(), 0);
      for (auto& flag : mesh.sharp) flag = rng() % 7 == 0;
    }
    try {
      require_manifold(mesh, "random mesh");
    } catch (const Error&) {
      continue;
    }
    return shuffled(mesh, rng);
  }
}

std::vector<test::NamedMesh> corpus() {
  std::vector<test::NamedMesh> meshes = test::generated_corpus();
  meshes.push_back({"large_torus", test::quad_grid(40, 30, true, true)});
  meshes.push_back({"large_disc", test::quad_grid(30, 20)});
  return meshes;
}

TEST(BaseConnectivity, RoundTripIsExactOnEveryKindOfMesh) {
  for (const auto& [name, mesh] : corpus()) {
    SCOPED_TRACE(name);
    const PolygonMesh canonical = canonical_order(mesh).mesh;
    const PolygonMesh decoded = decode(encode(canonical), connectivity_counts(canonical));
    expect_same_connectivity(canonical, decoded);
  }
}

TEST(BaseConnectivity, RoundTripIsExactOnRandomMeshes) {
  std::mt19937 rng(34);
  for (int i = 0; i < 200; ++i) {
    SCOPED_TRACE(i);
    const PolygonMesh canonical = canonical_order(random_mesh(rng)).mesh;
    const PolygonMesh decoded = decode(encode(canonical), connectivity_counts(canonical));
    expect_same_connectivity(canonical, decoded);
    if (HasFailure()) break;
  }
}

TEST(BaseConnectivity, CanonicalOrderKeepsTheMeshAndIsAFixedPoint) {
  std::mt19937 rng(7);
  std::vector<PolygonMesh> meshes;
  for (const auto& named : corpus()) meshes.push_back(shuffled(named.mesh, rng));
  for (int i = 0; i < 50; ++i) meshes.push_back(random_mesh(rng));
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    SCOPED_TRACE(i);
    const PolygonMesh& mesh = meshes[i];
    const detail::CanonicalMesh once = canonical_order(mesh);
    EXPECT_EQ(faces_by_position(once.mesh), faces_by_position(mesh));
    EXPECT_EQ(test::sharp_positions(once.mesh), test::sharp_positions(mesh));
    EXPECT_NO_THROW(require_manifold(once.mesh, "canonical mesh"));
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
      EXPECT_EQ(once.mesh.positions[once.new_of_old[v]].x, mesh.positions[v].x);
    const PolygonMesh twice = canonical_order(once.mesh).mesh;
    EXPECT_EQ(twice.face_offsets, once.mesh.face_offsets);
    EXPECT_EQ(twice.face_vertices, once.mesh.face_vertices);
    EXPECT_TRUE(is_canonical(once.mesh));
    if (HasFailure()) break;
  }
}

// On a closed mesh every vertex is first met in a face, so the canonical
// numbering is the order of first appearance in the face list.
TEST(BaseConnectivity, ClosedMeshesAreNumberedInOrderOfFirstAppearance) {
  for (const PolygonMesh& mesh : {test::genus_slab(2), test::quad_grid(9, 7, true, true), test::octahedron()}) {
    const PolygonMesh canonical = canonical_order(mesh).mesh;
    std::uint32_t next = 0;
    for (std::uint32_t v : canonical.face_vertices) {
      EXPECT_LE(v, next);
      if (v == next) ++next;
    }
    EXPECT_EQ(next, canonical.vertex_count());
  }
}

TEST(BaseConnectivity, EncoderRejectsAMeshNotInCanonicalOrder) {
  PolygonMesh mesh = canonical_order(test::genus_slab(2)).mesh;
  std::reverse(mesh.face_vertices.begin(), mesh.face_vertices.begin() + mesh.face_size(0));
  std::reverse(mesh.face_vertices.begin() + mesh.face_offsets[1], mesh.face_vertices.end());
  for (std::uint32_t& v : mesh.face_vertices) v = static_cast<std::uint32_t>(mesh.vertex_count() - 1 - v);
  EXPECT_FALSE(is_canonical(mesh));
  std::string bytes;
  detail::RangeEncoder rc(bytes);
  try {
    encode_connectivity(rc, mesh);
    FAIL() << "a mesh out of canonical order was encoded";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::InvalidArgument);
  }
}

// A regular quad torus has nearly no connectivity information: well under
// one bit per vertex (a face-size-and-index coder needs ~30).
TEST(BaseConnectivity, RegularQuadMeshCostsUnderOneBitPerVertex) {
  const PolygonMesh canonical = canonical_order(test::quad_grid(64, 64, true, true)).mesh;
  const std::string bytes = encode(canonical);
  EXPECT_LT(8.0 * static_cast<double>(bytes.size()) / static_cast<double>(canonical.vertex_count()), 1.0);
}

// Decoding takes time linear in the mesh: four times the faces in under
// eight times the time (a ratio, so the host's speed does not matter; both
// meshes beyond the caches, the best of five runs, so that a busy host or
// the smaller mesh alone fitting in cache does not decide it).
TEST(BaseConnectivity, DecodingTimeIsLinear) {
  const auto seconds_to_decode = [](int n) {
    const PolygonMesh canonical = canonical_order(test::quad_grid(n, n, true, true)).mesh;
    const std::string bytes = encode(canonical);
    double best = 1e30;
    for (int run = 0; run < 5; ++run) {
      const auto start = std::chrono::steady_clock::now();
      const PolygonMesh decoded = decode(bytes, connectivity_counts(canonical));
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      EXPECT_EQ(decoded.face_vertices, canonical.face_vertices);
    }
    return best;
  };
  const double small = seconds_to_decode(300), large = seconds_to_decode(600);
  EXPECT_LT(large, 8 * small) << small << " s for 90,000 faces, " << large << " s for 360,000";
}

// Decoding a hostile stream either gives a mesh require_manifold() accepts
// or throws Error(Format); never a crash, a hang or another error.
void expect_manifold_or_format_error(const std::string& bytes, const ConnectivityCounts& counts) {
  try {
    const PolygonMesh mesh = decode(bytes, counts);
    EXPECT_NO_THROW(require_manifold(mesh, "decoded mesh"));
    EXPECT_EQ(mesh.vertex_count(), counts.vertices);
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::Format) << error.what();
  }
}

TEST(BaseConnectivity, EveryTruncationDecodesOrThrowsFormat) {
  std::mt19937 rng(11);
  for (const PolygonMesh& mesh : {test::genus_slab(3), random_mesh(rng), test::mixed_disk()}) {
    const PolygonMesh canonical = canonical_order(mesh).mesh;
    const std::string bytes = encode(canonical);
    for (std::size_t length = 0; length < bytes.size(); ++length)
      expect_manifold_or_format_error(bytes.substr(0, length), connectivity_counts(canonical));
  }
}

TEST(BaseConnectivity, CorruptBytesDecodeOrThrowFormat) {
  std::mt19937 rng(12);
  for (int i = 0; i < 400; ++i) {
    const PolygonMesh canonical = canonical_order(i % 4 == 0 ? test::genus_slab(2) : random_mesh(rng)).mesh;
    std::string bytes = encode(canonical);
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < flips; ++k) bytes[rng() % bytes.size()] = static_cast<char>(rng());
    expect_manifold_or_format_error(bytes, connectivity_counts(canonical));
    if (HasFailure()) break;
  }
}

// Counts the stream cannot hold are not allocated: the decoder stops where
// the bytes end.
TEST(BaseConnectivity, LyingCountsThrowFormatWithoutAllocating) {
  const PolygonMesh canonical = canonical_order(test::genus_slab(2)).mesh;
  const std::string bytes = encode(canonical);
  const std::uint64_t huge = std::uint64_t{1} << 40;
  for (const ConnectivityCounts& counts :
       {ConnectivityCounts{huge, huge, huge}, ConnectivityCounts{canonical.vertex_count() - 1, huge, huge},
        ConnectivityCounts{0, 0, 0}}) {
    try {
      decode(bytes, counts);
      FAIL() << "decoded with the wrong counts";
    } catch (const Error& error) {
      EXPECT_EQ(error.kind(), ErrorKind::Format);
    }
  }
  std::string noise(4096, '\0');
  std::mt19937 rng(5);
  for (char& c : noise) c = static_cast<char>(rng());
  expect_manifold_or_format_error(noise, {huge, huge, huge});
}

// Real meshes: triangle meshes with many holes, genus 9, sharp CAD edges.
TEST(BaseConnectivity, RoundTripIsExactOnRealMeshes) {
  for (const char* name : {"meshes/elephant_106holes.off", "meshes/casting_genus9.off", "meshes/double_torus_quads.off",
                           "meshes/fandisk_sharp.obj"}) {
    ISOWAVE_REQUIRE_SHARED_FILE(path, name);
    SCOPED_TRACE(name);
    const PolygonMesh mesh = read_mesh(path);
    require_manifold(mesh, name);
    const PolygonMesh canonical = canonical_order(mesh).mesh;
    const std::string bytes = encode(canonical);
    expect_same_connectivity(canonical, decode(bytes, connectivity_counts(canonical)));
    // The bound for a base mesh: at most 8 bits per vertex (the
    // 1.0 format's face-size-and-index coding spends 28-29).
    EXPECT_LT(8.0 * static_cast<double>(bytes.size()) / static_cast<double>(mesh.vertex_count()), 8.0);
  }
}

}  // namespace
}  // namespace isowave
