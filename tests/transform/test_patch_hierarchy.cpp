// A patch's hierarchy against the whole one's: its entries name distinct
// entries of the whole array, and with every entry holding a random vector
// the synthesis of the fine control points of the patch's seed faces equals
// the whole synthesis bit for bit once the patch holds kExactRings rings
// around them (the mapping and the ring count both checked by the values).
#include <algorithm>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "isowave/core/error.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/patch_hierarchy.h"
#include "isowave/transform/wavelet_transform.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

// A 24 x 18 grid with a boundary, some quads split into triangles, pairs of
// triangles merged back as other quads' neighbours, faces shuffled and their
// corners rotated, a few vertices sharp: irregular valences, triangles next
// to quads and a face order unrelated to space.
PolygonMesh irregular_grid(std::uint32_t seed) {
  const PolygonMesh grid = test::quad_grid(24, 18);
  std::mt19937 rng(seed);
  std::vector<std::vector<std::uint32_t>> faces;
  for (std::size_t f = 0; f < grid.face_count(); ++f) {
    const std::uint32_t* v = grid.face_begin(f);
    if (rng() % 4 == 0) {
      faces.push_back({v[0], v[1], v[2]});
      faces.push_back({v[0], v[2], v[3]});
    } else {
      faces.push_back({v[0], v[1], v[2], v[3]});
    }
  }
  std::shuffle(faces.begin(), faces.end(), rng);
  PolygonMesh mesh;
  mesh.positions = grid.positions;
  for (std::vector<std::uint32_t>& face : faces) {
    std::rotate(face.begin(), face.begin() + static_cast<std::ptrdiff_t>(rng() % face.size()), face.end());
    mesh.add_face(face.data(), face.size());
  }
  mesh.sharp.assign(mesh.vertex_count(), 0);
  for (std::size_t v = 7; v < mesh.vertex_count(); v += 97) mesh.sharp[v] = 1;
  return mesh;
}

// Checks one patch grown `rings` around `seeds`; returns whether every fine
// control point of the seeds equals the whole synthesis's.
bool seeds_exact(const PolygonMesh& base, int levels, const std::vector<std::uint32_t>& seeds, int rings,
                 std::uint32_t seed) {
  const SubdivisionHierarchy whole(base, levels);
  const BaseIncidence incidence = base_incidence(base);
  std::vector<std::uint8_t> flags(base.face_count(), 0);
  for (const std::uint32_t f : seeds) flags[f] = 1;
  const PatchHierarchy patch(base, incidence, grow_patch(base, incidence, flags, rings), levels);
  const SubdivisionHierarchy& local = patch.hierarchy();
  const std::vector<std::uint32_t>& entries = patch.entries();
  // Distinct entries of the whole array, the base's first.
  EXPECT_EQ(entries.size(), local.fine_vertex_count());
  EXPECT_EQ(std::set<std::uint32_t>(entries.begin(), entries.end()).size(), entries.size());
  for (std::size_t v = 0; v < local.vertex_count(0); ++v) EXPECT_EQ(entries[v], patch.base_vertices()[v]);
  for (const std::uint32_t e : entries) EXPECT_LT(e, whole.fine_vertex_count());
  // The same coefficients in both, synthesized.
  std::vector<Vec3> all = test::random_vectors(whole.fine_vertex_count(), seed), part(entries.size());
  for (std::size_t k = 0; k < entries.size(); ++k) part[k] = all[entries[k]];
  synthesize(whole, all);
  synthesize(local, part);
  bool exact = true;
  const std::vector<std::uint32_t>& faces = patch.faces();
  for (const std::uint32_t f : seeds) {
    const auto at = static_cast<std::size_t>(std::lower_bound(faces.begin(), faces.end(), f) - faces.begin());
    std::vector<std::uint32_t> mine, theirs;
    for_each_fine_point(local, at, [&](std::size_t k) {
      mine.push_back(entries[k]);
      exact = exact && part[k] == all[entries[k]];
      return true;
    });
    for_each_fine_point(whole, f, [&](std::size_t k) { return theirs.push_back(static_cast<std::uint32_t>(k)), true; });
    EXPECT_EQ(mine, theirs) << "face " << f;
  }
  return exact;
}

TEST(PatchHierarchy, SeedFacesExactOnTheGeneratedCorpus) {
  for (const test::NamedMesh& named : test::generated_corpus()) {
    SCOPED_TRACE(named.name);
    for (int levels = 0; levels <= 3; ++levels)
      for (std::uint32_t f = 0; f < named.mesh.face_count(); f += 3)
        EXPECT_TRUE(seeds_exact(named.mesh, levels, {f}, kExactRings, 11 + f));
  }
}

TEST(PatchHierarchy, SeedFacesExactOnAnIrregularGrid) {
  for (std::uint32_t seed = 1; seed <= 3; ++seed) {
    const PolygonMesh mesh = irregular_grid(seed);
    std::mt19937 rng(seed);
    for (int levels = 1; levels <= 3; ++levels) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " L=" + std::to_string(levels));
      // One face, and a scattered set (patches with holes and several parts).
      std::vector<std::uint32_t> some;
      for (int k = 0; k < 12; ++k) some.push_back(static_cast<std::uint32_t>(rng() % mesh.face_count()));
      std::sort(some.begin(), some.end());
      some.erase(std::unique(some.begin(), some.end()), some.end());
      EXPECT_TRUE(seeds_exact(mesh, levels, {some[0]}, kExactRings, seed));
      EXPECT_TRUE(seeds_exact(mesh, levels, some, kExactRings, seed + 5));
    }
  }
}

// The ring count is what the lifting steps need, not more: one ring fewer
// leaves some seed face inexact.
TEST(PatchHierarchy, FewerRingsAreNotEnough) {
  const PolygonMesh mesh = irregular_grid(4);
  bool some_inexact = false;
  for (std::uint32_t f = 0; f < mesh.face_count() && !some_inexact; f += 17)
    some_inexact = !seeds_exact(mesh, 3, {f}, kExactRings - 1, f);
  EXPECT_TRUE(some_inexact);
}

TEST(PatchHierarchy, GrownPatchesAreManifold) {
  // Two faces sharing only a vertex: the patch takes the fan between them.
  const PolygonMesh grid = test::quad_grid(4, 4);
  const BaseIncidence incidence = base_incidence(grid);
  std::vector<std::uint8_t> flags(grid.face_count(), 0);
  flags[0] = flags[5] = 1;  // (0,0) and (1,1) meet at one corner
  const std::vector<std::uint32_t> faces = grow_patch(grid, incidence, flags, 0);
  EXPECT_EQ(faces, (std::vector<std::uint32_t>{0, 1, 4, 5}));
  EXPECT_NO_THROW(PatchHierarchy(grid, incidence, faces, 2));
}

TEST(PatchHierarchy, IncidenceNumbersEdgesAsTheHierarchy) {
  for (const test::NamedMesh& named : test::generated_corpus()) {
    SCOPED_TRACE(named.name);
    const SubdivisionHierarchy h(named.mesh, 1);
    const BaseIncidence incidence = base_incidence(named.mesh);
    const RefinementStep& s = h.step(1);
    ASSERT_EQ(incidence.edge_count(), s.parent_edge_count);
    EXPECT_EQ(incidence.edge_vertices, s.edge_vertices);
    for (std::size_t e = 0; e < incidence.edge_count(); ++e)
      for (int k = 0; k < 2; ++k) EXPECT_EQ(incidence.edge_faces[2 * e + k] + s.first_face_vertex(), s.edge_faces[2 * e + k]);
  }
}

}  // namespace
}  // namespace isowave
