// The topology tolerance (issue #35) on fields whose handles, tunnels,
// specks and bubbles are known by construction: the genus and components of
// the result are counted on the returned mesh (summarize_topology), never
// from the clean-up's own counters.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/topology_tolerance.h"
#include "isowave/extract/volume_io.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

constexpr double kPi = 3.14159265358979323846;

Volume filled_volume(std::array<std::size_t, 3> dims, float value) {
  Volume volume;
  volume.dims = dims;
  volume.values.assign(volume.sample_count(), value);
  return volume;
}

// A square ring of samples of side `side` in the plane z = k, one sample
// thick, set to `value` (the rest of the field is below iso 0).
void add_frame(Volume& volume, std::size_t i0, std::size_t j0, std::size_t k, std::size_t side, float value) {
  for (std::size_t d = 0; d <= side; ++d) {
    volume.values[volume.index(i0 + d, j0, k)] = value;
    volume.values[volume.index(i0 + d, j0 + side, k)] = value;
    volume.values[volume.index(i0, j0 + d, k)] = value;
    volume.values[volume.index(i0 + side, j0 + d, k)] = value;
  }
}

// max(field, rho - distance to the circle of radius `radius` about `centre` in a z-plane).
void add_torus(Volume& volume, Vec3 centre, double radius, double rho) {
  for (std::size_t k = 0; k < volume.dims[2]; ++k)
    for (std::size_t j = 0; j < volume.dims[1]; ++j)
      for (std::size_t i = 0; i < volume.dims[0]; ++i) {
        const double x = double(i) - centre.x, y = double(j) - centre.y, z = double(k) - centre.z;
        const double ring = std::hypot(x, y) - radius;
        float& v = volume.values[volume.index(i, j, k)];
        v = std::max(v, static_cast<float>(rho - std::hypot(ring, z)));
      }
}

void add_ball(Volume& volume, Vec3 centre, double radius) {
  for (std::size_t k = 0; k < volume.dims[2]; ++k)
    for (std::size_t j = 0; j < volume.dims[1]; ++j)
      for (std::size_t i = 0; i < volume.dims[0]; ++i) {
        const double d = norm(Vec3{double(i), double(j), double(k)} - centre);
        float& v = volume.values[volume.index(i, j, k)];
        v = std::max(v, static_cast<float>(radius - d));
      }
}

TopologySummary topology_at(const Volume& volume, double cells, Isosurface* out = nullptr) {
  IsosurfaceOptions options;
  options.topology_tolerance = cells;
  Isosurface surface = extract_isosurface(volume, options);
  require_manifold(surface.mesh, "tolerance result");
  const TopologySummary topology = summarize_topology(surface.mesh);
  if (out) *out = std::move(surface);
  return topology;
}

// Two one-sample frames with necks 2 pi t = 1.26 and 2.86 cells (crossings
// at t = 0.2 and 0.455 of the edge) and a torus of tube radius 2.5 cells
// (meridian 15.7 cells): T = 2 cuts the first frame only, T = 4 both, and the
// torus stays bit for bit.
Volume frames_and_torus() {
  Volume volume = filled_volume({60, 26, 13}, -4.0f);
  add_frame(volume, 2, 2, 6, 8, 1.0f);         // t = 1 / 5
  add_frame(volume, 14, 2, 6, 8, 10.0f / 3);   // t = (10/3) / (10/3 + 4) = 0.4545
  add_torus(volume, {42, 13, 6}, 8, 2.5);
  return volume;
}

std::vector<Vec3> sorted_positions_beyond(const PolygonMesh& mesh, double x) {
  std::vector<Vec3> positions;
  for (const Vec3& p : mesh.positions)
    if (p.x > x) positions.push_back(p);
  std::sort(positions.begin(), positions.end(),
            [](const Vec3& a, const Vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); });
  return positions;
}

TEST(TopologyTolerance, CutsHandlesWithNecksUnderTAndKeepsTheOthers) {
  const Volume volume = frames_and_torus();
  Isosurface exact, two, four;
  const TopologySummary t0 = topology_at(volume, 0, &exact);
  ASSERT_EQ(t0.genus, 3);  // the thin frames really are closed rings
  ASSERT_EQ(t0.components, 3u);
  const TopologySummary t2 = topology_at(volume, 2, &two);
  EXPECT_EQ(t2.genus, 2);
  EXPECT_EQ(t2.components, 3u);
  EXPECT_EQ(two.report.topology.handles_cut, 1u);
  const TopologySummary t4 = topology_at(volume, 4, &four);
  EXPECT_EQ(t4.genus, 1);
  EXPECT_EQ(t4.components, 3u);
  EXPECT_EQ(four.report.topology.handles_cut, 2u);
  // The torus (x > 30) is untouched.
  EXPECT_EQ(sorted_positions_beyond(four.mesh, 30), sorted_positions_beyond(exact.mesh, 30));
  // The surface moved less than T (D in cells, both ways), and the report's counts are the mesh's.
  EXPECT_GT(four.report.topology_d, 0.0);
  EXPECT_LT(four.report.topology_d, 4.0);
  EXPECT_EQ(four.report.after.genus, t4.genus);
  EXPECT_EQ(four.report.before.genus, t0.genus);
}

TEST(TopologyTolerance, FillsTunnelsWithNecksUnderT) {
  // The complement of a frame: a ring-shaped cavity (a torus, genus 1) in a solid.
  Volume volume = filled_volume({16, 16, 9}, 4.0f);
  add_frame(volume, 3, 3, 4, 9, -1.0f);  // t = 4 / 5 from the solid side: 0.2 from the ring's samples
  EXPECT_EQ(topology_at(volume, 0).genus, 1);
  EXPECT_EQ(topology_at(volume, 1).genus, 1);
  Isosurface two;
  const TopologySummary t2 = topology_at(volume, 2, &two);
  EXPECT_EQ(t2.genus, 0);
  EXPECT_EQ(t2.components, 1u);  // the cavity stays, as a ball
  EXPECT_EQ(two.report.topology.tunnels_filled, 1u);
  EXPECT_EQ(two.report.topology.handles_cut, 0u);
}

// A sponge: a solid slab pierced by three straight tunnels (genus 3), two of
// them one sample wide with necks of 1.26 and 2.86 cells, one 5 cells wide.
TEST(TopologyTolerance, FillsTheSpongesTunnelsUnderTAndKeepsTheWideOne) {
  Volume volume = filled_volume({44, 20, 17}, -4.0f);
  for (std::size_t k = 4; k <= 12; ++k)
    for (std::size_t j = 3; j <= 16; ++j)
      for (std::size_t i = 3; i <= 40; ++i) volume.values[volume.index(i, j, k)] = 4.0f;
  for (std::size_t k = 4; k <= 12; ++k) {  // crossings at -v / (4 - v) from a tunnel's samples
    volume.values[volume.index(9, 10, k)] = -1.0f;         // 0.2
    volume.values[volume.index(19, 10, k)] = -10.0f / 3;   // 0.4545
  }
  for (std::size_t k = 4; k <= 12; ++k)  // a wide tunnel, radius 2.5 cells
    for (std::size_t j = 0; j < 20; ++j)
      for (std::size_t i = 26; i < 38; ++i) {
        const double r = std::hypot(double(i) - 32, double(j) - 10);
        float& v = volume.values[volume.index(i, j, k)];
        v = std::min(v, static_cast<float>(r - 2.5));
      }
  ASSERT_EQ(topology_at(volume, 0).genus, 3);
  ASSERT_EQ(topology_at(volume, 0).components, 1u);
  Isosurface two, four;
  EXPECT_EQ(topology_at(volume, 2, &two).genus, 2);
  EXPECT_EQ(two.report.topology.tunnels_filled, 1u);
  const TopologySummary t4 = topology_at(volume, 4, &four);
  EXPECT_EQ(t4.genus, 1);
  EXPECT_EQ(t4.components, 1u);
  EXPECT_EQ(four.report.topology.tunnels_filled, 2u);
  EXPECT_EQ(four.report.topology.handles_cut, 0u);
}

TEST(TopologyTolerance, RemovesSpecksAndBubblesUnderTAcross) {
  Volume volume = filled_volume({40, 20, 20}, -1.0f);
  volume.values[volume.index(5, 5, 5)] = 1.0f;  // a speck 1 cell across
  add_ball(volume, {15, 10, 10}, 2.5);          // 5 cells across
  for (std::size_t k = 3; k < 17; ++k)          // a solid block with a one-sample bubble
    for (std::size_t j = 3; j < 17; ++j)
      for (std::size_t i = 24; i < 37; ++i) volume.values[volume.index(i, j, k)] = 1.0f;
  volume.values[volume.index(30, 10, 10)] = -1.0f;
  EXPECT_EQ(topology_at(volume, 0).components, 4u);
  EXPECT_EQ(topology_at(volume, 0.9).components, 4u);
  Isosurface two;
  EXPECT_EQ(topology_at(volume, 2, &two).components, 2u);
  EXPECT_EQ(two.report.topology.specks_removed, 1u);
  EXPECT_EQ(two.report.topology.bubbles_filled, 1u);
  EXPECT_EQ(topology_at(volume, 4).components, 2u);  // the ball stays
  EXPECT_EQ(topology_at(volume, 6).components, 1u);  // now it goes too
}

TEST(TopologyTolerance, SurfacesWithoutSmallFeaturesComeOutBitIdentical) {
  for (const char* name : {"sphere", "torus", "genus3"}) {
    const Volume volume = make_builtin_field(name, 64);
    Isosurface exact, tolerant;
    topology_at(volume, 0, &exact);
    topology_at(volume, 4, &tolerant);
    EXPECT_EQ(tolerant.report.topology.samples_changed, 0u) << name;
    EXPECT_EQ(tolerant.mesh.positions, exact.mesh.positions) << name;
    EXPECT_EQ(tolerant.mesh.face_vertices, exact.mesh.face_vertices) << name;
  }
}

// Shared data: hydrogen has no feature under 4 cells; the engine CT only
// sub-cell bubbles (its genus 18 is all thick handles).
TEST(TopologyTolerance, HydrogenStaysBitIdenticalAndTheEngineLosesOnlyBubbles) {
  ISOWAVE_REQUIRE_SHARED_FILE(hydrogen_path, "volumes/hydrogen.vti");
  const Volume hydrogen = read_volume(hydrogen_path);
  IsosurfaceOptions options;
  options.iso = 0.05;
  const Isosurface exact = extract_isosurface(hydrogen, options);
  options.topology_tolerance = 4;
  const Isosurface tolerant = extract_isosurface(hydrogen, options);
  EXPECT_EQ(tolerant.report.topology.samples_changed, 0u);
  EXPECT_EQ(tolerant.mesh.positions, exact.mesh.positions);
  EXPECT_EQ(tolerant.mesh.face_vertices, exact.mesh.face_vertices);

  ISOWAVE_REQUIRE_SHARED_FILE(engine_path, "volumes/engine_256x256x128.nrrd");
  const Volume engine = read_volume(engine_path);
  options.iso = 100;
  const Isosurface engine_surface = extract_isosurface(engine, options);
  const TopologySummary before = summarize_topology(contour_volume(engine, 100));
  const TopologySummary after = summarize_topology(engine_surface.mesh);
  const TopologyCleanup& t = engine_surface.report.topology;
  EXPECT_EQ(t.handles_cut + t.tunnels_filled + t.specks_removed, 0u);
  EXPECT_LE(t.bubbles_filled, 3u);
  EXPECT_EQ(after.genus, before.genus);
  EXPECT_EQ(after.components + t.bubbles_filled, before.components);
  EXPECT_LT(engine_surface.report.topology_d, 0.01);
}

// Random fields: whatever the tolerance changes, it adds no topology (no
// handle, no component), only the counted samples differ, each across the
// isovalue, and the result does not depend on the thread count.
TEST(TopologyTolerance, NoiseGainsNoTopologyAndOnlyCountedSamplesChange) {
  std::mt19937 rng(35);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  Volume noise = filled_volume({36, 32, 28}, 0.0f);
  for (float& v : noise.values) v = normal(rng);
  const TopologySummary before = topology_at(noise, 0);
  for (const double cells : {1.0, 3.0, 6.0}) {
    Volume cleaned = noise;
    IsosurfaceOptions options;
    options.topology_tolerance = cells;
    const Isosurface surface = extract_isosurface_in_place(cleaned, options);
    require_manifold(surface.mesh, "noise");
    const TopologySummary after = summarize_topology(surface.mesh);
    EXPECT_LT(after.genus, before.genus) << cells;
    // Cuts and fills split and merge nothing; each speck or bubble takes one component (or two, if it
    // joins what was on both sides of it).
    const TopologyCleanup& t = surface.report.topology;
    EXPECT_LE(after.components + t.specks_removed + t.bubbles_filled, before.components) << cells;
    EXPECT_GT(t.specks_removed + t.bubbles_filled, 0u) << cells;
    EXPECT_LT(surface.report.topology_d, cells) << cells;  // D of the clean-up, cells
    std::size_t changed = 0;
    for (std::size_t p = 0; p < noise.sample_count(); ++p) {
      if (cleaned.values[p] == noise.values[p]) continue;
      ++changed;
      EXPECT_NE(cleaned.values[p] >= 0, noise.values[p] >= 0) << p;
    }
    EXPECT_EQ(changed, surface.report.topology.samples_changed);
    EXPECT_GT(changed, 0u);
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    Volume serial = noise;
    clean_topology(serial, 0.0, cells);
    EXPECT_EQ(serial.values, cleaned.values) << cells;
  }
}

// The mesh-side part (simplify's): components by the extent of their vertices.
TEST(TopologyTolerance, MeshComponentsUnderAnExtentAreDropped) {
  Volume volume = filled_volume({40, 24, 24}, -1.0f);
  add_ball(volume, {10, 12, 12}, 6.5);  // 13 across
  add_ball(volume, {30, 12, 12}, 1.5);  // 3 across
  PolygonMesh mesh = contour_volume(volume, 0.0);
  ASSERT_EQ(summarize_topology(mesh).components, 2u);
  PolygonMesh kept = mesh;
  EXPECT_EQ(remove_components_under(kept, 2.0).components, 0u);
  EXPECT_EQ(kept.vertex_count(), mesh.vertex_count());
  const ComponentRemoval removal = remove_components_under(kept, 4.0);
  EXPECT_EQ(removal.components, 1u);
  require_manifold(kept, "kept");
  EXPECT_EQ(summarize_topology(kept).components, 1u);
  for (const Vec3& p : kept.positions) EXPECT_LT(p.x, 20.0);
}

TEST(TopologyTolerance, RejectsABadTolerance) {
  const Volume volume = make_builtin_field("sphere", 16);
  for (const double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    IsosurfaceOptions options;
    options.topology_tolerance = bad;
    try {
      extract_isosurface(volume, options);
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
    }
    Volume copy = volume;
    EXPECT_THROW(clean_topology(copy, 0.0, bad), Error);
  }
}

}  // namespace
}  // namespace isowave
