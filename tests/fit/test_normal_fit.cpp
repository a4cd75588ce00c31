// The normal fit (fit/normal_fit.h) on analytic fields: a sphere and a
// torus, whose every fine control point must end on the isosurface with
// every wavelet coefficient exactly along the coder's frame normal; the same
// result for any thread count; bad input refused.
#include <cmath>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "isowave/codec/isw_format.h"
#include "isowave/core/error.h"
#include "isowave/fit/normal_fit.h"
#include "isowave/fit/trilinear.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/wavelet_transform.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

constexpr double kFrameStep = 0.125;  // cells, as convert uses

struct Shape {
  Volume field;
  PolygonMesh base;                              // vertices on the surface
  std::function<double(const Vec3&)> distance;  // analytic signed distance to the surface
};

// Sphere of radius 11 cells, off the grid's symmetry, from a cube's corners.
Shape sphere() {
  const Vec3 c{20.3, 19.6, 20.1};
  const double r = 11;
  Shape s;
  s.distance = [=](const Vec3& p) { return std::sqrt(squared_norm(p - c)) - r; };
  s.field = test::sampled_volume({41, 41, 41}, [&](double x, double y, double z) { return -s.distance({x, y, z}); });
  s.base = test::cube();
  for (Vec3& p : s.base.positions) p = c + normalized(p - Vec3{0.5, 0.5, 0.5}) * r;
  return s;
}

// Torus of radii 15 and 5 cells from a wrapped 8 x 6 quad grid on it.
Shape torus() {
  const Vec3 c{24.2, 23.7, 10.4};
  Shape s;
  s.distance = [=](const Vec3& p) {
    const Vec3 q = p - c;
    return std::hypot(std::hypot(q.x, q.y) - 15.0, q.z) - 5.0;
  };
  s.field = test::sampled_volume({49, 49, 22}, [&](double x, double y, double z) { return -s.distance({x, y, z}); });
  s.base = test::quad_grid(8, 6, true, true);
  for (Vec3& p : s.base.positions) p = c + p * 5.0;
  return s;
}

NormalDirections coder_normals(const SubdivisionHierarchy& h) {
  return [&h](const std::vector<Vec3>& base) { return isw_frame_normals(h, base, kFrameStep); };
}

// Distance of p from the isosurface of the trilinear field, to first order (cells).
double trilinear_distance(const TrilinearGrid& grid, const Vec3& p) {
  const TrilinearSample s = grid.sample(p);
  return std::abs(s.value) / std::sqrt(squared_norm(s.gradient));
}

// The fit of `levels` levels, from the base or (start_levels > 0) from a
// fit of that many levels, as levels by error continues one.
void check_fit(const Shape& shape, int levels, int start_levels = 0) {
  const SubdivisionHierarchy h(shape.base, levels);
  NormalFitResult start;
  NormalFitOptions options;
  if (start_levels > 0) {
    const SubdivisionHierarchy coarse(shape.base, start_levels);
    start = normal_fit(coarse, shape.base.positions, shape.field, 0.0, coder_normals(coarse));
    options.start = &start;
  }
  const NormalFitResult fit = normal_fit(h, shape.base.positions, shape.field, 0.0, coder_normals(h), options);
  ASSERT_EQ(fit.positions.size(), h.fine_vertex_count());
  ASSERT_EQ(fit.levels.size(), std::size_t(levels));
  EXPECT_EQ(fit.non_normal_count(), 0u);

  // Every fine control point on the trilinear isosurface, and so near the analytic one.
  const TrilinearGrid grid(shape.field);
  double worst = 0, worst_analytic = 0, sum = 0;
  for (const Vec3& p : fit.positions) {
    const double d = trilinear_distance(grid, p);
    worst = std::max(worst, d);
    sum += d * d;
    worst_analytic = std::max(worst_analytic, std::abs(shape.distance(p)));
  }
  // A least-squares fit (a level has more points than coefficients): well
  // within a tenth of a cell, where marching cubes' own error lies.
  EXPECT_LT(std::sqrt(sum / double(fit.positions.size())), 0.01);
  EXPECT_LT(worst, 0.05);
  EXPECT_LT(worst_analytic, 0.08);  // plus the trilinear interpolant's own error

  // Every wavelet coefficient along its frame normal (the frames of the
  // base the fit reports, which the coder sends): no tangential part.
  ASSERT_EQ(fit.frame_base.size(), shape.base.vertex_count());
  std::vector<Vec3> coefficients = fit.positions;
  analyze(h, coefficients);
  const std::vector<Vec3> normals = isw_frame_normals(h, fit.frame_base, kFrameStep);
  double largest = 0;
  for (std::size_t i = h.vertex_count(0); i < coefficients.size(); ++i) {
    const Vec3& n = normals[i];
    const Vec3 tangential = coefficients[i] - n * dot(n, coefficients[i]);
    EXPECT_LT(std::sqrt(squared_norm(tangential)), 1e-9) << "coefficient " << i;
    largest = std::max(largest, std::sqrt(squared_norm(coefficients[i])));
  }
  EXPECT_GT(largest, 0.01);  // the detail is not trivially zero
}

TEST(NormalFit, SphereEndsOnTheIsosurfaceWithNormalDetail) { check_fit(sphere(), 4); }

TEST(NormalFit, TorusEndsOnTheIsosurfaceWithNormalDetail) { check_fit(torus(), 3); }

TEST(NormalFit, ContinuesAFitOfFewerLevels) {
  check_fit(sphere(), 3, 2);
  check_fit(torus(), 3, 1);
}

TEST(NormalFit, IdenticalForAnyThreadCount) {
  const Shape shape = torus();
  const SubdivisionHierarchy h(shape.base, 3);
  const NormalFitResult parallel = normal_fit(h, shape.base.positions, shape.field, 0.0, coder_normals(h));
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const NormalFitResult serial = normal_fit(h, shape.base.positions, shape.field, 0.0, coder_normals(h));
  EXPECT_EQ(parallel.positions, serial.positions);
  EXPECT_EQ(parallel.non_normal, serial.non_normal);
}

TEST(NormalFit, RejectsBadInput) {
  const Shape shape = sphere();
  const SubdivisionHierarchy h(shape.base, 2);
  std::vector<Vec3> few(3);
  EXPECT_THROW(normal_fit(h, few, shape.field, 0.0, coder_normals(h)), Error);
  std::vector<Vec3> not_finite = shape.base.positions;
  not_finite[2].y = std::nan("");
  EXPECT_THROW(normal_fit(h, not_finite, shape.field, 0.0, coder_normals(h)), Error);
  const NormalDirections wrong_size = [](const std::vector<Vec3>&) { return std::vector<Vec3>(5); };
  EXPECT_THROW(normal_fit(h, shape.base.positions, shape.field, 0.0, wrong_size), Error);
  NormalFitOptions options;
  options.rounds = 0;
  EXPECT_THROW(normal_fit(h, shape.base.positions, shape.field, 0.0, coder_normals(h), options), Error);
  // A start of as many levels.
  const NormalFitResult same = normal_fit(h, shape.base.positions, shape.field, 0.0, coder_normals(h));
  NormalFitOptions from_same;
  from_same.start = &same;
  EXPECT_THROW(normal_fit(h, shape.base.positions, shape.field, 0.0, coder_normals(h), from_same), Error);
  const SubdivisionHierarchy finer(shape.base, 3);
  EXPECT_NO_THROW(normal_fit(finer, shape.base.positions, shape.field, 0.0, coder_normals(finer), from_same));
}

}  // namespace
}  // namespace isowave
