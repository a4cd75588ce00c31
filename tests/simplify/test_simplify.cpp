// Whole-stage tests of simplify() (paper Sec. 4.1): topology preserved, face
// sizes 3..5, valences 3..8 (2..8 on the boundary), 2-manifold and
// consistently oriented output, target reached, and bad input rejected.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <limits>
#include <string>

#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "isowave/simplify/collapse_mesh.h"
#include "isowave/simplify/simplify.h"
#include "simplify_test_meshes.h"

namespace isowave::simplify {
namespace {

using Edge = std::pair<std::uint32_t, std::uint32_t>;

// Each edge of a polygon mesh (smaller index first) with the number of faces
// it borders, counted directly from the face list (independent of the report).
std::map<Edge, int> edge_face_counts(const PolygonMesh& mesh) {
  std::map<Edge, int> edges;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) {
      const std::uint32_t u = face[k], w = face[(k + 1) % mesh.face_size(f)];
      ++edges[{std::min(u, w), std::max(u, w)}];
    }
  }
  return edges;
}

// The edges of one face only, each as its face orients it.
std::vector<Edge> boundary_edges(const PolygonMesh& mesh) {
  const std::map<Edge, int> counts = edge_face_counts(mesh);
  std::vector<Edge> boundary;
  for (std::size_t f = 0; f < mesh.face_count(); ++f)
    for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) {
      const std::uint32_t u = mesh.face_begin(f)[k], w = mesh.face_begin(f)[(k + 1) % mesh.face_size(f)];
      if (counts.at({std::min(u, w), std::max(u, w)}) == 1) boundary.push_back({u, w});
    }
  return boundary;
}

// Valence and boundary flag per vertex of a polygon mesh.
void valences(const PolygonMesh& mesh, std::vector<int>& valence, std::vector<bool>& boundary) {
  const std::map<Edge, int> edges = edge_face_counts(mesh);
  valence.assign(mesh.vertex_count(), 0);
  boundary.assign(mesh.vertex_count(), false);
  for (const auto& [edge, count] : edges) {
    ++valence[edge.first];
    ++valence[edge.second];
    if (count == 1) boundary[edge.first] = boundary[edge.second] = true;
  }
}

int max_valence_of(const PolygonMesh& mesh) {
  std::vector<int> valence;
  std::vector<bool> boundary;
  valences(mesh, valence, boundary);
  return valence.empty() ? 0 : *std::max_element(valence.begin(), valence.end());
}

// Checks every property the issue asks of a base mesh built from `input`.
void expect_valid_base_mesh(const PolygonMesh& input, const SimplifyResult& result, const std::string& name,
                            bool input_valences_in_range = true) {
  SCOPED_TRACE(name);
  const PolygonMesh& base = result.base;
  ASSERT_NO_THROW(require_manifold(base, name + " base mesh"));
  const TopologySummary before = summarize_topology(input);
  const TopologySummary after = summarize_topology(base);
  EXPECT_EQ(after.genus, before.genus);
  EXPECT_EQ(after.components, before.components);
  EXPECT_EQ(after.boundary_loops, before.boundary_loops);
  EXPECT_EQ(result.report.input_genus, before.genus);
  EXPECT_EQ(result.report.input_components, before.components);
  EXPECT_EQ(result.report.input_boundary_loops, before.boundary_loops);
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    ASSERT_GE(base.face_size(f), 3u);
    ASSERT_LE(base.face_size(f), 5u);
  }
  std::vector<int> valence;
  std::vector<bool> boundary;
  valences(base, valence, boundary);
  std::size_t outside = 0;
  for (std::size_t v = 0; v < base.vertex_count(); ++v)
    if (valence[v] < (boundary[v] ? 2 : 3) || valence[v] > 8) ++outside;
  if (input_valences_in_range) {
    EXPECT_EQ(outside, 0u);
  }
  EXPECT_EQ(outside, result.report.vertices_outside_valence_range);
  EXPECT_EQ(base.vertex_count(), result.report.output_vertices);
  EXPECT_EQ(base.face_count(), result.report.output_faces);
  EXPECT_EQ(base.sharp.empty(), input.sharp.empty());
  // Sharp vertices are never merged away from their position: the base has
  // a sharp vertex exactly where the input has one, and no other.
  EXPECT_EQ(test::sharp_positions(base), test::sharp_positions(input));
  std::size_t face_total = 0;
  for (std::size_t s = 0; s < result.report.face_size_histogram.size(); ++s)
    face_total += result.report.face_size_histogram[s];
  EXPECT_EQ(face_total, base.face_count());
}

void expect_target(const SimplifyResult& result, std::size_t target) {
  if (result.report.vertices_after_collapse <= target + target / 20) return;
  // Not reached: the report must say why.
  EXPECT_FALSE(result.report.target_reached);
  EXPECT_NE(result.report.stop_reason.find("no legal collapse"), std::string::npos) << result.report.stop_reason;
  ADD_FAILURE() << "target " << target << " not reached: " << result.report.stop_reason;
}

// --- generated meshes, with the invariant check after every collapse ---

struct Generated {
  std::string name;
  PolygonMesh mesh;
  std::size_t target;
};

std::vector<Generated> generated_meshes() {
  std::vector<Generated> meshes;
  meshes.push_back({"sphere", test::icosphere(3), 40});
  meshes.push_back({"torus", test::fan_triangulate(test::quad_grid(24, 12, true, true)), 30});
  meshes.push_back({"cylinder", test::fan_triangulate(test::quad_grid(16, 10, true, false)), 24});
  meshes.push_back({"disk", test::fan_triangulate(test::quad_grid(12, 12)), 20});
  meshes.push_back({"genus2_slab", test::fan_triangulate(test::genus_slab(2)), 24});
  meshes.push_back({"genus3_slab", test::fan_triangulate(test::genus_slab(3)), 32});
  // Two components: a sphere and a torus side by side.
  PolygonMesh pair = test::icosphere(2);
  const PolygonMesh torus = test::fan_triangulate(test::quad_grid(16, 8, true, true));
  const std::uint32_t offset = static_cast<std::uint32_t>(pair.vertex_count());
  for (const Vec3& p : torus.positions) pair.positions.push_back(p + Vec3{10, 0, 0});
  for (std::size_t f = 0; f < torus.face_count(); ++f) {
    const std::uint32_t* t = torus.face_begin(f);
    pair.add_face({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  meshes.push_back({"sphere_and_torus", pair, 30});
  return meshes;
}

TEST(Simplify, GeneratedMeshesKeepTheirTopologyWithInvariantsCheckedAfterEveryCollapse) {
  for (const bool lazy : {true, false})
    for (Generated& generated : generated_meshes()) {
      SCOPED_TRACE(lazy ? "lazy stencil" : "eager stencil");
      test::jitter(generated.mesh, 0.01, 3);
      SimplifyOptions options;
      options.target_vertices = generated.target;
      options.lazy_stencil = lazy;
      options.validate_every_collapse = true;
      const SimplifyResult result = simplify(generated.mesh, options);
      expect_valid_base_mesh(generated.mesh, result, generated.name);
      expect_target(result, generated.target);
      EXPECT_GT(result.report.collapses, 0u);
    }
}

// The lazy stencil update changes the collapse order only where a priority
// rose; the base mesh stays about as close to the input as the paper's
// eager update makes it.
TEST(Simplify, LazyStencilBaseMeshIsAsCloseToTheInputAsTheEagerOne) {
  double lazy_sum = 0, eager_sum = 0;
  for (Generated& generated : generated_meshes()) {
    test::jitter(generated.mesh, 0.01, 5);
    SimplifyOptions options;
    options.target_vertices = generated.mesh.vertex_count() / 4;
    const SimplifyResult lazy = simplify(generated.mesh, options);
    options.lazy_stencil = false;
    const SimplifyResult eager = simplify(generated.mesh, options);
    ASSERT_TRUE(lazy.report.distance_computed && eager.report.distance_computed);
    EXPECT_LE(lazy.report.distance_rms, 1.25 * eager.report.distance_rms + 1e-9) << generated.name;
    lazy_sum += lazy.report.distance_rms;
    eager_sum += eager.report.distance_rms;
  }
  EXPECT_LE(lazy_sum, 1.1 * eager_sum);
}

TEST(Simplify, AsFarAsPossibleStopsAtALegalMinimumAboveTheLowerBound) {
  for (Generated& generated : generated_meshes()) {
    SimplifyOptions options;  // target 0
    options.validate_every_collapse = generated.mesh.vertex_count() < 400;
    const SimplifyResult result = simplify(generated.mesh, options);
    expect_valid_base_mesh(generated.mesh, result, generated.name);
    EXPECT_FALSE(result.report.target_reached);
    EXPECT_GE(result.report.vertices_after_collapse, result.report.lower_bound_vertices) << generated.name;
    EXPECT_NE(result.report.stop_reason.find("no legal collapse"), std::string::npos);
  }
}

TEST(Simplify, ValenceFlipsNeverStopEarlierThanThePaperRulesAlone) {
  std::size_t gained = 0, flip_round_collapses = 0;
  for (Generated& generated : generated_meshes()) {
    test::jitter(generated.mesh, 0.01, 11);
    SimplifyOptions paper;
    paper.valence_flips = false;
    paper.compute_distance = false;
    SimplifyOptions flips = paper;
    flips.valence_flips = true;
    flips.validate_every_collapse = generated.mesh.vertex_count() < 400;
    const SimplifyResult without = simplify(generated.mesh, paper);
    const SimplifyResult with = simplify(generated.mesh, flips);
    expect_valid_base_mesh(generated.mesh, with, generated.name);
    EXPECT_EQ(without.report.flips + without.report.input_valence_flips, 0u);
    EXPECT_LE(with.report.vertices_after_collapse, without.report.vertices_after_collapse) << generated.name;
    // No flip round when none is allowed (the input's own flips still happen).
    SimplifyOptions no_rounds = flips;
    no_rounds.max_flip_rounds = 0;
    const SimplifyResult rounds_off = simplify(generated.mesh, no_rounds);
    EXPECT_EQ(rounds_off.report.flip_rounds, 0u) << generated.name;
    EXPECT_EQ(rounds_off.report.collapses_after_flips, 0u) << generated.name;
    flip_round_collapses += with.report.collapses_after_flips;
    if (with.report.vertices_after_collapse < without.report.vertices_after_collapse) ++gained;
  }
  EXPECT_GT(gained, 0u);
  EXPECT_GT(flip_round_collapses, 0u);  // so that turning the rounds off is seen
}

TEST(Simplify, InputVerticesAboveTheValenceLimitAreFlippedDown) {
  // A planar disk whose centre has valence 12; target = input: no collapse.
  const PolygonMesh disk = test::wheel(12);
  SimplifyOptions options;
  options.valence_flips = true;
  options.target_vertices = disk.vertex_count();
  options.edge_removal = false;
  const SimplifyResult flipped = simplify(disk, options);
  expect_valid_base_mesh(disk, flipped, "disk");
  EXPECT_EQ(flipped.report.input_valence_flips, 4u);
  EXPECT_EQ(flipped.report.vertices_outside_valence_range, 0u);
  options.valence_flips = false;
  const SimplifyResult paper = simplify(disk, options);
  EXPECT_EQ(paper.report.vertices_outside_valence_range, 1u);
}

TEST(Simplify, ClosedComponentsNeverGoBelowATetrahedron) {
  const SimplifyResult result = simplify(test::icosphere(2));
  EXPECT_GE(result.base.vertex_count(), 4u);
  EXPECT_EQ(result.report.lower_bound_vertices, 4u);
  const SimplifyResult tetra = simplify(test::tetrahedron());
  EXPECT_EQ(tetra.report.collapses, 0u);
  EXPECT_EQ(tetra.base.vertex_count(), 4u);
}

TEST(Simplify, SharpVerticesKeepTheirPositions) {
  PolygonMesh mesh = test::fan_triangulate(test::quad_grid(20, 20));
  test::jitter(mesh, 0.05, 5);
  mesh.sharp.assign(mesh.vertex_count(), 0);
  for (std::uint32_t v = 0; v < mesh.vertex_count(); v += 7) mesh.sharp[v] = 1;
  SimplifyOptions options;
  options.target_vertices = 60;
  options.validate_every_collapse = true;
  const SimplifyResult result = simplify(mesh, options);
  // Every sharp vertex of the output sits exactly on a sharp input vertex,
  // and every sharp input vertex is kept (expect_valid_base_mesh).
  expect_valid_base_mesh(mesh, result, "sharp grid");
  EXPECT_GT(result.base.sharp_count(), 0u);
  EXPECT_LE(result.base.vertex_count(), 2 * options.target_vertices);  // collapses ran around them
}

TEST(Simplify, BoundaryVerticesStayOnTheInputBoundaryPolyline) {
  PolygonMesh disk = test::fan_triangulate(test::quad_grid(16, 16));  // the square [0, 16]^2
  // Sharp corners: otherwise a boundary edge may cut a corner (its midpoint
  // lies on the chord, not on the square).
  disk.sharp.assign(disk.vertex_count(), 0);
  for (std::uint32_t corner : {0u, 16u, 16u * 17u, 17u * 17u - 1u}) disk.sharp[corner] = 1;
  SimplifyOptions options;
  options.target_vertices = 40;
  const SimplifyResult result = simplify(disk, options);
  expect_valid_base_mesh(disk, result, "disk");
  // Whether p lies on an input boundary edge (exactly: every coordinate is a
  // binary fraction).
  const std::vector<Edge> input_boundary = boundary_edges(disk);
  const auto on_input_boundary = [&](const Vec3& p) {
    for (const auto& [u, w] : input_boundary) {
      const Vec3 a = disk.positions[u], b = disk.positions[w];
      const double along = dot(p - a, b - a);
      if (norm(cross(p - a, b - a)) == 0 && along >= 0 && along <= dot(b - a, b - a)) return true;
    }
    return false;
  };
  // Every base boundary edge runs along the input's: its endpoints and its
  // midpoint on it (an edge cutting a corner has its midpoint inside).
  const std::vector<Edge> base_boundary = boundary_edges(result.base);
  for (const auto& [u, w] : base_boundary) {
    const Vec3 a = result.base.positions[u], b = result.base.positions[w];
    EXPECT_TRUE(on_input_boundary(a) && on_input_boundary(b) && on_input_boundary(0.5 * (a + b)))
        << "boundary edge " << u << "-" << w << " left the input's boundary";
  }
  // The boundary was simplified, not just left alone: 64 edges before.
  EXPECT_EQ(input_boundary.size(), 64u);
  EXPECT_LE(base_boundary.size(), input_boundary.size() / 2);
}

// A flat ring (an isosurface grazing a box face is nearly flat near its
// boundary loop there, as on the engine's z = 0 face): (4.1) alone sees no
// cost in any collapse of it, so the paper's rules may shrink the hole's
// boundary loop to a sliver. Counting the boundary curve's move keeps the
// hole round.
TEST(Simplify, FlatRingKeepsItsHoleRound) {
  PolygonMesh ring;
  const int sectors = 48, circles = 12;
  const double pi = std::acos(-1.0), inner = 3, outer = 10;
  for (int j = 0; j <= circles; ++j)
    for (int i = 0; i < sectors; ++i) {
      const double r = inner + (outer - inner) * j / circles, a = 2 * pi * i / sectors;
      ring.positions.push_back({r * std::cos(a), r * std::sin(a), 0});
    }
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * sectors + i % sectors); };
  for (int j = 0; j < circles; ++j)
    for (int i = 0; i < sectors; ++i) {
      ring.add_face({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      ring.add_face({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  // Area inside the boundary loop nearest the centre: the hole.
  const auto hole_area = [](const PolygonMesh& mesh) {
    double area = 0;  // shoelace over the hole's boundary edges, each once, oriented by its face
    for (const auto& [u, w] : boundary_edges(mesh)) {
      const Vec3 &a = mesh.positions[u], &b = mesh.positions[w];
      if (norm(a) < 6.5 && norm(b) < 6.5) area += 0.5 * (a.x * b.y - b.x * a.y);  // counter-clockwise seen from +z
    }
    return area;
  };
  SimplifyOptions options;
  options.target_vertices = 32;
  const SimplifyResult result = simplify(ring, options);
  expect_valid_base_mesh(ring, result, "flat ring");
  options.boundary_curve_error = false;
  const SimplifyResult paper = simplify(ring, options);
  const double circle = pi * inner * inner;
  std::printf("hole area %.2f: base %.2f, paper's rules %.2f\n", circle, hole_area(result.base), hole_area(paper.base));
  // A regular octagon on the circle keeps 0.90 of its area. Measured: 0.91
  // of it kept, 0.73 with the paper's rules (0.72 against 0.57 at 24
  // vertices, 0.98 against 0.85 at 100).
  EXPECT_GE(hole_area(result.base), 0.85 * circle);
  EXPECT_GT(hole_area(result.base), hole_area(paper.base));
}

TEST(Simplify, EdgeRemovalMakesQuadsAndPentagonsAndCanBeTurnedOff) {
  PolygonMesh torus = test::fan_triangulate(test::quad_grid(40, 20, true, true));
  SimplifyOptions options;
  options.target_vertices = 200;
  const SimplifyResult with = simplify(torus, options);
  expect_valid_base_mesh(torus, with, "torus with edge removal");
  ASSERT_GE(with.report.face_size_histogram.size(), 5u);
  EXPECT_GT(with.report.face_size_histogram[4], 0u);
  EXPECT_GT(with.report.edges_removed, 0u);
  EXPECT_EQ(with.report.triangles_after_collapse - with.report.edges_removed, with.base.face_count());
  options.edge_removal = false;
  const SimplifyResult without = simplify(torus, options);
  EXPECT_EQ(without.report.edges_removed, 0u);
  for (std::size_t f = 0; f < without.base.face_count(); ++f) EXPECT_EQ(without.base.face_size(f), 3u);
  // Threshold 1.0 allows only exactly coplanar pairs: none on a jittered torus
  // (the regular one can make some by symmetry).
  test::jitter(torus, 0.01, 5);
  options.edge_removal = true;
  options.edge_removal_min_normal_dot = 1.0;
  EXPECT_EQ(simplify(torus, options).report.edges_removed, 0u);
}

TEST(Simplify, DistanceReportIsSmallForAModestReduction) {
  const PolygonMesh sphere = test::icosphere(4);  // 1026 vertices on the unit sphere
  SimplifyOptions options;
  options.target_vertices = 300;
  const SimplifyResult result = simplify(sphere, options);
  ASSERT_TRUE(result.report.distance_computed);
  // Chords of a 300-vertex sphere are ~0.2 long: sagitta ~0.005; allow 10x.
  EXPECT_GT(result.report.distance_max, 0.0);
  EXPECT_LT(result.report.distance_max, 0.05);
  EXPECT_LE(result.report.distance_rms, result.report.distance_max);
}

// --- bad input ---

ErrorKind error_kind_of(const PolygonMesh& mesh, const SimplifyOptions& options = {}) {
  try {
    simplify(mesh, options);
  } catch (const Error& error) {
    return error.kind();
  }
  ADD_FAILURE() << "no error";
  return ErrorKind::Io;
}

// The area budget (SimplifyOptions::max_vertex_area_share): every vertex
// holds a share of the input's area and the shares sum to the whole, so with
// no vertex above share * area / target the base keeps at least target /
// share vertices; without the budget the same collapse reaches the target.
TEST(SimplifyAreaBudget, KeepsAtLeastTargetOverShareVertices) {
  IsosurfaceOptions extract;
  const PolygonMesh input = extract_isosurface(make_builtin_field("mixing", 32), extract).mesh;
  for (const bool flips : {false, true}) {
    SimplifyOptions options;
    options.valence_flips = flips;
    options.target_vertices = input.vertex_count() / 20;
    options.compute_distance = false;
    const std::size_t free_base = simplify(input, options).base.vertex_count();
    EXPECT_LT(double(free_base), 1.5 * double(options.target_vertices)) << "the collapse alone nears the target";
    for (const double share : {0.5, 0.25}) {
      options.max_vertex_area_share = share;
      const SimplifyResult result = simplify(input, options);
      EXPECT_GE(double(result.base.vertex_count()), double(options.target_vertices) / share - 1) << share;
      // With flips the collapse goes farther, where the budget is what stops it.
      if (flips) {
        EXPECT_GT(result.report.rejected_at_pop[static_cast<int>(Legality::AreaBudget)], 0u) << share;
      }
    }
  }
}

TEST(SimplifyBadInput, NonManifoldEdge) {
  PolygonMesh mesh = test::tetrahedron();
  mesh.positions.push_back({0, 0, 5});
  mesh.add_face({0, 1, 4});  // third face on edge (0, 1)
  EXPECT_EQ(error_kind_of(mesh), ErrorKind::Topology);
}

TEST(SimplifyBadInput, RepeatedVertexInATriangle) {
  PolygonMesh mesh = test::tetrahedron();
  mesh.face_vertices[1] = mesh.face_vertices[0];
  EXPECT_EQ(error_kind_of(mesh), ErrorKind::Topology);
}

TEST(SimplifyBadInput, NanCoordinate) {
  PolygonMesh mesh = test::icosphere(1);
  mesh.positions[3].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_kind_of(mesh), ErrorKind::Format);
}

TEST(SimplifyBadInput, QuadsAreNotAccepted) {
  EXPECT_EQ(error_kind_of(test::cube()), ErrorKind::Unsupported);
}

TEST(SimplifyBadInput, UnreferencedVertexAndEmptyMesh) {
  PolygonMesh mesh = test::icosphere(1);
  mesh.positions.push_back({9, 9, 9});
  EXPECT_EQ(error_kind_of(mesh), ErrorKind::Topology);
  EXPECT_EQ(error_kind_of(PolygonMesh{}), ErrorKind::Topology);
}

TEST(SimplifyBadInput, OptionsOutOfRange) {
  SimplifyOptions options;
  options.edge_removal_min_normal_dot = 2;
  EXPECT_EQ(error_kind_of(test::icosphere(1), options), ErrorKind::InvalidArgument);
  options = {};
  options.max_valence = 2;
  EXPECT_EQ(error_kind_of(test::icosphere(1), options), ErrorKind::InvalidArgument);
  options = {};
  options.max_flip_rounds = -1;
  EXPECT_EQ(error_kind_of(test::icosphere(1), options), ErrorKind::InvalidArgument);
  options = {};
  options.batch_error_factor = 0.5;
  EXPECT_EQ(error_kind_of(test::icosphere(1), options), ErrorKind::InvalidArgument);
  options.batch_error_factor = std::nan("");
  EXPECT_EQ(error_kind_of(test::icosphere(1), options), ErrorKind::InvalidArgument);
  options = {};
  options.max_vertex_area_share = -1;
  EXPECT_EQ(error_kind_of(test::icosphere(1), options), ErrorKind::InvalidArgument);
}

TEST(SimplifyBadInput, DegenerateTrianglesAreAcceptedAndNoneIsCreated) {
  // A flat grid with a row of collinear triangles squashed to zero area.
  PolygonMesh mesh = test::fan_triangulate(test::quad_grid(10, 10));
  for (Vec3& p : mesh.positions)
    if (p.y == 5) p.y = 4;  // rows 4 and 5 coincide: the triangles between them have zero area
  SimplifyOptions options;
  options.target_vertices = 30;
  options.validate_every_collapse = true;
  const SimplifyResult result = simplify(mesh, options);
  expect_valid_base_mesh(mesh, result, "degenerate grid");
}

TEST(SimplifyBadInput, TargetAboveTheInputSizeCollapsesNothing) {
  const PolygonMesh sphere = test::icosphere(2);
  SimplifyOptions options;
  options.target_vertices = sphere.vertex_count() + 100;
  const SimplifyResult result = simplify(sphere, options);
  EXPECT_EQ(result.report.collapses, 0u);
  EXPECT_EQ(result.report.vertices_after_collapse, sphere.vertex_count());
  EXPECT_EQ(result.report.target_vertices, sphere.vertex_count());
  EXPECT_NE(result.report.stop_reason.find("at or above"), std::string::npos);
  expect_valid_base_mesh(sphere, result, "sphere, no collapse");
}

// --- shared meshes ---

void run_shared_mesh(const std::string& path, double ratio) {
  PolygonMesh mesh = read_mesh(path);
  remove_unreferenced_vertices(mesh);
  const bool input_in_range = max_valence_of(mesh) <= 8;
  SimplifyOptions options;
  options.target_vertices = static_cast<std::size_t>(double(mesh.vertex_count()) * ratio);
  const SimplifyResult result = simplify(mesh, options);
  // Input vertices of valence > 8 that no collapse touched may remain.
  expect_valid_base_mesh(mesh, result, path, input_in_range);
  expect_target(result, options.target_vertices);
  ASSERT_TRUE(result.report.distance_computed);
  EXPECT_TRUE(std::isfinite(result.report.distance_rms));
}

#define SHARED_MESH_TEST(name, file, ratio)                  \
  TEST(SimplifySharedMeshes, name) {                          \
    ISOWAVE_REQUIRE_SHARED_FILE(path, "meshes/" file);        \
    run_shared_mesh(path, ratio);                             \
  }

SHARED_MESH_TEST(BunnyHoles, "bunny_holes.obj", 0.02)
SHARED_MESH_TEST(Armadillo, "armadillo.off", 0.02)
SHARED_MESH_TEST(FertilityGenus4, "fertility_genus4.off", 0.05)
SHARED_MESH_TEST(CastingGenus9, "casting_genus9.off", 0.05)
SHARED_MESH_TEST(RockerArmGenus1, "rocker_arm_genus1.obj", 0.03)
SHARED_MESH_TEST(MushroomDisk, "mushroom_disk.off", 0.05)
SHARED_MESH_TEST(Mech4Holes, "mech_4holes.off", 0.05)
SHARED_MESH_TEST(Elephant106Holes, "elephant_106holes.off", 0.5)

// --- extracted isosurfaces ---

void run_isosurface(const Volume& volume, double iso, const std::string& name, double ratio) {
  IsosurfaceOptions extraction;
  extraction.iso = iso;
  const Isosurface surface = extract_isosurface(volume, extraction);
  ASSERT_GT(surface.mesh.face_count(), 0u) << name;
  SimplifyOptions options;
  options.target_vertices = static_cast<std::size_t>(double(surface.mesh.vertex_count()) * ratio);
  const SimplifyResult result = simplify(surface.mesh, options);
  expect_valid_base_mesh(surface.mesh, result, name, max_valence_of(surface.mesh) <= 8);
  // Many tiny components may make the target unreachable: then the report
  // must say so and the count must respect the lower bound.
  if (result.report.vertices_after_collapse > options.target_vertices + options.target_vertices / 20) {
    EXPECT_NE(result.report.stop_reason.find("no legal collapse"), std::string::npos) << name;
    EXPECT_GE(result.report.vertices_after_collapse, result.report.lower_bound_vertices);
  }
}

TEST(SimplifyIsosurfaces, BuiltinFields) {
  for (const char* name : {"sphere", "torus", "genus3", "marschner-lobb"})
    run_isosurface(make_builtin_field(name, 48), 0.0, std::string("builtin ") + name, 0.05);
}

TEST(SimplifyIsosurfaces, ParallelPhaseKeepsTheRulesAndDoesNotDependOnTiming) {
  // The mixing field at 36^3 (about 9 K vertices), forced through the
  // two-thread phase with every invariant checked after it and after each
  // serial collapse.
  IsosurfaceOptions extraction;
  const Isosurface surface = extract_isosurface(make_builtin_field("mixing", 36), extraction);
  SimplifyOptions options;
  options.parallel_min_vertices = 0;
  options.validate_every_collapse = true;
  options.compute_distance = false;
  // The serial phase is announced once, after the parallel collapses.
  int announcements = 0;
  options.serial_phase_begins = [&] { ++announcements; };
  const SimplifyResult parallel = simplify(surface.mesh, options);
  EXPECT_EQ(announcements, 1);
  expect_valid_base_mesh(surface.mesh, parallel, "mixing, parallel", max_valence_of(surface.mesh) <= 8);
  // On a mesh this small the band between the halves is wide; still, a good
  // part of the work is parallel.
  EXPECT_GT(parallel.report.parallel_collapses, parallel.report.collapses / 4);
  // The same run again gives the same mesh: each thread sees only its half.
  const SimplifyResult again = simplify(surface.mesh, options);
  EXPECT_EQ(again.base.face_vertices, parallel.base.face_vertices);
  EXPECT_EQ(again.base.positions, parallel.base.positions);
  // As far as the serial loop gets, within a few percent.
  options.parallel = false;
  options.validate_every_collapse = false;
  const SimplifyResult serial = simplify(surface.mesh, options);
  EXPECT_EQ(serial.report.parallel_collapses, 0u);
  EXPECT_LE(double(parallel.base.vertex_count()), 1.05 * double(serial.base.vertex_count()));
}

// A gyroid, sin x cos y + sin y cos z + sin z cos x = 0, over `periods`
// periods per axis on an n^3 grid: one sheet of high genus (955 for 64^3
// and 6.4 periods), cut by the box.
Volume gyroid_volume(std::size_t n, double periods) {
  Volume volume;
  volume.dims = {n, n, n};
  volume.values.resize(n * n * n);
  const double scale = 2 * M_PI * periods / double(n);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t i = 0; i < n; ++i) {
        const double x = scale * double(i), y = scale * double(j), z = scale * double(k);
        volume.values[volume.index(i, j, k)] =
            float(std::sin(x) * std::cos(y) + std::sin(y) * std::cos(z) + std::sin(z) * std::cos(x));
      }
  return volume;
}

// The flip round runs on two threads too, each confined to its half, then
// serially on the edges they had to leave: a valid base mesh, the same on
// every run, about as small as the serial flip round makes it. Needs a
// surface of high genus, where the paper's rules stall early.
TEST(SimplifyIsosurfaces, FlipRoundOnTwoThreadsKeepsTheRulesAndDoesNotDependOnTiming) {
  IsosurfaceOptions extraction;
  const Isosurface surface = extract_isosurface(gyroid_volume(64, 6.4), extraction);
  SimplifyOptions options;
  options.valence_flips = true;
  options.parallel_min_vertices = 0;
  options.compute_distance = false;
  const SimplifyResult parallel = simplify(surface.mesh, options);
  expect_valid_base_mesh(surface.mesh, parallel, "gyroid, parallel", max_valence_of(surface.mesh) <= 8);
  ASSERT_GT(parallel.report.collapses_after_flips, 0u);
  EXPECT_GT(parallel.report.parallel_flip_round_collapses, parallel.report.collapses_after_flips / 4);
  const SimplifyResult again = simplify(surface.mesh, options);
  EXPECT_EQ(again.base.face_vertices, parallel.base.face_vertices);
  EXPECT_EQ(again.base.positions, parallel.base.positions);
  options.parallel = false;
  const SimplifyResult serial = simplify(surface.mesh, options);
  EXPECT_LE(double(parallel.report.vertices_after_collapse), 1.02 * double(serial.report.vertices_after_collapse));
  std::printf("vertices after collapse: parallel %zu (%zu collapses after flips, %zu on two threads), serial %zu\n",
              parallel.report.vertices_after_collapse, parallel.report.collapses_after_flips,
              parallel.report.parallel_flip_round_collapses, serial.report.vertices_after_collapse);
}

// The two-thread phase (and the flip round) collapse in batches of edges
// within a factor of ten in error (SimplifyOptions::batch_error_factor); the
// base mesh stays about as close to the input as one collapse at a time in
// priority order makes it. Batching everything (factor 1e20) fails on mixing.
TEST(SimplifyIsosurfaces, BatchedParallelPhaseIsAsCloseToTheInputAsOneAtATime) {
  double batched_sum = 0, one_at_a_time_sum = 0;
  for (const char* name : {"mixing", "genus3", "marschner-lobb"}) {
    IsosurfaceOptions extraction;
    const Isosurface surface = extract_isosurface(make_builtin_field(name, 64), extraction);
    SimplifyOptions options;
    options.parallel_min_vertices = 0;
    options.target_vertices = surface.mesh.vertex_count() / 10;
    const SimplifyResult batched = simplify(surface.mesh, options);
    options.batch_error_factor = 1;
    const SimplifyResult one_at_a_time = simplify(surface.mesh, options);
    ASSERT_GT(batched.report.parallel_collapses, 0u);
    ASSERT_TRUE(batched.report.distance_computed && one_at_a_time.report.distance_computed);
    EXPECT_NE(batched.base.positions, one_at_a_time.base.positions) << name << ": the order did not change";
    EXPECT_LE(batched.report.distance_rms, 1.25 * one_at_a_time.report.distance_rms) << name;
    batched_sum += batched.report.distance_rms;
    one_at_a_time_sum += one_at_a_time.report.distance_rms;
    std::printf("%s: distance RMS batched %.4f, one at a time %.4f\n", name, batched.report.distance_rms,
                one_at_a_time.report.distance_rms);
  }
  EXPECT_LE(batched_sum, 1.1 * one_at_a_time_sum);
}

TEST(SimplifyIsosurfaces, HydrogenVolume) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/hydrogen.vti");
  run_isosurface(read_volume(path), 0.05, "hydrogen", 0.05);
}

TEST(SimplifyIsosurfaces, IronProteinVolume) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/ironProt.vtk");
  run_isosurface(read_volume(path), 128, "ironProt", 0.05);
}

TEST(SimplifyIsosurfaces, ViscousFingersVolume) {
  // Many small components: the target may be unreachable, which the report must say.
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/viscousfingers_099.vti");
  run_isosurface(read_volume(path), 30, "viscous fingers", 0.02);
}

}  // namespace
}  // namespace isowave::simplify
