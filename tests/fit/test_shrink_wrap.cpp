// Shrink-wrap fitting: extracted isosurface -> base mesh (isowave simplify) ->
// signed distance -> shrink-wrap to L = 3, measured with the quality report.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <tbb/global_control.h>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/error.h"
#include "isowave/core/surface_distance.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "isowave/fit/fit_quality.h"
#include "isowave/fit/shrink_wrap.h"
#include "isowave/fit/trilinear.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/pipeline/prepare.h"
#include "isowave/simplify/simplify.h"
#include "isowave/transform/wavelet_transform.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

struct Pipeline {
  Volume field;
  double iso = 0;
  PolygonMesh extracted, base;
  SignedDistanceField distance;
};

Pipeline prepare(Volume field, double iso, std::size_t base_vertices, std::size_t min_component_vertices = 0) {
  PrepareOptions options;
  options.extract.iso = iso;
  options.extract.min_component_vertices = min_component_vertices;
  PreparedSurface prepared = prepare_surface(std::move(field), options, "test");
  Pipeline p{std::move(prepared.field), iso, std::move(prepared.isosurface.mesh), {}, std::move(prepared.distance)};
  simplify::SimplifyOptions simplify_options;
  simplify_options.target_vertices = base_vertices;
  simplify_options.compute_distance = false;
  p.base = simplify::simplify(p.extracted, simplify_options).base;
  return p;
}

// The pipeline's options: the coverage pull reads the extracted surface.
ShrinkWrapOptions options_for(const Pipeline& p) {
  ShrinkWrapOptions options;
  options.surface = &p.extracted;
  return options;
}

void expect_targets(const Pipeline& p, const std::string& name) {
  SCOPED_TRACE(name);
  const SubdivisionHierarchy hierarchy(p.base, 3);
  const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  ASSERT_EQ(result.positions.size(), hierarchy.fine_vertex_count());
  for (const Vec3& v : result.positions) ASSERT_TRUE(is_finite(v));
  const BinnedSurfaceDistance reference(p.extracted);
  const FitQuality q = measure_fit_quality(hierarchy, 3, result.positions, p.extracted, reference, p.field, p.iso,
                                           Orientation::TowardLower);
  EXPECT_EQ(q.nonfinite_vertices, 0u);
  EXPECT_LE(q.isosurface_rms, 0.01);
  EXPECT_LE(q.surface_rms, 0.05);
  EXPECT_LE(q.surface_max, 0.5);
  EXPECT_LE(q.coverage_p99, 0.5);
  EXPECT_LE(q.folded_fraction, 0.001);
}

// A sphere cut by a slab of NaN samples (one of them Inf): extraction counts
// them as outside, so the surface is two caps closed by flat lids between
// the last finite samples and the slab. The shrink-wrap's searches and the
// report see the field with those samples filled (fill_non_finite_samples);
// before, the lid points had no isosurface to be corrected onto, none of
// them could be measured, and every lid face counted as folded (28% of the
// fine faces).
TEST(ShrinkWrap, ASphereCutByNonFiniteSamplesMeetsTheTargets) {
  Volume field = test::sampled_volume({40, 40, 40}, [](double x, double y, double z) {
    return 16.0 - std::sqrt((x - 19.5) * (x - 19.5) + (y - 19.5) * (y - 19.5) + (z - 19.5) * (z - 19.5));
  });
  for (std::size_t k = 17; k <= 20; ++k)
    for (std::size_t j = 0; j < 40; ++j)
      for (std::size_t i = 0; i < 40; ++i) field.values[field.index(i, j, k)] = std::nanf("");
  field.values[field.index(20, 20, 18)] = std::numeric_limits<float>::infinity();
  const Pipeline p = prepare(std::move(field), 0.0, 100);
  expect_targets(p, "sphere cut by NaN samples");
  const SubdivisionHierarchy hierarchy(p.base, 3);
  const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  EXPECT_EQ(result.correction.failed, 0u);
  EXPECT_EQ(isosurface_distance(result.positions, result.positions.size(), p.field, p.iso, 1.0).undefined, 0u);
  // The stand-alone correction sees the same field: the fit moved a fifth of
  // a cell across the lids (along z) goes back onto the isosurface.
  const WrapLevelMesh fine = make_wrap_level_mesh(hierarchy, 3, result.positions, p.field, p.iso);
  std::vector<Vec3> moved = result.positions;
  for (Vec3& v : moved) v.z += 0.2;
  const CorrectionStatistics corrected = correct_to_isosurface(fine, p.field, p.iso, 2.0, moved);
  EXPECT_EQ(corrected.failed, 0u);
  EXPECT_LE(isosurface_distance(moved, moved.size(), p.field, p.iso, 1.0).rms, 0.01);
}

TEST(ShrinkWrap, Genus3MeetsTheTargets) {
  // Base of 150 vertices (about 1/40 of the 6,000 extracted ones).
  expect_targets(prepare(make_builtin_field("genus3", 96), 0.0, 150), "genus3");
}

TEST(ShrinkWrap, HydrogenMeetsTheTargets) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/hydrogen.vti");
  // Base of about 1/64 of the 9,840 extracted vertices.
  expect_targets(prepare(read_volume(path), 0.05, 154), "hydrogen");
}

TEST(ShrinkWrap, ViscousFingersMeetsTheTargets) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/viscousfingers_099.vti");
  // Base of about 1/16 of the 14,000 extracted vertices (genus 1, 5 components, boundaries).
  expect_targets(prepare(read_volume(path), 30, 874), "viscous fingers");
}

TEST(ShrinkWrap, IronProteinMeetsTheTargets) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/ironProt.vtk");
  // A legacy VTK electron density; base of 1/16 of the 7,424 extracted
  // vertices (2026-11-26: 0.0369 RMS / 0.344 max from the extracted mesh,
  // coverage p99 0.14, 1 of 26,112 faces folded).
  expect_targets(prepare(read_volume(path), 128, 464), "iron protein");
}

// The built-in mixing layer has droplets and filaments a few cells across,
// finer than a base mesh of 1/16 of the extracted vertices can follow. The
// coverage, isosurface and fold targets are met (folded 0.32% before the
// unfold, on necks and tunnels thinner than a cell: see the next test), and
// the maximum distance to the extracted mesh (0.395 cells; 1.42 before the
// correction's second step rule on the distance field, from one vertex
// pressed onto the x = 0 face); its RMS is not quite (0.0510 against 0.05),
// because the flat triangles themselves stray 0.046 RMS and up to 1.0 cell
// from the exact isosurface the fit lies on (extracted_surface_deviation):
// the fit is asserted to come as near to them as points on that isosurface
// can (1.10 times that here; 0.92-1.25 on 16 shared and built-in volumes).
TEST(ShrinkWrap, MixingStaysFiniteAndMostlyOnTheIsosurface) {
  const Pipeline p = prepare(make_builtin_field("mixing", 96), 0.0, 2400);
  const SubdivisionHierarchy hierarchy(p.base, 3);
  const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  for (const Vec3& v : result.positions) ASSERT_TRUE(is_finite(v));
  EXPECT_GE(double(result.correction.corrected), 0.97 * double(result.correction.movable));
  const BinnedSurfaceDistance reference(p.extracted);
  const FitQuality q = measure_fit_quality(hierarchy, 3, result.positions, p.extracted, reference, p.field, p.iso,
                                           Orientation::TowardLower);
  EXPECT_EQ(q.nonfinite_vertices, 0u);
  EXPECT_LE(q.surface_rms, 1.25 * extracted_surface_deviation(p.extracted, p.field, p.iso).rms);
  EXPECT_LE(q.surface_max, 0.5);
  // The droplets no longer fold (droplet_vertices): coverage p99 0.31
  // cells (0.93 with the paper's steps). Folded 0.06% with the unfold, 0.32%
  // with the coarse untangle and the local reverts in untangle() alone (0.78%
  // without those, 1.83% with the paper's steps); isosurface RMS 0.0005
  // cells (0.0051 with Newton's steps alone on the distance field, within 2
  // cells).
  EXPECT_LE(q.coverage_p99, 0.5);
  EXPECT_LE(q.folded_fraction, 0.001);
  EXPECT_FALSE(result.unfold.skipped);
  EXPECT_EQ(result.unfold.folded_after, q.folded_faces);  // the same measure, counted independently
  EXPECT_LE(q.isosurface_rms, 0.002);
  EXPECT_GT(result.correction.along_box_face, 0u);
}

// What the raw mixing layer misses comes from its sub-cell topology: the
// folded faces sit on necks and tunnels thinner than a cell (genus 24 at
// 96^3), which the base mesh must keep and the fine mesh wraps as spirals
// and pinches. A Gaussian pre-filter of one voxel (isowave --smooth 1)
// removes those (genus 4, 29 components instead of 79), and then every
// target holds: folded 0.06%, distance to the extracted mesh 0.020 RMS and
// 0.36 cells max, coverage p99 0.12 cells.
TEST(ShrinkWrap, MixingSmoothedByOneVoxelMeetsTheTargets) {
  // Base of about 1/16 of the 29,577 extracted vertices, as for the raw field.
  expect_targets(prepare(gaussian_smoothed(make_builtin_field("mixing", 96), 1.0), 0.0, 1850), "mixing, sigma 1");
}

// The raw field sampled finer: at 128^3 its flat triangles stray less from
// the exact isosurface, and every target holds without a pre-filter
// (2026-11-26: distance to the extracted mesh 0.0454 RMS / 0.391 max,
// isosurface RMS 0.0022, coverage p99 0.26, folded 0.064%; at 112^3
// 0.0497 / 0.384, at 160^3 0.0405 / 0.400).
TEST(ShrinkWrap, MixingAt128MeetsTheTargets) {
  // Base of about 1/16 of the 70,880 extracted vertices.
  expect_targets(prepare(make_builtin_field("mixing", 128), 0.0, 4430), "mixing at 128^3");
}

TEST(ShrinkWrap, TetrahedronDropletDoesNotTurnInsideOut) {
  // A sphere of radius 2.45 cells simplified to a tetrahedron: with the
  // paper's steps every fine face ends up inside out (the relaxation shrinks
  // the tetrahedron, the attraction along its corners' normals flattens it).
  const Pipeline p = prepare(make_builtin_field("sphere", 8), 0.0, 4);
  ASSERT_EQ(p.base.vertex_count(), 4u);
  expect_targets(p, "tetrahedron droplet");  // of its 192 fine faces, none folded
}

TEST(ShrinkWrap, SmallComponentInsideAThinDiscStaysNearItsBase) {
  // A tetrahedron of radius 1.39 cells inside a disc 3 cells thick and 24
  // across: a droplet candidate whose inside reaches far. The rays from its
  // centroid that run along the disc cross the surface at the rim, 12 cells
  // away; the search along them used to reach three times the current
  // radius, so a vertex that went farther let the next round go farther
  // still, and the fit ended on the rim (miranda: vertices flung 167 cells).
  const PreparedSurface prepared = prepare_surface(
      test::sampled_volume({48, 48, 17},
                           [](double x, double y, double z) {
                             return std::min(1.5 - std::abs(z - 8.0), 12.0 - std::hypot(x - 24.0, y - 24.0));
                           }),
      PrepareOptions{}, "disc");  // a band of 3 cells
  const Volume& disc = prepared.field;
  const SignedDistanceField& distance = prepared.distance;
  const Vec3 centre{24, 24, 8};
  PolygonMesh tetrahedron;
  for (const Vec3& corner : {Vec3{1, 1, 1}, Vec3{1, -1, -1}, Vec3{-1, 1, -1}, Vec3{-1, -1, 1}})
    tetrahedron.positions.push_back(centre + 0.8 * corner);
  tetrahedron.add_face({0, 1, 2});  // outward
  tetrahedron.add_face({0, 3, 1});
  tetrahedron.add_face({0, 2, 3});
  tetrahedron.add_face({1, 3, 2});
  const SubdivisionHierarchy hierarchy(tetrahedron, 3);
  const ShrinkWrapResult result = shrink_wrap(hierarchy, tetrahedron.positions, distance, disc);
  double farthest = 0;
  std::size_t on_faces = 0;
  for (const Vec3& v : result.positions) {
    farthest = std::max(farthest, norm(v - centre));
    on_faces += std::abs(std::abs(v[2] - 8.0) - 1.5) < 0.01;
  }
  // Three times the base radius, plus the final correction's 2 cells (3.39
  // cells; 12.0, the rim, before).
  EXPECT_LE(farthest, 3 * 0.8 * std::sqrt(3.0) + 2.0);
  EXPECT_GT(on_faces, result.positions.size() / 4);  // and it did reach the disc's faces
}

// The coverage pull (ShrinkWrapOptions::coverage_pull). A ball of radius 8 cells
// with six fingers 2 cells thick and 13 long; a 24-vertex base mesh keeps
// only stubs of them, and the attraction, which moves points only along
// their own normals, leaves the rest out (coverage RMS 1.45 cells, p99 5.2).
// The pull, measured by exact distances from the extracted vertices to the
// fitted surface, brings a good part of the fingers back (RMS 0.88, p99 3.9)
// without folding or leaving the isosurface.
TEST(ShrinkWrap, CoveragePullCoversWhatTheBaseMeshCutOff) {
  Volume field = test::sampled_volume({48, 40, 40}, [](double x, double y, double z) {
    const Vec3 q{x - 14.0, y - 20.0, z - 20.0};
    double value = 8.0 - norm(q);
    for (const Vec3& axis : {Vec3{1, 0, 0}, Vec3{-1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, -1, 0}, Vec3{0, 0, 1}, Vec3{0, 0, -1}})
      value = std::max(value, 1.0 - norm(q - std::clamp(dot(q, axis), 0.0, 13.0) * axis));
    return value;
  });
  const Pipeline p = prepare(std::move(field), 0.0, 24);
  const SubdivisionHierarchy hierarchy(p.base, 3);
  const ShrinkWrapResult paper = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field);
  const ShrinkWrapResult pulled = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  const BinnedSurfaceDistance reference(p.extracted);
  const FitQuality before = measure_fit_quality(hierarchy, 3, paper.positions, p.extracted, reference, p.field, 0.0,
                                                Orientation::TowardLower);
  const FitQuality after = measure_fit_quality(hierarchy, 3, pulled.positions, p.extracted, reference, p.field, 0.0,
                                               Orientation::TowardLower);
  EXPECT_GT(before.coverage_rms, 1.0);  // the fingers are left out without the pull
  EXPECT_LT(after.coverage_rms, 0.75 * before.coverage_rms);
  EXPECT_LT(after.coverage_p99, before.coverage_p99 - 1.0);
  EXPECT_GT(pulled.levels.back().pulled_vertices, 0u);
  EXPECT_EQ(after.nonfinite_vertices, 0u);
  EXPECT_LE(after.isosurface_rms, 0.01);
  EXPECT_LE(after.folded_fraction, 0.001);
  // The finest level is pulled last, after its correction: each pulled point
  // is corrected onto the isosurface or goes back where it was, so no more
  // points lie off it than the correction itself left.
  const IsosurfaceDistance off = isosurface_distance(pulled.positions, pulled.positions.size(), p.field, 0.0, 1e-3);
  EXPECT_LE(off.far, pulled.correction.failed);
}

// A finger lying on a box face: a half ball of radius 8 cells on the z = 0
// face with a half cylinder of radius 1.5 cells along it, 16 cells long, so
// the isosurface meets the face in a keyhole-shaped loop whose long, thin
// strip the fit's boundary curve shortens (subdivision and relaxation shrink
// a closed curve, the attraction moves along the curve's normal only). The
// pull moves box-held points too, within their face, toward the strip's end
// (the engine's z = 0 face: 471 -> 93 extracted vertices over 2 cells from
// the decoded surface).
TEST(ShrinkWrap, CoveragePullStretchesBoundaryCurvesOnABoxFace) {
  Volume field = test::sampled_volume({40, 24, 12}, [](double x, double y, double z) {
    const Vec3 q{x - 10.0, y - 12.0, z};
    const double ball = 8.0 - norm(q);
    const double finger = 1.5 - norm(q - std::clamp(q.x, 0.0, 26.0) * Vec3{1, 0, 0});
    return std::max(ball, finger);
  });
  const Pipeline p = prepare(std::move(field), 0.0, 24);
  const SubdivisionHierarchy hierarchy(p.base, 3);
  const ShrinkWrapResult pulled = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  const SurfaceDistance fit(hierarchy.control_mesh(3, pulled.positions));
  double farthest = 0;
  std::size_t on_face = 0;
  for (const Vec3& v : p.extracted.positions) {
    if (v.z > 0.5) continue;
    ++on_face;
    farthest = std::max(farthest, fit.distance(v));
  }
  ASSERT_GT(on_face, 100u);
  EXPECT_LE(farthest, 2.5);  // 5.87 cells when only points off the box were pulled, 1.97 now
  const BinnedSurfaceDistance reference(p.extracted);
  const FitQuality q = measure_fit_quality(hierarchy, 3, pulled.positions, p.extracted, reference, p.field, 0.0,
                                           Orientation::TowardLower);
  EXPECT_EQ(q.nonfinite_vertices, 0u);
  EXPECT_LE(q.isosurface_rms, 0.01);
  EXPECT_LE(q.folded_fraction, 0.001);
}

TEST(ShrinkWrap, BoundaryCurvesLeaveABoxEdgeIntoTheFaceTheyLieIn) {
  // The sheet y = 15 - 0.7 (1 - ((z - 7.5) / 4)^2) (inside above it) meets
  // the box edges x = 0, y = 15 and x = 15, y = 15 at z = 3.5 and 11.5, and
  // between them its boundary curves bulge 0.7 cell into the faces x = 0 and
  // x = 15. The base is two quads lying on the face y = 15, so each of those
  // curves starts as one edge along a box edge; refinement puts its new
  // vertices on that box edge, and only held on x = 0 or x = 15 (rather than
  // on y = 15, where the isosurface stays on the box edge) can they reach
  // the curve.
  const auto sheet = [](double, double y, double z) {
    const double s = (z - 7.5) / 4.0;
    return y - 15.0 + 0.7 * (1.0 - s * s);
  };
  PrepareOptions whole_grid;
  whole_grid.distance_band_cells = 0;
  PreparedSurface prepared = prepare_surface(test::sampled_volume({16, 16, 16}, sheet), whole_grid, "sheet");
  Pipeline p{std::move(prepared.field), 0, std::move(prepared.isosurface.mesh), {}, std::move(prepared.distance)};
  p.base.positions = {{0, 15, 3.5}, {7.5, 15, 3.5}, {15, 15, 3.5}, {0, 15, 11.5}, {7.5, 15, 11.5}, {15, 15, 11.5}};
  p.base.sharp = {1, 0, 1, 1, 0, 1};
  p.base.add_face({0, 1, 4, 3});  // normal -y: outward, toward lower values
  p.base.add_face({1, 2, 5, 4});
  const SubdivisionHierarchy hierarchy(p.base, 3);

  // The rule itself: level 1's vertex on the edge x = 15, y = 15 is held on
  // x = 15 (face 1), and without an isovalue on the last face, y = 15 (3).
  std::vector<Vec3> level1 = p.base.positions;
  level1.resize(hierarchy.vertex_count(3));
  subdivide_level(hierarchy, 1, level1);
  std::size_t on_edge = 0;
  const WrapLevelMesh with_iso = make_wrap_level_mesh(hierarchy, 1, level1, p.field, 0.0);
  const WrapLevelMesh without = make_wrap_level_mesh(hierarchy, 1, level1, p.field);
  for (std::size_t v = 0; v < with_iso.vertex_count; ++v) {
    if (with_iso.role[v] != WrapRole::Boundary || level1[v].y != 15 || (level1[v].x != 0 && level1[v].x != 15)) continue;
    ++on_edge;
    EXPECT_EQ(with_iso.box_face[v], level1[v].x == 0 ? 0 : 1) << "vertex " << v;
    EXPECT_EQ(without.box_face[v], 3) << "vertex " << v;
  }
  EXPECT_EQ(on_edge, 2u);

  const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  const WrapLevelMesh fine = make_wrap_level_mesh(hierarchy, 3, result.positions, p.field, 0.0);
  const TrilinearGrid field(p.field);
  std::size_t on_curves = 0;
  for (std::size_t v = 0; v < fine.vertex_count; ++v) {
    if (fine.role[v] != WrapRole::Boundary || (fine.box_face[v] >> 1) != 0) continue;
    ++on_curves;
    const Vec3& x = result.positions[v];
    const TrilinearSample s = field.sample(x);
    EXPECT_LE(std::abs(s.value) / norm(s.gradient), 0.01) << "vertex " << v << " at " << x.y << ", " << x.z;
    EXPECT_NEAR(x.y, 15.0 - 0.7 * (1.0 - std::pow((x.z - 7.5) / 4.0, 2)), 0.02) << "vertex " << v;
  }
  EXPECT_EQ(on_curves, 2u * 7u);  // 2^3 - 1 new vertices along each curve
}

TEST(ShrinkWrap, ResultDoesNotDependOnThreadCount) {
  const Pipeline p = prepare(make_builtin_field("marschner-lobb", 48), 0.0, 200);
  const SubdivisionHierarchy hierarchy(p.base, 2);
  ShrinkWrapOptions options = options_for(p);
  options.pull_max_edge_cells = 2.0;  // level 2's edges average 1.07 cells: pull there too
  options.unfold_max_folded_fraction = 1.0;  // 62 faces folded, over the default limit: unfold too
  std::vector<Vec3> one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options).positions;
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options);
    EXPECT_GT(result.levels.back().pulled_vertices, 0u);
    EXPECT_GT(result.unfold.moved, 0u);
    two = result.positions;
  }
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t v = 0; v < one.size(); ++v) ASSERT_TRUE(one[v] == two[v]) << "vertex " << v;
}

// Without untangle() the unfold's limit is judged by a count of its own, and
// the result reports that count (before, the unfold then always ran, and the
// count was 0 when it did not: 14.5 s of unfolding on miranda).
TEST(ShrinkWrap, WithoutTheUntangleTheUnfoldLimitStillHolds) {
  const Pipeline p = prepare(make_builtin_field("marschner-lobb", 48), 0.0, 200);
  const SubdivisionHierarchy hierarchy(p.base, 2);
  ShrinkWrapOptions options = options_for(p);
  options.untangle_rounds = 0;
  options.unfold_max_folded_fraction = 0.0;  // unfold only a fit without folds
  const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options);
  const BinnedSurfaceDistance reference(p.extracted);
  const FitQuality q = measure_fit_quality(hierarchy, 2, result.positions, p.extracted, reference, p.field, p.iso,
                                           Orientation::TowardLower);
  ASSERT_GT(q.folded_faces, 0u);
  EXPECT_TRUE(result.unfold.skipped);
  EXPECT_EQ(result.unfold.moved, 0u);
  EXPECT_EQ(result.folded_faces, q.folded_faces);  // the same measure, counted independently
}

TEST(ShrinkWrap, BoundaryVerticesStayOnTheBoxAndSharpOnesNeverMove) {
  // Marschner-Lobb meets the four side faces of the box.
  const Pipeline p = prepare(make_builtin_field("marschner-lobb", 48), 0.0, 200);
  ASSERT_GT(p.base.sharp_count(), 0u);
  const SubdivisionHierarchy hierarchy(p.base, 2);
  const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  const WrapLevelMesh mesh = make_wrap_level_mesh(hierarchy, 2, result.positions, p.field);
  const Vec3 high = volume_box_max(p.field), low = volume_box_min(p.field);
  std::size_t on_box = 0;
  for (std::size_t v = 0; v < mesh.vertex_count; ++v) {
    const Vec3& x = result.positions[v];
    for (int a = 0; a < 3; ++a) ASSERT_TRUE(x[a] >= low[a] && x[a] <= high[a]);
    if (mesh.role[v] == WrapRole::Boundary) {
      ASSERT_GE(mesh.box_face[v], 0) << "boundary vertex " << v << " not on a box face";
      const int face = mesh.box_face[v];
      EXPECT_EQ(x[face >> 1], (face & 1) ? high[face >> 1] : low[face >> 1]);
      ++on_box;
    }
    if (v < p.base.vertex_count() && p.base.is_sharp(v)) {
      EXPECT_TRUE(x == p.base.positions[v]);
    }
  }
  EXPECT_GT(on_box, 0u);
}

TEST(ShrinkWrap, RelaxationAveragesWithTheNeighbourCentroid) {
  // A flat 4x4 grid of quads: an interior vertex moved off the plane comes
  // half-way back; boundary vertices average only along the boundary.
  PolygonMesh grid = test::quad_grid(4, 4);
  for (Vec3& p : grid.positions) p += Vec3{2, 2, 2};
  Volume box;
  box.dims = {10, 10, 10};
  box.values.assign(box.sample_count(), 0.0f);
  const SubdivisionHierarchy hierarchy(grid, 1);
  std::vector<Vec3> in = grid.positions;
  const std::uint32_t centre = 12;  // (2, 2) in the 5x5 vertex grid
  in[centre].z += 1.0;
  const WrapLevelMesh mesh = make_wrap_level_mesh(hierarchy, 0, in, box);
  std::vector<Vec3> out;
  relax(mesh, box, 0.5, in, out);
  EXPECT_NEAR(out[centre].z, 2.5, 1e-12);
  EXPECT_NEAR(out[centre].x, in[centre].x, 1e-12);
  const std::uint32_t edge = 2;  // (2, 0): on the boundary, neighbours (1, 0) and (3, 0) along it
  EXPECT_EQ(mesh.role[edge], WrapRole::Boundary);
  EXPECT_NEAR(out[edge].y, in[edge].y, 1e-12);
}

TEST(ShrinkWrap, CorrectionRetriesFromTheNeighboursCentroid) {
  // The plane z = 4 (field 10 - z, iso 6) and a 4 x 4 quad grid on it whose
  // centre vertex is lifted 5 cells: its root along the gradient lies beyond
  // the 2-cell search, its neighbours' centroid is on the plane.
  const Volume field = test::sampled_volume({12, 12, 12}, [](double, double, double z) { return 10.0 - z; });
  PolygonMesh grid = test::quad_grid(4, 4);
  for (Vec3& p : grid.positions) p += Vec3{3, 3, 4};
  const std::uint32_t centre = 12;  // (2, 2) in the 5x5 vertex grid
  std::vector<Vec3> positions = grid.positions;
  positions[centre].z += 5.0;
  const SubdivisionHierarchy hierarchy(grid, 1);
  const WrapLevelMesh mesh = make_wrap_level_mesh(hierarchy, 0, positions, field);
  ASSERT_EQ(mesh.role[centre], WrapRole::Free);
  const CorrectionStatistics stats = correct_to_isosurface(mesh, field, 6.0, 2.0, positions);
  EXPECT_EQ(stats.from_neighbours, 1u);
  EXPECT_EQ(stats.failed, 0u);
  EXPECT_NEAR(positions[centre].x, 5.0, 1e-9);
  EXPECT_NEAR(positions[centre].y, 5.0, 1e-9);
  EXPECT_NEAR(positions[centre].z, 4.0, 1e-9);
  EXPECT_NEAR(stats.max_move_cells, 5.0, 1e-9);
}

// An nx x ny quad grid 3 cells above the plane z = 4 (field 10 - z, iso 6:
// normals toward +z, as the grid's): every vertex's root along the gradient,
// and its neighbours' centroid's, lies beyond a 2-cell search.
struct GridAbovePlane {
  Volume field;
  PolygonMesh grid;
  WrapLevelMesh mesh;
};
GridAbovePlane grid_above_plane(int nx, int ny) {
  GridAbovePlane g;
  g.field = test::sampled_volume({std::size_t(nx) + 4, std::size_t(ny) + 4, 12},
                                 [](double, double, double z) { return 10.0 - z; });
  g.grid = test::quad_grid(nx, ny);
  for (Vec3& p : g.grid.positions) p += Vec3{2, 2, 7};
  g.mesh = make_wrap_level_mesh(SubdivisionHierarchy(g.grid, 1), 0, g.grid.positions, g.field);
  return g;
}

TEST(ShrinkWrap, CorrectionsWideSearchFindsRootsBeyondItsRange) {
  // The wide search (6 cells, 26 directions) finds each root straight below,
  // which folds no face (a vertical move keeps a face's projected area).
  const GridAbovePlane g = grid_above_plane(4, 4);
  std::vector<Vec3> narrow = g.grid.positions;
  EXPECT_EQ(correct_to_isosurface(g.mesh, g.field, 6.0, 2.0, narrow).failed, g.grid.vertex_count());
  std::vector<Vec3> wide = g.grid.positions;
  const CorrectionStatistics stats = correct_to_isosurface(g.mesh, g.field, 6.0, 2.0, wide, {Orientation::TowardLower});
  EXPECT_EQ(stats.from_wide_search, g.grid.vertex_count());
  EXPECT_EQ(stats.failed, 0u);
  for (std::size_t v = 0; v < wide.size(); ++v) {
    EXPECT_NEAR(wide[v].z, 4.0, 1e-4) << "vertex " << v;
    EXPECT_NEAR(wide[v].x, g.grid.positions[v].x, 1e-12) << "vertex " << v;
    EXPECT_NEAR(wide[v].y, g.grid.positions[v].y, 1e-12) << "vertex " << v;
  }
  // Beyond three times the range it gives up: 7 cells above the plane.
  std::vector<Vec3> far = g.grid.positions;
  for (Vec3& p : far) p.z = 11.0;
  EXPECT_EQ(correct_to_isosurface(g.mesh, g.field, 6.0, 2.0, far, {Orientation::TowardLower}).failed,
            g.grid.vertex_count());
}

TEST(ShrinkWrap, CorrectionStartsStrandedVerticesFromTheExtractedSurface) {
  // A 4 x 4 quad grid 9 cells above the plane z = 4 (field 10 - z, iso 6), where
  // neither the gradient line (2 cells) nor the wide search (6 cells)
  // reaches; with the extracted plane and its distance field (|d| >= 1
  // cell: stranded), each vertex starts again from the plane's nearest
  // point, straight below. A grid 20 cells above, beyond the 16-cell reach,
  // stays, and so does one 40 above (no face near enough to search).
  const Volume field = test::sampled_volume({12, 12, 48}, [](double, double, double z) { return 10.0 - z; });
  const Volume distance = test::sampled_volume({12, 12, 48}, [](double, double, double z) {
    return std::clamp(z - 4.0, -3.0, 3.0);  // as a band of 3 cells leaves it
  });
  PolygonMesh plane = test::quad_grid(11, 11);
  for (Vec3& p : plane.positions) p.z = 4.0;
  PolygonMesh grid = test::quad_grid(4, 4);  // free: over a cell from the box's sides
  for (Vec3& p : grid.positions) p += Vec3{4, 4, 13};
  const WrapLevelMesh mesh = make_wrap_level_mesh(SubdivisionHierarchy(grid, 1), 0, grid.positions, field);
  for (std::size_t v = 0; v < grid.vertex_count(); ++v) ASSERT_LT(mesh.box_face[v], 0);
  std::vector<Vec3> without = grid.positions;
  EXPECT_EQ(correct_to_isosurface(mesh, field, 6.0, 2.0, without, {Orientation::TowardLower}).failed,
            grid.vertex_count());
  std::vector<Vec3> with = grid.positions;
  const CorrectionFallbacks fallbacks{Orientation::TowardLower, &plane, &distance};
  const CorrectionStatistics stats = correct_to_isosurface(mesh, field, 6.0, 2.0, with, fallbacks);
  EXPECT_EQ(stats.from_extracted_surface, grid.vertex_count());
  EXPECT_EQ(stats.failed, 0u);
  EXPECT_NEAR(stats.max_move_cells, 9.0, 1e-6);
  for (std::size_t v = 0; v < with.size(); ++v) {
    EXPECT_NEAR(with[v].z, 4.0, 1e-4) << "vertex " << v;
    EXPECT_NEAR(with[v].x, grid.positions[v].x, 1e-9) << "vertex " << v;
    EXPECT_NEAR(with[v].y, grid.positions[v].y, 1e-9) << "vertex " << v;
  }
  std::vector<Vec3> far = grid.positions;
  for (Vec3& p : far) p.z = 24.0;
  const CorrectionStatistics beyond = correct_to_isosurface(mesh, field, 6.0, 2.0, far, fallbacks);
  EXPECT_EQ(beyond.from_extracted_surface, 0u);
  EXPECT_EQ(beyond.failed, grid.vertex_count());
  for (Vec3& p : far) p.z = 44.0;
  const std::vector<Vec3> farther = far;
  EXPECT_EQ(correct_to_isosurface(mesh, field, 6.0, 2.0, far, fallbacks).failed,
            grid.vertex_count());
  EXPECT_EQ(far, farther);
}

TEST(ShrinkWrap, EmbryosStrandedPointsEndOnTheIsosurface) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/embryo_256x256x256.nrrd");
  // A base of 1/16 of the 440,365 extracted vertices (components under 50
  // dropped, as bench_fit does): some of its faces span voids, and refined, their
  // points fall up to 8 cells from any surface, where the 8-bit field is
  // nearly flat. Before the correction started them from the extracted
  // surface, 80 points stayed over a cell off the isosurface (the worst 655
  // cells by the first-order measure), RMS 0.668.
  const Pipeline p = prepare(read_volume(path), 50, 440365 / 16, 50);
  ASSERT_EQ(p.extracted.vertex_count(), 440365u);
  const SubdivisionHierarchy hierarchy(p.base, 3);
  const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  EXPECT_GT(result.correction.from_extracted_surface, 0u);
  const IsosurfaceDistance off = isosurface_distance(result.positions, result.positions.size(), p.field, p.iso, 1.0);
  EXPECT_LE(off.rms, 0.01);
  EXPECT_EQ(off.far, 0u);
}

TEST(ShrinkWrap, CorrectionsWideSearchIsALastResortForFewVertices) {
  // A 110 x 100 grid (11,211 vertices): the wide search takes the first
  // 10,000 failures (1% of the vertices, but at least 10,000).
  const GridAbovePlane g = grid_above_plane(110, 100);
  std::vector<Vec3> positions = g.grid.positions;
  const CorrectionStatistics stats = correct_to_isosurface(g.mesh, g.field, 6.0, 2.0, positions,
                                                           {Orientation::TowardLower});
  EXPECT_EQ(stats.from_wide_search, 10000u);
  EXPECT_EQ(stats.failed, g.grid.vertex_count() - 10000);
  for (std::size_t v = 0; v < positions.size(); ++v)
    ASSERT_NEAR(positions[v].z, v < 10000 ? 4.0 : 7.0, 1e-4) << "vertex " << v;
}

TEST(ShrinkWrap, UnfoldOpensAFoldAndKeepsThePointsOnTheIsosurface) {
  // A fold on the plane z = 4 (field 10 - z, iso 6: normals toward +z): an
  // interior column of an 8 x 8 quad grid pushed 0.7 past the next, which
  // inverts the six faces between them that no boundary corner holds.
  const Volume field = test::sampled_volume({20, 20, 20}, [](double, double, double z) { return 10.0 - z; });
  PolygonMesh grid = test::quad_grid(8, 8);
  for (Vec3& p : grid.positions) p += Vec3{3, 3, 4};
  std::vector<Vec3> folded = grid.positions;
  for (int row = 1; row < 8; ++row) folded[std::size_t(row) * 9 + 3].x = 3 + 4.7;
  const SubdivisionHierarchy hierarchy(grid, 1);
  const WrapLevelMesh mesh = make_wrap_level_mesh(hierarchy, 0, folded, field);
  std::vector<Vec3> flat = grid.positions;
  // The grid's own orientation.
  ASSERT_EQ(unfold(mesh, field, 6.0, Orientation::TowardLower, 0, 2.0, flat).folded_before, 0u);
  std::vector<Vec3> unfolded = folded;
  const UnfoldStatistics stats = unfold(mesh, field, 6.0, Orientation::TowardLower, 10, 2.0, unfolded);
  EXPECT_EQ(stats.folded_before, 6u);
  EXPECT_EQ(stats.folded_after, 0u);
  EXPECT_GT(stats.moved, 0u);
  for (std::size_t v = 0; v < unfolded.size(); ++v) EXPECT_NEAR(unfolded[v].z, 4.0, 1e-9) << "vertex " << v;
  std::vector<Vec3> one_thread = folded;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    unfold(mesh, field, 6.0, Orientation::TowardLower, 10, 2.0, one_thread);
  }
  for (std::size_t v = 0; v < unfolded.size(); ++v) ASSERT_TRUE(one_thread[v] == unfolded[v]) << "vertex " << v;
}

TEST(ShrinkWrap, CorrectionSearchesAlongABoxFaceWhenTheGradientLeavesTheBox) {
  // Field y - x, iso 5: the surface y = x + 5. A free vertex at x = 0.3 has
  // its root along the gradient (-1, 1, 0) outside the box (x = -0.35); along
  // the face x = 0 it is 1.3 cells away, at y = 5.3.
  const Volume field = test::sampled_volume({10, 10, 10}, [](double x, double y, double) { return y - x; });
  PolygonMesh grid = test::quad_grid(4, 4);
  for (Vec3& p : grid.positions) p += Vec3{3, 3, 2};
  const std::uint32_t centre = 12;  // interior: free
  grid.positions[centre] = {0.3, 4.0, 2.0};
  const SubdivisionHierarchy hierarchy(grid, 1);
  std::vector<Vec3> positions = grid.positions;
  const WrapLevelMesh mesh = make_wrap_level_mesh(hierarchy, 0, positions, field);
  ASSERT_EQ(mesh.role[centre], WrapRole::Free);
  ASSERT_LT(mesh.box_face[centre], 0);
  const CorrectionStatistics stats = correct_to_isosurface(mesh, field, 5.0, 2.0, positions);
  EXPECT_GE(stats.along_box_face, 1u);
  EXPECT_NEAR(positions[centre].x, 0.3, 1e-12);
  EXPECT_NEAR(positions[centre].y, 5.3, 1e-3);
  EXPECT_NEAR(positions[centre].z, 2.0, 1e-12);
}

TEST(ShrinkWrap, CorrectionSearchesWithinABoxFaceWhereTheGradientIsNormalToIt) {
  // Field min(3 - r, 1 + z), r the distance from the axis x = y = 8, iso 0:
  // a cylinder of radius 3 cut open by the face z = 0, inside which the
  // gradient is (0, 0, 1) where r < 2 + z. A 2 x 2 quad grid on that face
  // around the axis (vertices 1.5 cells apart): the four corners (r = 2.1)
  // find the circle along the gradient; the four edge midpoints (r = 1.5)
  // find no root along it or its part within the face, only by searching
  // the face; the centre is 3 cells from the circle, out of range.
  const Volume field = test::sampled_volume({16, 16, 8}, [](double x, double y, double z) {
    return std::min(3.0 - std::hypot(x - 8.0, y - 8.0), 1.0 + z);
  });
  PolygonMesh grid = test::quad_grid(2, 2);
  for (Vec3& p : grid.positions) p = Vec3{8.0 + 1.5 * (p.x - 1.0), 8.0 + 1.5 * (p.y - 1.0), 0.0};
  const SubdivisionHierarchy hierarchy(grid, 1);
  std::vector<Vec3> positions = grid.positions;
  const WrapLevelMesh mesh = make_wrap_level_mesh(hierarchy, 0, positions, field);
  const CorrectionStatistics stats = correct_to_isosurface(mesh, field, 0.0, 2.0, positions);
  EXPECT_EQ(stats.along_box_face, 4u);
  EXPECT_EQ(stats.failed, 1u);
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const Vec3 from = grid.positions[v] - Vec3{8, 8, 0}, to = positions[v] - Vec3{8, 8, 0};
    EXPECT_EQ(positions[v].z, 0.0) << "vertex " << v;
    if (norm(from) == 0) {
      EXPECT_TRUE(to == from);  // the centre: no root within 2 cells
      continue;
    }
    // Radially out onto the trilinear interpolant's circle (the samples' r
    // interpolated: within 0.05 of radius 3).
    EXPECT_NEAR(norm(to), 3.0, 0.05) << "vertex " << v;
    EXPECT_NEAR(dot(to, from) / (norm(to) * norm(from)), 1.0, 1e-9) << "vertex " << v;
  }
}

TEST(FitQuality, FineFacesAreNumberedByParentFace) {
  // The evenness figure assigns level-l face j to level-1 face j >> 2(l-1):
  // each quad's first corner (a v vertex) must be a corner of that parent.
  const SubdivisionHierarchy hierarchy(test::mixed_disk(), 3);
  for (int level = 2; level <= 3; ++level) {
    const PolygonMesh fine = hierarchy.control_mesh(level, std::vector<Vec3>(hierarchy.vertex_count(level)));
    const PolygonMesh parent = hierarchy.control_mesh(level - 1, std::vector<Vec3>(hierarchy.vertex_count(level - 1)));
    for (std::size_t f = 0; f < fine.face_count(); ++f) {
      const std::uint32_t* parent_face = parent.face_begin(f / 4);
      const std::uint32_t corner = fine.face_begin(f)[0];
      ASSERT_TRUE(std::find(parent_face, parent_face + 4, corner) != parent_face + 4) << "level " << level << " face " << f;
    }
  }
}

TEST(FitQuality, ReportsDistancesFoldsAndEvenness) {
  const Pipeline p = prepare(make_builtin_field("sphere", 40), 0.0, 60);
  const SubdivisionHierarchy hierarchy(p.base, 2);
  const BinnedSurfaceDistance reference(p.extracted);
  // Perfect fit: the sphere's own subdivided control points pulled onto the isosurface.
  const ShrinkWrapResult result = shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options_for(p));
  const FitQuality good = measure_fit_quality(hierarchy, 2, result.positions, p.extracted, reference, p.field, 0.0,
                                              Orientation::TowardLower);
  EXPECT_EQ(good.folded_faces, 0u);
  EXPECT_LT(good.surface_max, 0.5);
  EXPECT_EQ(good.surface_far, 0u);
  EXPECT_EQ(good.isosurface_far, 0u);
  // The distances both ways are CGAL's (AABB trees, the reference).
  {
    const PolygonMesh fitted = hierarchy.control_mesh(2, result.positions);
    const auto rms_max = [&](const std::vector<double>& d) {
      double sum = 0, max = 0;
      for (double x : d) sum += x * x, max = std::max(max, x);
      return std::pair<double, double>{std::sqrt(sum / double(d.size())) / p.field.cell_size(), max / p.field.cell_size()};
    };
    const auto [surface_rms, surface_max] = rms_max(SurfaceDistance(p.extracted).distances(fitted.positions));
    const auto [coverage_rms, coverage_max] = rms_max(SurfaceDistance(fitted).distances(p.extracted.positions));
    EXPECT_NEAR(good.surface_rms, surface_rms, 1e-9);
    EXPECT_NEAR(good.surface_max, surface_max, 1e-9);
    EXPECT_NEAR(good.coverage_rms, coverage_rms, 1e-9);
    EXPECT_NEAR(good.coverage_max, coverage_max, 1e-9);
    EXPECT_GT(coverage_max, 0.0);
  }
  // The same mesh with reversed orientation is entirely folded.
  const FitQuality flipped = measure_fit_quality(hierarchy, 2, result.positions, p.extracted, reference, p.field,
                                                 0.0, Orientation::TowardHigher);
  EXPECT_EQ(flipped.folded_faces, flipped.faces);
  // Moving one vertex 3 cells outward shows in the maximum distances.
  std::vector<Vec3> moved = result.positions;
  const Vec3 centre{19.5, 19.5, 19.5};
  moved[0] = moved[0] + 3.0 * normalized(moved[0] - centre);
  const FitQuality bad = measure_fit_quality(hierarchy, 2, moved, p.extracted, reference, p.field, 0.0,
                                             Orientation::TowardLower);
  EXPECT_NEAR(bad.surface_max, 3.0, 0.3);
  EXPECT_EQ(bad.surface_far, 1u);
  EXPECT_GT(bad.isosurface_max, 2.5);
  EXPECT_EQ(bad.isosurface_far, 1u);  // the field is a distance: that vertex alone is over a cell off
  // Sliding one corner of a fine face 95% of the way to the opposite corner
  // shrinks that face to a sliver: the smallest area ratio drops.
  const PolygonMesh fine = hierarchy.control_mesh(2, result.positions);
  const std::uint32_t* face = fine.face_begin(0);
  std::vector<Vec3> squeezed = result.positions;
  squeezed[face[0]] = result.positions[face[0]] + 0.95 * (result.positions[face[2]] - result.positions[face[0]]);
  const FitQuality uneven =
      measure_fit_quality(hierarchy, 2, squeezed, p.extracted, reference, p.field, 0.0, Orientation::TowardLower);
  EXPECT_LT(uneven.area_ratio_min, 0.5 * good.area_ratio_min);
}

TEST(ShrinkWrap, RejectsBadInput) {
  const Pipeline p = prepare(make_builtin_field("sphere", 24), 0.0, 50);
  const SubdivisionHierarchy hierarchy(p.base, 1);
  std::vector<Vec3> positions = p.base.positions;
  positions.pop_back();
  EXPECT_THROW(shrink_wrap(hierarchy, positions, p.distance, p.field), Error);
  positions = p.base.positions;
  positions[0].x = std::nan("");
  EXPECT_THROW(shrink_wrap(hierarchy, positions, p.distance, p.field), Error);
  // A base from another volume: more than a cell outside the box (within
  // a cell is tolerated, as rounding in a written base mesh would be).
  const double cell = p.field.cell_size();
  positions = p.base.positions;
  positions[0].x = volume_box_max(p.field).x + 1.5 * cell;
  EXPECT_THROW(shrink_wrap(hierarchy, positions, p.distance, p.field), Error);
  positions[0].x = volume_box_max(p.field).x + 0.5 * cell;
  EXPECT_NO_THROW(shrink_wrap(hierarchy, positions, p.distance, p.field));
  // A base facing the other way (extracted with the other flip): every
  // face reversed.
  PolygonMesh reversed = p.base;
  for (std::size_t f = 0; f < reversed.face_count(); ++f)
    std::reverse(reversed.face_vertices.begin() + reversed.face_offsets[f],
                 reversed.face_vertices.begin() + reversed.face_offsets[f + 1]);
  EXPECT_THROW(shrink_wrap(SubdivisionHierarchy(reversed, 1), reversed.positions, p.distance, p.field), Error);
  // A base with a hole inside the box (one face left out), where the
  // extracted sphere has none. (Bases whose boundary lies on the box are
  // fitted: BoundaryVerticesStayOnTheBoxAndSharpOnesNeverMove.)
  PolygonMesh holed;
  holed.positions = p.base.positions;
  for (std::size_t f = 1; f < p.base.face_count(); ++f) holed.add_face(p.base.face_begin(f), p.base.face_size(f));
  try {
    shrink_wrap(SubdivisionHierarchy(holed, 1), holed.positions, p.distance, p.field);
    ADD_FAILURE() << "a base with a hole inside the box was fitted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("on a boundary of the base mesh"), std::string::npos) << error.what();
  }
  ShrinkWrapOptions options;
  options.relaxation_weight = 0;
  EXPECT_THROW(shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options), Error);
  options = options_for(p);
  options.pull_reach_cells = 0.5 * options.pull_covered_cells;
  EXPECT_THROW(shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options), Error);
  options = options_for(p);
  options.final_pull_reach_cells = std::numeric_limits<double>::infinity();
  EXPECT_THROW(shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options), Error);
  options = ShrinkWrapOptions();
  options.unfold_rounds = -1;
  EXPECT_THROW(shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options), Error);
  options = ShrinkWrapOptions();
  options.unfold_max_folded_fraction = std::nan("");
  EXPECT_THROW(shrink_wrap(hierarchy, p.base.positions, p.distance, p.field, options), Error);
  const Volume other = make_builtin_field("sphere", 20);
  EXPECT_THROW(shrink_wrap(hierarchy, p.base.positions, p.distance, other), Error);
}

}  // namespace
}  // namespace isowave
