// Isosurface extraction: topology and geometry against analytic surfaces,
// the 2-manifold / orientation contract on adversarial fields (random noise,
// samples exactly at the isovalue, NaN), thread-count independence, and the
// clean-ups against counts made independently in the test.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numeric>
#include <random>
#include <tuple>
#include <vector>

#include "isosurface_checks.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

using test::boundary_edges;
using test::box_faces_of;
using test::expect_boundary_on_box;
using test::fraction_toward_lower;

constexpr double kPi = 3.14159265358979323846;

Volume random_volume(std::array<std::size_t, 3> dims, std::uint32_t seed, int levels) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> level(0, levels - 1);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  Volume volume;
  volume.dims = dims;
  volume.values.resize(volume.sample_count());
  for (float& v : volume.values) v = levels > 0 ? static_cast<float>(level(rng)) : uniform(rng);
  return volume;
}

TEST(Isosurface, SphereAreaAndEulerCharacteristic) {
  const Volume volume = make_builtin_field("sphere", 128);
  const PolygonMesh mesh = contour_volume(volume, 0.0);
  ASSERT_NO_THROW(require_manifold(mesh, "sphere"));
  const TopologySummary topology = summarize_topology(mesh);
  EXPECT_EQ(topology.euler_characteristic, 2);
  EXPECT_EQ(topology.components, 1u);
  EXPECT_EQ(topology.boundary_edges, 0u);
  const double radius = 0.35 * 127;
  EXPECT_NEAR(surface_area(mesh) / (4 * kPi * radius * radius), 1.0, 0.005);
  // Vertices lie on the sphere to within the linear interpolation error.
  const Vec3 centre{63.5, 63.5, 63.5};
  for (const Vec3& p : mesh.positions) ASSERT_NEAR(norm(p - centre), radius, 0.05);
  EXPECT_GT(fraction_toward_lower(volume, mesh), 0.99);
}

TEST(Isosurface, TorusAndGenus3HaveTheirGenus) {
  for (const auto& [name, genus] : {std::pair<const char*, long long>{"torus", 1}, {"genus3", 3}}) {
    const Volume volume = make_builtin_field(name, 128);
    const PolygonMesh mesh = contour_volume(volume, 0.0);
    ASSERT_NO_THROW(require_manifold(mesh, name));
    const TopologySummary topology = summarize_topology(mesh);
    EXPECT_EQ(topology.genus, genus) << name;
    EXPECT_EQ(topology.components, 1u) << name;
    EXPECT_EQ(topology.boundary_edges, 0u) << name;
    EXPECT_GT(fraction_toward_lower(volume, mesh), 0.99) << name;
  }
  // Torus area 4 pi^2 R r.
  const PolygonMesh torus = contour_volume(make_builtin_field("torus", 128), 0.0);
  EXPECT_NEAR(surface_area(torus) / (4 * kPi * kPi * 0.25 * 127 * 0.1 * 127), 1.0, 0.01);
}

TEST(Isosurface, SphereCutByTheBoxHasItsBoundaryOnTheBox) {
  // A sphere centred near a corner of an anisotropic, shifted grid: cut by
  // three box faces, its boundary curves meet at box edges.
  Volume volume = test::sampled_volume({40, 36, 33}, [](double i, double j, double k) {
    return 20.0 - std::sqrt((i - 30) * (i - 30) + (j - 28) * (j - 28) + (k - 26) * (k - 26));
  });
  volume.spacing = {0.5, 1.25, 2.0};
  volume.origin = {-3, 7, 1.5};
  const PolygonMesh mesh = contour_volume(volume, 0.0);
  ASSERT_NO_THROW(require_manifold(mesh, "cut sphere"));
  const auto boundary = boundary_edges(mesh);
  EXPECT_GT(boundary.size(), 0u);
  expect_boundary_on_box(volume, mesh, "cut sphere");
  // Sharp exactly where a vertex lies on two box faces (a box edge).
  std::size_t on_box_edges = 0;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const int faces = box_faces_of(volume, mesh.positions[v]);
    const bool on_edge = __builtin_popcount(static_cast<unsigned>(faces)) >= 2;
    on_box_edges += on_edge;
    EXPECT_EQ(mesh.is_sharp(v), on_edge) << "vertex " << v;
  }
  EXPECT_GT(on_box_edges, 0u);
  const TopologySummary topology = summarize_topology(mesh);
  EXPECT_EQ(topology.components, 1u);
  EXPECT_EQ(topology.boundary_loops, 1u);  // one curve around the corner region
  EXPECT_EQ(topology.genus, 0);
  EXPECT_GT(fraction_toward_lower(volume, mesh), 0.99);
}

// One vertex per crossed grid edge (counted here), at distinct positions.
void expect_one_vertex_per_crossed_edge(const Volume& volume, double iso, const PolygonMesh& mesh,
                                        std::size_t centroids, const std::string& name) {
  const auto inside = [&](std::size_t i, std::size_t j, std::size_t k) {
    const float v = volume.at(i, j, k);
    return std::isfinite(v) && v >= iso;
  };
  std::size_t crossed = 0;
  for (std::size_t k = 0; k < volume.dims[2]; ++k)
    for (std::size_t j = 0; j < volume.dims[1]; ++j)
      for (std::size_t i = 0; i < volume.dims[0]; ++i) {
        if (i + 1 < volume.dims[0] && inside(i, j, k) != inside(i + 1, j, k)) ++crossed;
        if (j + 1 < volume.dims[1] && inside(i, j, k) != inside(i, j + 1, k)) ++crossed;
        if (k + 1 < volume.dims[2] && inside(i, j, k) != inside(i, j, k + 1)) ++crossed;
      }
  EXPECT_EQ(mesh.vertex_count(), crossed + centroids) << name;
  std::vector<std::tuple<double, double, double>> sorted;
  for (const Vec3& p : mesh.positions) sorted.emplace_back(p.x, p.y, p.z);
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << name << ": duplicate vertex positions";
}

double smallest_triangle_area(const PolygonMesh& mesh) {
  double smallest = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* t = mesh.face_begin(f);
    smallest =
        std::min(smallest,
                 norm(cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]])));
  }
  return smallest;
}

TEST(Isosurface, AdversarialFieldsGiveOrientedManifolds) {
  struct Case {
    std::string name;
    Volume volume;
    double iso;
  };
  std::vector<Case> cases;
  for (std::uint32_t seed = 1; seed <= 4; ++seed)
    cases.push_back({"uniform noise " + std::to_string(seed), random_volume({23, 17, 29}, seed, 0), 0.5});
  // Integer fields: a large share of the samples are exactly at the isovalue.
  for (std::uint32_t seed = 11; seed <= 14; ++seed)
    cases.push_back({"integers 0..2, iso 1, seed " + std::to_string(seed), random_volume({21, 25, 19}, seed, 3), 1.0});
  cases.push_back({"binary 0/1 at iso 1", random_volume({24, 24, 24}, 21, 2), 1.0});
  cases.push_back({"binary 0/1 at iso 0.5", random_volume({24, 24, 24}, 22, 2), 0.5});
  // Checkerboard: every face ambiguous with a saddle exactly at the isovalue.
  cases.push_back(
      {"checkerboard",
       test::sampled_volume({12, 12, 12}, [](double i, double j, double k) { return (int(i + j + k) % 2) ? 1.0 : -1.0; }), 0.0});
  // Plateaus exactly at the isovalue next to both sides.
  cases.push_back({"terraces",
                   test::sampled_volume({30, 30, 30},
                               [](double i, double j, double k) {
                                 return std::round(std::sin(i * 0.4) + std::cos(j * 0.3) + std::sin(k * 0.5 + i * 0.1));
                               }),
                   0.0});
  Volume with_nan = random_volume({20, 20, 20}, 31, 0);
  for (std::size_t n = 0; n < with_nan.values.size(); n += 7)
    with_nan.values[n] = n % 3 == 0   ? std::numeric_limits<float>::quiet_NaN()
                         : n % 3 == 1 ? std::numeric_limits<float>::infinity()
                                      : -std::numeric_limits<float>::infinity();
  cases.push_back({"noise with NaN and Inf", with_nan, 0.5});
  for (const std::string& name : builtin_field_names())
    cases.push_back({"builtin " + name, make_builtin_field(name, 48), 0.0});

  // Values +-1 at iso 0: every ambiguous face's decider is a tie.
  Volume signs = random_volume({22, 22, 22}, 41, 2);
  for (float& v : signs.values) v = 2 * v - 1;
  cases.push_back({"random signs, decider ties", signs, 0.0});

  std::size_t total_centroids = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    for (bool flip : {false, true}) {
      std::size_t centroids = 0;
      const PolygonMesh mesh = contour_volume(c.volume, c.iso, flip, &centroids);
      total_centroids += centroids;
      ASSERT_NO_THROW(require_manifold(mesh, c.name));
      expect_boundary_on_box(c.volume, mesh, c.name);
      expect_one_vertex_per_crossed_edge(c.volume, c.iso, mesh, centroids, c.name);
      EXPECT_GT(smallest_triangle_area(mesh), 0.0);
      // Normals toward lower values (or higher with flip), in aggregate.
      const double lower = fraction_toward_lower(c.volume, mesh);
      if (flip)
        EXPECT_LT(lower, 0.05) << c.name;
      else
        EXPECT_GT(lower, 0.95) << c.name;
    }
  }
  EXPECT_GT(total_centroids, 0u) << "the loop-centre fallback was not exercised";
}

TEST(Isosurface, OutputDoesNotDependOnThreadCount) {
  const Volume volume = make_builtin_field("mixing", 96);
  PolygonMesh one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = contour_volume(volume, 0.0);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = contour_volume(volume, 0.0);
  }
  ASSERT_GT(one.face_count(), 1000u);
  EXPECT_TRUE(one.positions == two.positions);
  EXPECT_TRUE(one.face_vertices == two.face_vertices);
  EXPECT_TRUE(one.sharp == two.sharp);
}

// Component vertex counts from a breadth-first search over face adjacency
// through shared vertices (independent of the library's union-find).
std::vector<std::size_t> component_vertex_counts(const PolygonMesh& mesh) {
  std::vector<std::vector<std::uint32_t>> faces_of(mesh.vertex_count());
  for (std::size_t f = 0; f < mesh.face_count(); ++f)
    for (std::uint32_t i = 0; i < mesh.face_size(f); ++i) faces_of[mesh.face_begin(f)[i]].push_back(std::uint32_t(f));
  std::vector<bool> seen(mesh.vertex_count(), false);
  std::vector<std::size_t> counts;
  for (std::uint32_t start = 0; start < mesh.vertex_count(); ++start) {
    if (seen[start] || faces_of[start].empty()) continue;
    std::size_t count = 0;
    std::vector<std::uint32_t> stack{start};
    seen[start] = true;
    while (!stack.empty()) {
      const std::uint32_t v = stack.back();
      stack.pop_back();
      ++count;
      for (std::uint32_t f : faces_of[v])
        for (std::uint32_t i = 0; i < mesh.face_size(f); ++i) {
          const std::uint32_t w = mesh.face_begin(f)[i];
          if (!seen[w]) {
            seen[w] = true;
            stack.push_back(w);
          }
        }
    }
    counts.push_back(count);
  }
  return counts;
}

TEST(Isosurface, MinComponentVerticesDropsExactlyTheSmallComponents) {
  const Volume volume = make_builtin_field("mixing", 96);
  IsosurfaceOptions plain;
  const Isosurface all = extract_isosurface(volume, plain);
  const std::vector<std::size_t> counts = component_vertex_counts(all.mesh);
  ASSERT_EQ(counts.size(), all.report.before.components);
  for (std::size_t threshold : {7, 30, 200}) {
    SCOPED_TRACE(threshold);
    std::size_t small = 0, small_vertices = 0;
    for (std::size_t c : counts)
      if (c < threshold) {
        ++small;
        small_vertices += c;
      }
    ASSERT_GT(small, 0u);
    IsosurfaceOptions options;
    options.min_component_vertices = threshold;
    const Isosurface cleaned = extract_isosurface(volume, options);
    ASSERT_NO_THROW(require_manifold(cleaned.mesh, "cleaned"));
    EXPECT_EQ(cleaned.report.dropped_components, small);
    EXPECT_EQ(cleaned.report.dropped_vertices, small_vertices);
    EXPECT_EQ(cleaned.mesh.vertex_count(), all.mesh.vertex_count() - small_vertices);
    const std::vector<std::size_t> kept = component_vertex_counts(cleaned.mesh);
    EXPECT_EQ(kept.size(), counts.size() - small);
    for (std::size_t c : kept) EXPECT_GE(c, threshold);
    EXPECT_EQ(cleaned.report.after.components, kept.size());
    EXPECT_NEAR(cleaned.report.after.area + cleaned.report.dropped_area, all.report.after.area,
                1e-9 * all.report.after.area);
    EXPECT_EQ(cleaned.report.before.components, counts.size());
  }
}

TEST(Isosurface, SmoothingKeepsASphereAndRemovesNoiseComponents) {
  const double radius = 0.35 * 127;
  IsosurfaceOptions options;
  options.smooth_sigma = 1.5;
  const Isosurface sphere = extract_isosurface(make_builtin_field("sphere", 128), options);
  EXPECT_NEAR(sphere.report.after.area / (4 * kPi * radius * radius), 1.0, 0.01);
  EXPECT_EQ(sphere.report.after.euler_characteristic, 2);

  // A sphere drowned in sample noise: many small components until smoothed.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> noise(-4, 4);
  const Volume noisy = test::sampled_volume({64, 64, 64}, [&](double i, double j, double k) {
    return 20 - std::sqrt((i - 31.5) * (i - 31.5) + (j - 31.5) * (j - 31.5) + (k - 31.5) * (k - 31.5)) + noise(rng);
  });
  const Isosurface raw = extract_isosurface(noisy, {});
  EXPECT_GT(raw.report.after.components, 50u);
  options.smooth_sigma = 2.0;
  const Isosurface smoothed = extract_isosurface(noisy, options);
  ASSERT_NO_THROW(require_manifold(smoothed.mesh, "smoothed noisy sphere"));
  EXPECT_EQ(smoothed.report.after.components, 1u);
  EXPECT_EQ(smoothed.report.after.genus, 0);
  EXPECT_EQ(smoothed.report.before.components, raw.report.after.components);
}

TEST(Isosurface, ReportIsConsistent) {
  const Isosurface result = extract_isosurface(make_builtin_field("mixing", 64), {});
  const SurfaceStatistics& s = result.report.after;
  EXPECT_EQ(s.vertices, result.mesh.vertex_count());
  EXPECT_EQ(s.faces, result.mesh.face_count());
  EXPECT_EQ(s.euler_characteristic, (long long)s.vertices - (long long)s.edges + (long long)s.faces);
  EXPECT_EQ(s.euler_characteristic, 2 * (long long)s.components - 2 * s.genus - (long long)s.boundary_loops);
  EXPECT_EQ(std::accumulate(s.component_size_histogram.begin(), s.component_size_histogram.end(), std::size_t{0}),
            s.components);
  EXPECT_GT(s.boundary_loops, 0u);  // the mixing layer meets the box sides
  EXPECT_EQ(result.report.sharp_vertices, result.mesh.sharp_count());
  EXPECT_GT(result.report.sharp_vertices, 0u);
}

TEST(Isosurface, RejectsBadInput) {
  Volume flat;
  flat.dims = {10, 10, 1};
  flat.values.assign(100, 0.0f);
  EXPECT_THROW(contour_volume(flat, 0.0), Error);
  const Volume sphere = make_builtin_field("sphere", 16);
  EXPECT_THROW(contour_volume(sphere, std::numeric_limits<double>::quiet_NaN()), Error);
  IsosurfaceOptions options;
  options.smooth_sigma = -1;
  EXPECT_THROW(extract_isosurface(sphere, options), Error);
  EXPECT_THROW(make_builtin_field("no-such-field", 32), Error);
  EXPECT_THROW(make_builtin_field("sphere", 4), Error);
  // The surface misses the volume: an empty mesh.
  EXPECT_EQ(contour_volume(sphere, 1e9).face_count(), 0u);
}

}  // namespace
}  // namespace isowave
