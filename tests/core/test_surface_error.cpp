// The surface error D (surface_error.h) against answers computed without it:
// planar cases with closed-form distances, and inscribed spheres and tori
// whose RMS distance from the analytic surface comes from a quadrature over
// their faces (not from area_samples()).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <utility>

#include <tbb/global_control.h>

#include "isowave/core/error.h"
#include "isowave/core/surface_error.h"

namespace isowave {
namespace {

constexpr double kPi = 3.14159265358979323846;

PolygonMesh square(double z) {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, z}, {1, 0, z}, {1, 1, z}, {0, 1, z}};
  mesh.add_face({0, 1, 2, 3});
  return mesh;
}

// The rectangle [0, 2] x [0, 1] as one hexagon whose fan from (0, 0) has a
// zero-area triangle, one of area 1 (below the diagonal y = x / 2) and two
// of area 1/2.
PolygonMesh rectangle_hexagon() {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {0, 1, 0}};
  mesh.add_face({0, 1, 2, 3, 4, 5});
  return mesh;
}

// The icosahedron inscribed in the unit sphere, its triangles split into 4
// `levels` times with the new vertices pushed onto the sphere.
PolygonMesh icosphere(int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  PolygonMesh mesh;
  mesh.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& p : mesh.positions) p = normalized(p);
  for (const auto& f : {std::array<std::uint32_t, 3>{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                        {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2},
                        {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}})
    mesh.add_face(f.data(), 3);
  for (int level = 0; level < levels; ++level) {
    PolygonMesh finer;
    finer.positions = mesh.positions;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto [it, added] = midpoints.try_emplace({std::min(a, b), std::max(a, b)}, std::uint32_t(finer.positions.size()));
      if (added) finer.positions.push_back(normalized(mesh.positions[a] + mesh.positions[b]));
      return it->second;
    };
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      const std::uint32_t* v = mesh.face_begin(f);
      const std::uint32_t ab = midpoint(v[0], v[1]), bc = midpoint(v[1], v[2]), ca = midpoint(v[2], v[0]);
      finer.add_face({v[0], ab, ca});
      finer.add_face({ab, v[1], bc});
      finer.add_face({ca, bc, v[2]});
      finer.add_face({ab, bc, ca});
    }
    mesh = std::move(finer);
  }
  return mesh;
}

constexpr double kTorusMajor = 1.0, kTorusMinor = 0.4;

// nu x nv quads with corners on the torus of radii kTorusMajor, kTorusMinor
// about the z axis (each quad is a planar isosceles trapezoid).
PolygonMesh torus(int nu, int nv) {
  PolygonMesh mesh;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      const double rho = kTorusMajor + kTorusMinor * std::cos(v);
      mesh.positions.push_back({rho * std::cos(u), rho * std::sin(u), kTorusMinor * std::sin(v)});
    }
  const auto vertex = [&](int i, int j) { return std::uint32_t((i % nu) * nv + j % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) mesh.add_face({vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1)});
  return mesh;
}

double distance_to_torus(const Vec3& p) {
  return std::abs(std::hypot(std::hypot(p.x, p.y) - kTorusMajor, p.z) - kTorusMinor);
}

// sqrt(integral of distance^2 over the mesh / its area): each fan triangle
// split into 16 x 16 similar ones, each integrated by the rule of its three
// edge midpoints (exact for quadratics).
double quadrature_rms(const PolygonMesh& mesh, const std::function<double(const Vec3&)>& distance) {
  constexpr int m = 16;
  double integral = 0, area = 0;
  const auto add = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    const double part = 0.5 * norm(cross(b - a, c - a));
    const double d0 = distance(0.5 * (a + b)), d1 = distance(0.5 * (b + c)), d2 = distance(0.5 * (c + a));
    integral += part * (d0 * d0 + d1 * d1 + d2 * d2) / 3;
    area += part;
  };
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* v = mesh.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < mesh.face_size(f); ++k) {
      const Vec3 a = mesh.positions[v[0]], ab = mesh.positions[v[k]] - a, ac = mesh.positions[v[k + 1]] - a;
      const auto at = [&](int i, int j) { return a + (double(i) / m) * ab + (double(j) / m) * ac; };
      for (int i = 0; i < m; ++i)
        for (int j = 0; i + j < m; ++j) {
          add(at(i, j), at(i + 1, j), at(i, j + 1));
          if (i + j + 1 < m) add(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
        }
    }
  }
  return std::sqrt(integral / area);
}

TEST(SurfaceError, ParallelSquaresAreTheirOffsetApart) {
  const double h = 0.375;
  const SurfaceError error = surface_error(square(0), square(h), 20000);
  EXPECT_NEAR(error.forward_rms, h, 1e-12);
  EXPECT_NEAR(error.forward_max, h, 1e-12);
  EXPECT_NEAR(error.backward_rms, h, 1e-12);
  EXPECT_NEAR(error.backward_max, h, 1e-12);
  EXPECT_NEAR(error.d(), h, 1e-12);
}

TEST(SurfaceError, SquareInsideARectangleOfTwiceItsArea) {
  // From the square every point is on the rectangle; from the rectangle half
  // the area is on the square and half at a distance uniform in [0, 1]:
  // RMS sqrt(1/2 * 1/3). With 200,000 samples the RMS's relative standard
  // deviation is about 0.2%.
  const SurfaceError error = surface_error(square(0), rectangle_hexagon());
  EXPECT_NEAR(error.forward_rms, 0.0, 1e-12);
  EXPECT_NEAR(error.forward_max, 0.0, 1e-12);
  EXPECT_NEAR(error.backward_rms, std::sqrt(1.0 / 6), 0.01 * std::sqrt(1.0 / 6));
  EXPECT_NEAR(error.backward_max, 1.0, 1e-3);
  EXPECT_EQ(error.d(), error.backward_rms);
}

TEST(SurfaceError, SamplesAreUniformOverTheArea) {
  // On the hexagon's fan (triangles of area 0, 1, 1/2, 1/2): half the
  // samples below y = x / 2 (the area-1 triangle), means at the rectangle's
  // centre (1, 1/2), none outside it. Standard errors about 0.002.
  const std::vector<Vec3> samples = area_samples(rectangle_hexagon(), 100000, 5);
  ASSERT_EQ(samples.size(), 100000u);
  double below = 0, mean_x = 0, mean_y = 0;
  for (const Vec3& p : samples) {
    ASSERT_TRUE(p.x >= 0 && p.x <= 2 && p.y >= 0 && p.y <= 1 && p.z == 0);
    below += p.y < p.x / 2;
    mean_x += p.x;
    mean_y += p.y;
  }
  const double n = double(samples.size());
  EXPECT_NEAR(below / n, 0.5, 0.01);
  EXPECT_NEAR(mean_x / n, 1.0, 0.01);
  EXPECT_NEAR(mean_y / n, 0.5, 0.01);
}

TEST(SurfaceError, InscribedSpheresMatchTheAnalyticDistance) {
  // Against an icosphere 3 levels finer than the finest one measured: its
  // own distance from the sphere (1/64 of theirs or less) and the slight
  // tilt between the sphere and a face change D by under 3%.
  const PolygonMesh reference = icosphere(7);
  double previous = 0;
  for (int levels = 1; levels <= 4; ++levels) {
    SCOPED_TRACE("icosphere of " + std::to_string(levels) + " levels");
    const PolygonMesh mesh = icosphere(levels);
    const double expected = quadrature_rms(mesh, [](const Vec3& p) { return 1 - norm(p); });
    const SurfaceError error = surface_error(mesh, reference);
    EXPECT_NEAR(error.forward_rms, expected, 0.03 * expected);
    EXPECT_NEAR(error.backward_rms, expected, 0.03 * expected);
    EXPECT_NEAR(error.d(), expected, 0.03 * expected);
    if (levels > 1) {
      EXPECT_NEAR(previous / error.d(), 4.0, 0.4) << "halving the edges divides D by about 4";
    }
    previous = error.d();
  }
}

TEST(SurfaceError, InscribedToriMatchTheAnalyticDistance) {
  const PolygonMesh reference = torus(512, 256);
  double previous = 0;
  for (int n = 16; n <= 64; n *= 2) {
    SCOPED_TRACE("torus of " + std::to_string(n) + " x " + std::to_string(n / 2) + " quads");
    const PolygonMesh mesh = torus(n, n / 2);
    const double expected = quadrature_rms(mesh, distance_to_torus);
    const SurfaceError error = surface_error(mesh, reference);
    EXPECT_NEAR(error.forward_rms, expected, 0.03 * expected);
    EXPECT_NEAR(error.backward_rms, expected, 0.03 * expected);
    if (n > 16) {
      EXPECT_NEAR(previous / error.d(), 4.0, 0.4) << "halving the edges divides D by about 4";
    }
    previous = error.d();
  }
}

TEST(SurfaceError, SameResultForAnyThreadCount) {
  const PolygonMesh mesh = icosphere(3), reference = torus(64, 32);
  std::vector<Vec3> samples[3];
  SurfaceError errors[3];
  const int threads[3] = {1, 2, 4};
  for (int run = 0; run < 3; ++run) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads[run]);
    samples[run] = area_samples(mesh, 50000, 17);
    errors[run] = surface_error(mesh, reference, 50000);
  }
  for (int run = 1; run < 3; ++run) {
    SCOPED_TRACE(std::to_string(threads[run]) + " threads");
    EXPECT_TRUE(samples[run] == samples[0]);
    EXPECT_EQ(errors[run].forward_rms, errors[0].forward_rms);
    EXPECT_EQ(errors[run].forward_max, errors[0].forward_max);
    EXPECT_EQ(errors[run].backward_rms, errors[0].backward_rms);
    EXPECT_EQ(errors[run].backward_max, errors[0].backward_max);
  }
  EXPECT_FALSE(area_samples(mesh, 50000, 18) == samples[0]) << "another seed gives other samples";
}

// Both directions' RMS and maximum alike, to the bit.
void expect_same(const SurfaceError& a, const SurfaceError& b) {
  EXPECT_EQ(a.forward_rms, b.forward_rms);
  EXPECT_EQ(a.backward_rms, b.backward_rms);
  EXPECT_EQ(a.forward_max, b.forward_max);
  EXPECT_EQ(a.backward_max, b.backward_max);
}

TEST(SurfaceError, AReferenceMeasuresManyMeshesAsEachAlone) {
  const PolygonMesh reference = icosphere(4);
  const SurfaceErrorReference against(reference, 5000);
  for (const int levels : {1, 2, 3}) {
    expect_same(against.measure(icosphere(levels)), surface_error(icosphere(levels), reference, 5000));
  }
  EXPECT_THROW(SurfaceErrorReference(reference, 0), Error);
}

// A reference kept with its first samples measures as one made with that
// many (their samples are the same points), on both directions; the two
// directions apart add up to measure().
TEST(SurfaceError, AReferenceWithItsFirstSamplesMeasuresAsOneMadeWithThem) {
  const PolygonMesh reference = icosphere(4);
  const SurfaceErrorReference against(reference, 5000);
  const SurfaceErrorReference fewer = against.with_first_samples(700);
  EXPECT_EQ(fewer.samples(), 700u);
  for (const int levels : {1, 2}) {
    expect_same(fewer.measure(icosphere(levels)), surface_error(icosphere(levels), reference, 700));
    double rms = 0, max = 0;
    against.backward(icosphere(levels), rms, max);
    const SurfaceError all = against.measure(icosphere(levels));
    EXPECT_EQ(rms, all.backward_rms);
    EXPECT_EQ(max, all.backward_max);
  }
  // Distances to the unit sphere's inscribed icosphere: at most its own gap.
  const std::vector<double> to = against.distances_to_reference({{0, 0, 1}, {0, 0, 2}});
  ASSERT_EQ(to.size(), 2u);
  EXPECT_LT(to[0], 0.01);
  EXPECT_NEAR(to[1], 1.0, 0.01);
  EXPECT_THROW(against.with_first_samples(0), Error);
  EXPECT_THROW(against.with_first_samples(5001), Error);
}

TEST(SurfaceError, MeshesWithoutAreaAreRefused) {
  PolygonMesh empty, degenerate;
  degenerate.positions = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  degenerate.add_face({0, 1, 2});
  for (const PolygonMesh* mesh : {&empty, &degenerate}) {
    try {
      area_samples(*mesh, 10, 1);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
    }
    EXPECT_THROW(surface_error(*mesh, square(0)), Error);
    EXPECT_THROW(surface_error(square(0), *mesh), Error);
  }
  EXPECT_THROW(surface_error(square(0), square(1), 0), Error);
}

}  // namespace
}  // namespace isowave
