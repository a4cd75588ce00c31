// The BFS signed-distance field against the exact distance to the extracted
// triangle mesh (CGAL AABB tree), on analytic fields and shared volumes.
#include <gtest/gtest.h>

#include <array>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/fit/trilinear.h"
#include "isowave/core/surface_distance.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

struct Accuracy {
  std::size_t nodes = 0;
  double mean = 0, max = 0;  // cells
  std::size_t wrong_sign = 0;
};

// Every node within 3 cells of the surface (by the exact distance).
Accuracy measure(const Volume& field, double iso, const SignedDistanceField& sdf, const PolygonMesh& mesh) {
  const SurfaceDistance exact(mesh);
  std::vector<Vec3> nodes;
  std::vector<std::size_t> index;
  for (std::size_t k = 0; k < field.dims[2]; ++k)
    for (std::size_t j = 0; j < field.dims[1]; ++j)
      for (std::size_t i = 0; i < field.dims[0]; ++i)
        if (std::abs(sdf.distance.at(i, j, k)) <= 4 * field.cell_size()) {
          nodes.push_back(field.world(double(i), double(j), double(k)));
          index.push_back(field.index(i, j, k));
        }
  const std::vector<double> distances = exact.distances(nodes);
  Accuracy a;
  double sum = 0;
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    if (distances[n] > 3 * field.cell_size()) continue;
    const double value = sdf.distance.values[index[n]];
    const double error = std::abs(std::abs(value) - distances[n]) / field.cell_size();
    sum += error;
    a.max = std::max(a.max, error);
    ++a.nodes;
    const bool inside = field.values[index[n]] >= iso;
    if (value != 0 && (value < 0) != inside) ++a.wrong_sign;
  }
  a.mean = a.nodes ? sum / double(a.nodes) : 0;
  return a;
}

void expect_accurate(const Volume& field, double iso, const std::string& name) {
  SCOPED_TRACE(name);
  IsosurfaceOptions options;
  options.iso = iso;
  const PolygonMesh mesh = extract_isosurface(field, options).mesh;
  ASSERT_GT(mesh.face_count(), 0u);
  SignedDistanceOptions sdf_options;
  sdf_options.iso = iso;
  const SignedDistanceField sdf = compute_signed_distance(field, sdf_options);
  for (float v : sdf.distance.values) ASSERT_TRUE(std::isfinite(v));
  const Accuracy a = measure(field, iso, sdf, mesh);
  std::printf("  %s: %zu nodes within 3 cells, mean |error| %.4f cell, max %.4f cell\n", name.c_str(), a.nodes, a.mean,
              a.max);
  EXPECT_GT(a.nodes, 1000u);
  EXPECT_LE(a.mean, 0.05) << a.nodes << " nodes";
  EXPECT_LE(a.max, 0.5);
  EXPECT_EQ(a.wrong_sign, 0u);
}

TEST(SignedDistance, AnalyticFieldsWithinThreeCells) {
  for (const char* name : {"sphere", "genus3", "mixing"}) expect_accurate(make_builtin_field(name, 80), 0.0, name);
}

TEST(SignedDistance, SharedVolumesWithinThreeCells) {
  ISOWAVE_REQUIRE_SHARED_FILE(hydrogen, "volumes/hydrogen.vti");
  expect_accurate(read_volume(hydrogen), 0.05, "hydrogen");
  ISOWAVE_REQUIRE_SHARED_FILE(fingers, "volumes/viscousfingers_099.vti");
  expect_accurate(read_volume(fingers), 30, "viscous fingers");
}

TEST(SignedDistance, NarrowBandAgreesInsideTheBandAndClampsOutside) {
  const Volume field = make_builtin_field("genus3", 64);
  const SignedDistanceField full = compute_signed_distance(field);
  SignedDistanceOptions options;
  options.band_cells = 2.5;
  const SignedDistanceField band = compute_signed_distance(field, options);
  const double cell = field.cell_size();
  EXPECT_LT(band.statistics.queue_pops, full.statistics.queue_pops);
  std::size_t inside_band = 0;
  for (std::size_t n = 0; n < field.sample_count(); ++n) {
    const float f = full.distance.values[n], b = band.distance.values[n];
    ASSERT_EQ(f < 0, b < 0) << "node " << n;  // sign from the field in both
    ASSERT_LE(std::abs(b), 2.5 * cell * (1 + 1e-6));
    if (std::abs(f) < 2.0 * cell) {
      ++inside_band;
      EXPECT_NEAR(f, b, 0.05 * cell) << "node " << n;
    }
  }
  EXPECT_GT(inside_band, 1000u);
}

TEST(SignedDistance, SignFollowsFlip) {
  const Volume field = make_builtin_field("sphere", 32);
  SignedDistanceOptions options;
  const SignedDistanceField normal = compute_signed_distance(field, options);
  options.flip = true;
  const SignedDistanceField flipped = compute_signed_distance(field, options);
  const std::size_t centre = field.index(16, 16, 16), corner = field.index(0, 0, 0);
  EXPECT_LT(normal.distance.values[centre], 0);  // inside the sphere: higher values
  EXPECT_GT(normal.distance.values[corner], 0);
  for (std::size_t n = 0; n < field.sample_count(); ++n) ASSERT_EQ(normal.distance.values[n], -flipped.distance.values[n]);
}

TEST(SignedDistance, DroppedComponentsLeaveNoZeroCrossing) {
  // Two spheres; extraction keeps only the large one.
  const Volume field = test::sampled_volume({48, 48, 48}, [](double x, double y, double z) {
    const Vec3 p{x, y, z};
    return std::max(12 - norm(p - Vec3{18, 24, 24}), 3 - norm(p - Vec3{38, 24, 24}));
  });
  IsosurfaceOptions extract_options;
  extract_options.min_component_vertices = 200;
  const Isosurface surface = extract_isosurface(field, extract_options);
  ASSERT_EQ(surface.report.after.components, 1u);
  SignedDistanceOptions options;
  options.surface = &surface.mesh;
  const SignedDistanceField sdf = compute_signed_distance(field, options);
  EXPECT_GT(sdf.statistics.flipped_nodes, 0u);
  // The small sphere's centre is outside the kept surface: positive, and as far as the big sphere.
  const double centre = sdf.distance.at(38, 24, 24);
  EXPECT_NEAR(centre, norm(Vec3{38, 24, 24} - Vec3{18, 24, 24}) - 12, 0.5);
}

TEST(SignedDistance, ADroppedSpeckSharingACellWithTheKeptSurfaceLeavesNoZeroCrossing) {
  // Kept: the half-space x + y <= 20 (a staircase of samples). Dropped: one
  // sample inside at (11, 11, 8), whose face neighbours are all outside but
  // which is a corner of a cell the kept surface passes through (the one at
  // (10, 10, 8), whose corner (10, 10, 8) is inside). It seeds the queue, so
  // a flood that stops at seeds does not find it enclosed; one that stops at
  // the ends of grid edges the kept mesh crosses does.
  const Volume field = test::sampled_volume({24, 24, 16}, [](double x, double y, double z) {
    if (x == 11 && y == 11 && z == 8) return 0.5;  // the face's saddle below 0: apart
    return x + y <= 20 ? 1.0 : -1.0;
  });
  IsosurfaceOptions extract_options;
  extract_options.min_component_vertices = 10;
  const Isosurface surface = extract_isosurface(field, extract_options);
  ASSERT_EQ(surface.report.after.components, 1u);
  ASSERT_GT(surface.report.before.components, 1u);
  SignedDistanceOptions options;
  options.surface = &surface.mesh;
  options.band_cells = 3;
  const SignedDistanceField sdf = compute_signed_distance(field, options);
  EXPECT_GE(sdf.statistics.flipped_nodes, 1u);
  // Outside the kept surface (positive), with its outside neighbours.
  EXPECT_GT(sdf.distance.at(11, 11, 8), 0.0f);
  for (const auto& [i, j, k] : {std::array<std::size_t, 3>{12, 11, 8}, {10, 11, 8}, {11, 12, 8}, {11, 10, 8},
                                {11, 11, 9}, {11, 11, 7}})
    EXPECT_GT(sdf.distance.at(i, j, k), 0.0f);
  // Without the surface mesh the speck is a surface of its own: negative.
  const SignedDistanceField unmasked = compute_signed_distance(field, {});
  EXPECT_LT(unmasked.distance.at(11, 11, 8), 0.0f);
  // The field the shrink-wrap searches: the speck's sample mirrored across
  // the isovalue, nothing else changed, and its isosurface the kept one.
  Volume cleaned = field;
  EXPECT_EQ(mirror_enclosed_samples(field, sdf, cleaned.values.data()), 1u);
  EXPECT_EQ(cleaned.at(11, 11, 8), -0.5f);
  for (std::size_t n = 0; n < field.values.size(); ++n) {
    if (n == field.index(11, 11, 8)) continue;
    ASSERT_EQ(cleaned.values[n], field.values[n]) << "sample " << n;
  }
  const Isosurface cleaned_surface = extract_isosurface(cleaned, {});
  EXPECT_EQ(cleaned_surface.report.before.components, 1u);
  EXPECT_EQ(cleaned_surface.mesh.vertex_count(), surface.mesh.vertex_count());
  EXPECT_EQ(mirror_enclosed_samples(field, unmasked, cleaned.values.data()), 0u);  // nothing dropped
}

// A ramp f = x - 1.5 (iso 0) with three non-finite samples: one with a
// single inside neighbour, one with five, one with none.
TEST(SignedDistance, FilledNonFiniteSamplesKeepExtractionsClassAndMidpoints) {
  Volume field = test::sampled_volume({4, 3, 3}, [](double x, double, double) { return x - 1.5; });
  const std::vector<float> ramp = field.values;
  std::vector<float> untouched = ramp;
  EXPECT_EQ(fill_non_finite_samples(field, 0.0, untouched.data()), 0u);  // all finite: nothing written
  EXPECT_EQ(untouched, ramp);
  field.values[field.index(1, 1, 1)] = std::nanf("");  // inside neighbour: (2, 1, 1) = 0.5
  field.values[field.index(3, 1, 1)] = std::numeric_limits<float>::infinity();  // five: 0.5 and four of 1.5
  field.values[field.index(0, 0, 0)] = -std::nanf("");  // none: the lowest finite value, -1.5
  std::vector<float> out = field.values;
  EXPECT_EQ(fill_non_finite_samples(field, 0.0, out.data()), 3u);
  for (std::size_t n = 0; n < out.size(); ++n) {
    ASSERT_TRUE(std::isfinite(out[n])) << n;
    // Inside exactly where extraction counts a sample inside.
    EXPECT_EQ(out[n] >= 0.0f, std::isfinite(field.values[n]) && field.values[n] >= 0.0f) << n;
    if (std::isfinite(field.values[n])) {
      EXPECT_EQ(out[n], field.values[n]) << n;
    }
  }
  EXPECT_FLOAT_EQ(out[field.index(1, 1, 1)], -0.5f);
  EXPECT_FLOAT_EQ(out[field.index(3, 1, 1)], -(0.5f + 4 * 1.5f) / 5);
  EXPECT_FLOAT_EQ(out[field.index(0, 0, 0)], -1.5f);
  // The isosurface crosses the edge to the single inside neighbour at its
  // midpoint, where extraction puts that edge's vertex.
  const TrilinearGrid grid(field, out.data());
  EXPECT_NEAR(grid.value(Vec3{1.5, 1.0, 1.0}), 0.0, 1e-7);
  // An isovalue at a sample's value: the filled sample stays below it.
  std::vector<float> at_iso = field.values;
  fill_non_finite_samples(field, 0.5, at_iso.data());
  EXPECT_LT(at_iso[field.index(1, 1, 1)], 0.5f);
}

TEST(SignedDistance, RejectsBadInput) {
  Volume flat;
  flat.dims = {1, 4, 4};
  flat.values.assign(16, 0.0f);
  EXPECT_THROW(compute_signed_distance(flat), Error);
  const Volume field = make_builtin_field("sphere", 16);
  SignedDistanceOptions options;
  options.band_cells = -1;
  EXPECT_THROW(compute_signed_distance(field, options), Error);
  options.band_cells = 0;
  options.iso = std::nan("");
  EXPECT_THROW(compute_signed_distance(field, options), Error);
}

TEST(SignedDistance, NoSurfaceGivesFarValueEverywhere) {
  const Volume field = make_builtin_field("sphere", 16);
  SignedDistanceOptions options;
  options.iso = 1e6;  // nothing reaches it: every node outside
  const SignedDistanceField sdf = compute_signed_distance(field, options);
  EXPECT_EQ(sdf.statistics.seed_nodes, 0u);
  for (float v : sdf.distance.values) ASSERT_FLOAT_EQ(v, float(sdf.far_value));
}

}  // namespace
}  // namespace isowave
