// Unit tests of paper Sec. 4.1's building blocks: formulas (4.1)-(4.3), the
// bucket index, FIFO order, and each collapse-legality rule on hand-built
// neighbourhoods.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/simplify/bucket_queue.h"
#include "isowave/simplify/collapse_error.h"
#include "isowave/simplify/collapse_mesh.h"
#include "simplify_test_meshes.h"

namespace isowave::simplify {
namespace {

using test::fan_triangulate;

// --- (4.1) and (4.2) ---

TEST(CollapseError, PlanarRingOfEqualTrianglesGivesTheClampedMinimum) {
  // Flat ring, equal areas: every n_i = n, d in the plane -> dE0 = 0, ratio 1.
  const std::vector<Vec3> c = {{0, 0, 2}, {0, 0, 2}, {0, 0, 2}, {0, 0, 2}};
  const CollapseErrorTerms terms = collapse_error_terms({1, 0, 0}, c.data(), c.size());
  EXPECT_EQ(terms.delta_e0, 0.0);
  EXPECT_EQ(terms.delta_e1, 1e-8);
  EXPECT_DOUBLE_EQ(terms.weight, 1.0);
  EXPECT_DOUBLE_EQ(terms.delta_e, 1e-8);
}

TEST(CollapseError, UnequalAreasRaiseTheWeight) {
  // ratio = min(c.n)/max|c| = 1/2 -> weight 1.5^16.
  const std::vector<Vec3> c = {{0, 0, 1}, {0, 0, 2}};
  const CollapseErrorTerms terms = collapse_error_terms({0, 3, 0}, c.data(), c.size());
  EXPECT_NEAR(terms.weight, 656.8408355712891, 1e-9);
  EXPECT_NEAR(terms.delta_e, 656.8408355712891e-8, 1e-15);
}

TEST(CollapseError, BentRingByHand) {
  // n_0 = z, n_1 = y; d/2 = (0, 1, 2): |d/2 . n_0| = 2, |d/2 . n_1| = 1.
  // n = (0, 1, 1)/sqrt 2; c_i . n = 2/sqrt 2 each; max|c| = 2 -> ratio 1/sqrt 2.
  const std::vector<Vec3> c = {{0, 0, 2}, {0, 2, 0}};
  const CollapseErrorTerms terms = collapse_error_terms({0, 2, 4}, c.data(), c.size());
  EXPECT_DOUBLE_EQ(terms.delta_e0, 2.0);
  EXPECT_DOUBLE_EQ(terms.delta_e1, 2.0);
  const double weight = std::pow(2.0 - 1.0 / std::sqrt(2.0), 16);
  EXPECT_NEAR(terms.weight, weight, 1e-9 * weight);
  EXPECT_NEAR(terms.delta_e, 2.0 * weight, 1e-9 * weight);
}

TEST(CollapseError, TangledRingGetsTheLargestWeightOfARatioOfZero) {
  // Opposite normals cancel: n = 0, so min(c_i . n) = 0 and the weight is 2^16.
  const std::vector<Vec3> c = {{0, 0, 1}, {0, 0, -1}};
  const CollapseErrorTerms terms = collapse_error_terms({0, 0, 2}, c.data(), c.size());
  EXPECT_DOUBLE_EQ(terms.delta_e0, 1.0);
  EXPECT_DOUBLE_EQ(terms.weight, 65536.0);
  EXPECT_DOUBLE_EQ(terms.delta_e, 65536.0);
}

TEST(CollapseError, FoldedRingWeighsMoreThanTwoToTheSixteen) {
  // Three normals up, one down: n = z, min c.n = -1, max |c| = 1 -> weight 3^16.
  const std::vector<Vec3> c = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, -1}};
  const CollapseErrorTerms terms = collapse_error_terms({0, 0, 1e-9}, c.data(), c.size());
  EXPECT_DOUBLE_EQ(terms.weight, 43046721.0);
  EXPECT_EQ(terms.delta_e1, 1e-8);  // dE0 = 5e-10 is clamped
}

// --- bucket index ---

TEST(PriorityBucket, MapsLogOneOverEOntoTheRange) {
  constexpr std::uint32_t kBuckets = 100000;
  // log(1/E) spans [log 1e-10, log 1e10] = 46.05 units over 1e5 buckets.
  EXPECT_EQ(priority_bucket(1e-10 * 0.999, kBuckets), kBuckets - 1);
  EXPECT_EQ(priority_bucket(1e-20, kBuckets), kBuckets - 1);  // clamped
  EXPECT_EQ(priority_bucket(0.0, kBuckets), kBuckets - 1);
  EXPECT_EQ(priority_bucket(1e10 * 1.001, kBuckets), 0u);
  EXPECT_EQ(priority_bucket(1e30, kBuckets), 0u);
  EXPECT_NEAR(double(priority_bucket(1.0, kBuckets)), 50000.0, 1.0);    // log(1/1) = 0: the middle
  EXPECT_NEAR(double(priority_bucket(1e-5, kBuckets)), 75000.0, 1.0);   // three quarters up
  EXPECT_NEAR(double(priority_bucket(1e5, kBuckets)), 25000.0, 1.0);    // one quarter up
  // One bucket is a factor exp(46.05 / 1e5) = 1.00046 in E.
  EXPECT_NEAR(double(priority_bucket(1.0, kBuckets)) - double(priority_bucket(1.0015, kBuckets)), 3.25, 1.0);
  EXPECT_EQ(priority_bucket(1.0, 1), 0u);
}

TEST(PriorityBucket, SmallerErrorNeverGetsALowerPriority) {
  std::uint32_t previous = 0;
  for (double e = 1e12; e > 1e-12; e /= 1.37) {
    const std::uint32_t bucket = priority_bucket(e, 100000);
    EXPECT_GE(bucket, previous);
    previous = bucket;
  }
}

TEST(PriorityBucket, SpanOfAnErrorFactorIsTheBucketDistanceOfTwoErrorsThatFarApart) {
  constexpr std::uint32_t kBuckets = 100000;
  EXPECT_EQ(priority_bucket_span(1.0, kBuckets), 0u);
  EXPECT_EQ(priority_bucket_span(1e20, kBuckets), kBuckets);  // the whole range
  EXPECT_EQ(priority_bucket_span(1e30, kBuckets), kBuckets);
  for (const double factor : {1.5, 10.0, 1000.0})
    for (double e = 1e-8; e < 1e6; e *= 7.3) {
      // Buckets are floors of a linear map of log(E): two errors a factor
      // apart are the span's floor or ceiling apart (within rounding).
      const double apart = double(priority_bucket(e, kBuckets)) - double(priority_bucket(e * factor, kBuckets));
      EXPECT_NEAR(apart, double(priority_bucket_span(factor, kBuckets)), 1.0) << factor << " " << e;
    }
}

// --- bucket queue ---

TEST(BucketQueue, HighestBucketFirstAndFifoInsideABucket) {
  BucketQueue queue(10, 100000);
  queue.push(5, 70000);
  queue.push(2, 70000);
  queue.push(9, 70000);
  queue.push(3, 70001);
  queue.push(1, 12);
  queue.push(0, 99999);
  EXPECT_EQ(queue.size(), 6u);
  EXPECT_EQ(queue.pop(), 0u);
  EXPECT_EQ(queue.pop(), 3u);
  EXPECT_EQ(queue.pop(), 5u);
  queue.push(5, 70000);  // re-entered: now behind 2 and 9
  EXPECT_EQ(queue.pop(), 2u);
  EXPECT_EQ(queue.pop(), 9u);
  EXPECT_EQ(queue.pop(), 5u);
  EXPECT_EQ(queue.pop(), 1u);
  EXPECT_TRUE(queue.empty());
}

TEST(BucketQueue, RemoveFromTheMiddleKeepsTheOrder) {
  BucketQueue queue(8, 64 * 64 * 3);  // three words of the upper bitmap level
  for (std::uint32_t item = 0; item < 6; ++item) queue.push(item, 4000);
  queue.push(7, 5);
  queue.remove(2);
  queue.remove(0);
  queue.remove(5);
  EXPECT_FALSE(queue.contains(2));
  EXPECT_EQ(queue.bucket_of(7), 5u);
  std::vector<std::uint32_t> order;
  while (!queue.empty()) order.push_back(queue.pop());
  EXPECT_EQ(order, (std::vector<std::uint32_t>{1, 3, 4, 7}));
}

TEST(BucketQueue, CallerKeptLinksGiveTheSameOrderAndTwoQueuesCanShareThem) {
  // Links inside larger records, as the collapse keeps them in its edge records.
  struct Record {
    double payload;
    BucketQueue::Links links;
  };
  std::vector<Record> records(10, Record{0.0, {0, 0, BucketQueue::kNotQueued}});
  BucketQueue even(&records[0].links, sizeof(Record), records.size(), 100000);
  BucketQueue odd(&records[0].links, sizeof(Record), records.size(), 100000);
  BucketQueue own(records.size(), 100000);
  for (const auto& [item, bucket] : std::vector<std::pair<std::uint32_t, std::uint32_t>>{
           {4, 70000}, {2, 70000}, {8, 70000}, {6, 70001}, {0, 12}, {5, 70000}, {3, 70000}, {1, 9}}) {
    (item % 2 == 0 ? even : odd).push(item, bucket);
    if (item % 2 == 0) own.push(item, bucket);
  }
  even.remove(2);
  own.remove(2);
  EXPECT_TRUE(odd.contains(5));
  EXPECT_FALSE(even.contains(2));
  std::vector<std::uint32_t> shared_order, own_order, odd_order;
  while (!even.empty()) shared_order.push_back(even.pop());
  while (!own.empty()) own_order.push_back(own.pop());
  while (!odd.empty()) odd_order.push_back(odd.pop());
  EXPECT_EQ(shared_order, (std::vector<std::uint32_t>{6, 4, 8, 0}));
  EXPECT_EQ(shared_order, own_order);
  EXPECT_EQ(odd_order, (std::vector<std::uint32_t>{5, 3, 1}));
  for (const Record& record : records) EXPECT_EQ(record.links.bucket, BucketQueue::kNotQueued);
}

// --- corner table ---

TEST(CollapseMesh, RenumberedTableMatchesTheTableOfTheRenumberedMesh) {
  // The parallel construction with a vertex order against the plain one on
  // the mesh renumbered by hand, triangles ordered by their smallest vertex.
  PolygonMesh sphere = test::icosphere(3);
  test::jitter(sphere, 0.05, 5);
  PolygonMesh holed;  // with boundaries
  holed.positions = sphere.positions;
  for (std::size_t f = 0; f < sphere.face_count(); ++f)
    if (f % 29 != 3) holed.add_face({sphere.face_begin(f)[0], sphere.face_begin(f)[1], sphere.face_begin(f)[2]});
  const std::uint32_t n = static_cast<std::uint32_t>(holed.vertex_count());
  std::vector<std::uint32_t> order(n), new_index(n);
  for (std::uint32_t k = 0; k < n; ++k) order[k] = (k * 37 + 11) % n;  // a permutation: gcd(37, n) = 1
  ASSERT_EQ(std::gcd(37u, n), 1u);
  for (std::uint32_t k = 0; k < n; ++k) new_index[order[k]] = k;
  PolygonMesh renumbered;
  for (std::uint32_t k = 0; k < n; ++k) renumbered.positions.push_back(holed.positions[order[k]]);
  std::vector<std::pair<std::uint32_t, std::size_t>> triangles;
  for (std::size_t f = 0; f < holed.face_count(); ++f) {
    const std::uint32_t* t = holed.face_begin(f);
    triangles.emplace_back(std::min({new_index[t[0]], new_index[t[1]], new_index[t[2]]}), f);
  }
  std::sort(triangles.begin(), triangles.end());
  for (const auto& [smallest, f] : triangles) {
    const std::uint32_t* t = holed.face_begin(f);
    renumbered.add_face({new_index[t[0]], new_index[t[1]], new_index[t[2]]});
  }
  const CollapseMesh built(holed, order);
  const CollapseMesh reference(renumbered);
  EXPECT_EQ(built.validate(), "");
  ASSERT_EQ(built.edge_slots(), reference.edge_slots());
  const PolygonMesh a = built.to_polygon_mesh(), b = reference.to_polygon_mesh();
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.face_vertices, b.face_vertices);
  for (std::uint32_t e = 0; e < built.edge_slots(); ++e) {
    EXPECT_EQ(built.edge_halfedge(e), reference.edge_halfedge(e)) << e;
    const Evaluation x = built.evaluate(e), y = reference.evaluate(e);
    EXPECT_EQ(x.legality, y.legality) << e;
    EXPECT_EQ(x.delta_error, y.delta_error) << e;
  }
}

TEST(CollapseMesh, ConstructionRejectsWhatRequireManifoldRejects) {
  const auto rejected = [](const PolygonMesh& mesh) {
    try {
      CollapseMesh table(mesh);
    } catch (const Error& error) {
      return error.kind() == ErrorKind::Topology;
    }
    return false;
  };
  PolygonMesh pinched = test::tetrahedron();  // a second tetrahedron sharing vertex 0: two fans
  const std::size_t base = pinched.vertex_count();
  for (std::size_t v = 1; v < base; ++v) pinched.positions.push_back(pinched.positions[v] + Vec3{0, 0, 5});
  const std::size_t faces = pinched.face_count();
  for (std::size_t f = 0; f < faces; ++f) {
    std::array<std::uint32_t, 3> face;
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t v = pinched.face_begin(f)[i];
      face[i] = v == 0 ? 0 : static_cast<std::uint32_t>(v + base - 1);
    }
    pinched.add_face({face[0], face[1], face[2]});
  }
  EXPECT_THROW(require_manifold(pinched, "pinched"), Error);
  EXPECT_TRUE(rejected(pinched));
  PolygonMesh flipped = test::tetrahedron();  // one face reversed: edges traversed twice one way
  std::swap(flipped.face_vertices[1], flipped.face_vertices[2]);
  EXPECT_TRUE(rejected(flipped));
  PolygonMesh third = test::tetrahedron();  // a third triangle on an edge
  third.positions.push_back({0, 0, 5});
  third.add_face({third.face_begin(0)[0], third.face_begin(0)[1], 4});
  EXPECT_TRUE(rejected(third));
  PolygonMesh unused = test::tetrahedron();
  unused.positions.push_back({9, 9, 9});
  EXPECT_TRUE(rejected(unused));
  PolygonMesh repeated = test::tetrahedron();
  repeated.face_vertices[1] = repeated.face_vertices[0];
  EXPECT_TRUE(rejected(repeated));
  EXPECT_FALSE(rejected(test::tetrahedron()));
}

// --- legality rules ---

// A planar fan around interior vertex 0 at the origin with its ring 1..5 on
// the boundary; vertex 1 = (1, 0) is v_j. Collapsing (0, 1) places the new
// vertex at vertex 1 (a boundary endpoint) and turns triangle (0, 4, 5) into
// (p, 4, 5), flipped when vertex 5 is placed as given.
PolygonMesh planar_fan(const Vec3& fifth) {
  PolygonMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}, fifth};
  mesh.add_face({0, 1, 2});
  mesh.add_face({0, 2, 3});
  mesh.add_face({0, 3, 4});
  mesh.add_face({0, 4, 5});
  mesh.add_face({0, 5, 1});
  return mesh;
}

std::uint32_t edge_between(const CollapseMesh& mesh, std::uint32_t a, std::uint32_t b) {
  const std::uint32_t e = mesh.find_edge(a, b);
  EXPECT_NE(e, CollapseMesh::kNone) << "no edge " << a << "-" << b;
  return e;
}

TEST(CollapseLegality, NormalFlipIsRejectedAndItsControlIsLegal) {
  // (0.26, -0.15): the line from vertex 4 = (0, -1) through it passes between
  // the origin and (1, 0), so (p, 4, 5) turns over.
  const CollapseMesh flipped(planar_fan({0.26, -0.15, 0}));
  EXPECT_EQ(flipped.evaluate(edge_between(flipped, 0, 1)).legality, Legality::NormalFlip);
  const CollapseMesh fine(planar_fan({0.9, -0.5, 0}));
  const Evaluation legal = fine.evaluate(edge_between(fine, 0, 1));
  EXPECT_EQ(legal.legality, Legality::Legal);
  EXPECT_EQ(legal.position, (Vec3{1, 0, 0}));  // interior edge with one boundary endpoint
}

TEST(CollapseLegality, ZeroAreaResultIsRejected) {
  // Vertex 5 on the line from (0, -1) to (1, 0): (p, 4, 5) would be degenerate.
  const CollapseMesh mesh(planar_fan({0.5, -0.5, 0}));
  EXPECT_EQ(mesh.evaluate(edge_between(mesh, 0, 1)).legality, Legality::DegenerateTriangle);
}

TEST(CollapseLegality, StricterNormalThresholdRejectsAnyBend) {
  CollapseRules strict;
  strict.min_normal_dot = 0.99;
  const CollapseMesh mesh(test::icosphere(1), strict);
  const CollapseMesh loose(test::icosphere(1));
  std::size_t flips = 0, legal = 0;
  for (std::uint32_t e = 0; e < mesh.edge_slots(); ++e) {
    if (mesh.evaluate(e).legality == Legality::NormalFlip) ++flips;
    if (loose.evaluate(e).legality == Legality::Legal) ++legal;
  }
  EXPECT_EQ(flips, mesh.edge_slots());
  EXPECT_GT(legal, 0u);
}

TEST(CollapseLegality, InteriorEdgeJoiningBoundaryVerticesAndLoopMinimum) {
  PolygonMesh square;
  square.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  square.add_face({0, 1, 2});
  square.add_face({0, 2, 3});
  CollapseMesh mesh(square);
  EXPECT_EQ(mesh.evaluate(edge_between(mesh, 0, 2)).legality, Legality::InteriorEdgeOnBoundary);
  const std::uint32_t boundary_edge = edge_between(mesh, 0, 1);
  const Evaluation evaluation = mesh.evaluate(boundary_edge);
  ASSERT_EQ(evaluation.legality, Legality::Legal);
  EXPECT_EQ(evaluation.position, (Vec3{0.5, 0, 0}));  // boundary edges collapse to the midpoint
  std::uint32_t removed[3], opposite[2];
  mesh.collapse(boundary_edge, evaluation.position, removed, opposite);
  EXPECT_EQ(mesh.validate(), "");
  EXPECT_EQ(mesh.alive_vertices(), 3u);
  for (std::uint32_t e = 0; e < mesh.edge_slots(); ++e) {
    if (!mesh.edge_alive(e)) continue;
    EXPECT_EQ(mesh.evaluate(e).legality, Legality::BoundaryLoopMinimum);
  }
}

TEST(CollapseLegality, TetrahedronIsTheMinimumOfAClosedComponent) {
  const CollapseMesh mesh(test::tetrahedron());
  for (std::uint32_t e = 0; e < mesh.edge_slots(); ++e)
    EXPECT_EQ(mesh.evaluate(e).legality, Legality::NewVertexValence);  // 3 + 3 - 4 = 2 < 3
}

TEST(CollapseLegality, OppositeVertexValence) {
  // Triangular bipyramid: poles 3, 4 of valence 3; equator edge (0, 1) would
  // leave its opposite poles with valence 2.
  PolygonMesh bipyramid;
  bipyramid.positions = {{1, 0, 0}, {-0.5, 0.87, 0}, {-0.5, -0.87, 0}, {0, 0, 1}, {0, 0, -1}};
  for (std::uint32_t k = 0; k < 3; ++k) {
    bipyramid.add_face({k, (k + 1) % 3, 3});
    bipyramid.add_face({(k + 1) % 3, k, 4});
  }
  const CollapseMesh mesh(bipyramid);
  EXPECT_EQ(mesh.evaluate(edge_between(mesh, 0, 1)).legality, Legality::OppositeVertexValence);
}

TEST(CollapseLegality, LinkConditionOnAThinTorus) {
  // 3 x 8 torus: vertices (0, j) and (1, j) share (2, j) besides the two
  // opposite vertices; all valences 6, so only the link condition fails.
  const CollapseMesh mesh(fan_triangulate(test::quad_grid(3, 8, true, true)));
  EXPECT_EQ(mesh.evaluate(edge_between(mesh, 0, 1)).legality, Legality::LinkCondition);
  const CollapseMesh wide(fan_triangulate(test::quad_grid(8, 8, true, true)));
  EXPECT_EQ(wide.evaluate(edge_between(wide, 0, 1)).legality, Legality::Legal);
}

TEST(CollapseLegality, NewVertexValenceAboveEight) {
  CollapseMesh mesh(fan_triangulate(test::quad_grid(8, 8, true, true)));
  const std::uint32_t e = edge_between(mesh, 0, 1);
  const Evaluation evaluation = mesh.evaluate(e);
  ASSERT_EQ(evaluation.legality, Legality::Legal);
  std::uint32_t removed[3], opposite[2];
  const std::uint32_t v = mesh.collapse(e, evaluation.position, removed, opposite);
  EXPECT_EQ(mesh.valence(v), 8u);  // 6 + 6 - 4
  EXPECT_EQ(mesh.validate(), "");
  // Every edge at v now has 8 + 6 - 4 = 10 > 8, or 8 + 5 - 4 = 9 at a and b.
  std::size_t checked = 0;
  for (std::uint32_t f = 0; f < mesh.edge_slots(); ++f) {
    if (!mesh.edge_alive(f)) continue;
    const std::uint32_t h = mesh.edge_halfedge(f);
    if (mesh.origin(h) != v && mesh.target(h) != v) continue;
    EXPECT_EQ(mesh.evaluate(f).legality, Legality::NewVertexValence);
    ++checked;
  }
  EXPECT_EQ(checked, 8u);
  CollapseRules seven;
  seven.max_valence = 7;
  const CollapseMesh strict(fan_triangulate(test::quad_grid(8, 8, true, true)), seven);
  EXPECT_EQ(strict.evaluate(edge_between(strict, 0, 1)).legality, Legality::NewVertexValence);
}

TEST(CollapseLegality, SharpEndpoints) {
  // Planar 8 x 8 grid (vertex i + 9 j at (i, j)): collapsing onto a vertex of
  // a convex star never flips, so only the sharp rules decide.
  PolygonMesh grid = fan_triangulate(test::quad_grid(8, 8));
  grid.sharp.assign(grid.vertex_count(), 0);
  grid.sharp[0] = grid.sharp[1] = 1;
  grid.sharp[10] = 1;
  const CollapseMesh mesh(grid);
  EXPECT_EQ(mesh.evaluate(edge_between(mesh, 0, 1)).legality, Legality::BothEndpointsSharp);
  // One sharp endpoint: the new vertex is that endpoint.
  const Evaluation evaluation = mesh.evaluate(edge_between(mesh, 10, 11));
  ASSERT_EQ(evaluation.legality, Legality::Legal);
  EXPECT_EQ(evaluation.position, grid.positions[10]);
  const Evaluation plain = mesh.evaluate(edge_between(mesh, 20, 21));
  ASSERT_EQ(plain.legality, Legality::Legal);
  EXPECT_EQ(plain.position, (grid.positions[20] + grid.positions[21]) * 0.5);
}

// --- edge flips (valence balancing beyond the paper) ---

// Sorted vertex triples of the alive triangles: the triangulation as a set.
std::vector<std::array<std::uint32_t, 3>> triangle_set(const CollapseMesh& mesh) {
  const PolygonMesh polygons = mesh.to_polygon_mesh();
  std::vector<std::array<std::uint32_t, 3>> set;
  for (std::size_t f = 0; f < polygons.face_count(); ++f) {
    const std::uint32_t* t = polygons.face_begin(f);
    std::array<std::uint32_t, 3> sorted{t[0], t[1], t[2]};
    std::sort(sorted.begin(), sorted.end());
    set.push_back(sorted);
  }
  std::sort(set.begin(), set.end());
  return set;
}

TEST(EdgeFlip, FlipMovesValenceAndFlippingAgainRestoresTheTriangulation) {
  CollapseMesh mesh(fan_triangulate(test::quad_grid(8, 8)));
  const auto before = triangle_set(mesh);
  const std::uint32_t e = edge_between(mesh, 20, 30);  // a diagonal of the planar grid
  const auto [vi, vj, a, b] = mesh.edge_vertices(e);
  const std::uint32_t valences[4] = {mesh.valence(vi), mesh.valence(vj), mesh.valence(a), mesh.valence(b)};
  ASSERT_TRUE(mesh.can_flip(e));
  mesh.flip(e);
  EXPECT_EQ(mesh.validate(), "");
  EXPECT_EQ(mesh.find_edge(vi, vj), CollapseMesh::kNone);
  EXPECT_EQ(mesh.find_edge(a, b), e);
  EXPECT_EQ(mesh.valence(vi), valences[0] - 1);
  EXPECT_EQ(mesh.valence(vj), valences[1] - 1);
  EXPECT_EQ(mesh.valence(a), valences[2] + 1);
  EXPECT_EQ(mesh.valence(b), valences[3] + 1);
  EXPECT_NE(triangle_set(mesh), before);
  ASSERT_TRUE(mesh.can_flip(e));
  mesh.flip(e);
  EXPECT_EQ(mesh.validate(), "");
  EXPECT_EQ(triangle_set(mesh), before);
}

TEST(EdgeFlip, IllegalFlips) {
  // Boundary edge; an edge whose flip would duplicate an existing edge.
  const CollapseMesh grid(fan_triangulate(test::quad_grid(8, 8)));
  EXPECT_FALSE(grid.can_flip(edge_between(grid, 0, 1)));
  const CollapseMesh tetrahedron(test::tetrahedron());
  for (std::uint32_t e = 0; e < tetrahedron.edge_slots(); ++e) EXPECT_FALSE(tetrahedron.can_flip(e));
  // The octahedron's quads bend by 109 degrees: only a threshold of -1 lets them flip.
  const CollapseMesh octahedron(test::icosphere(0));
  CollapseRules any_bend;
  any_bend.flip_min_normal_dot = -1;
  const CollapseMesh loose(test::icosphere(0), any_bend);
  for (std::uint32_t e = 0; e < octahedron.edge_slots(); ++e) {
    EXPECT_FALSE(octahedron.can_flip(e));
    EXPECT_TRUE(loose.can_flip(e));
  }
  // A sharp endpoint never loses its edge.
  PolygonMesh sharp = fan_triangulate(test::quad_grid(8, 8));
  sharp.sharp.assign(sharp.vertex_count(), 0);
  sharp.sharp[20] = 1;
  const CollapseMesh with_sharp(sharp);
  EXPECT_FALSE(with_sharp.can_flip(edge_between(with_sharp, 20, 30)));
  EXPECT_TRUE(grid.can_flip(edge_between(grid, 20, 30)));
  // Valence: a and b may not rise above the limit.
  CollapseRules six;
  six.max_valence = 6;
  const CollapseMesh capped(fan_triangulate(test::quad_grid(8, 8)), six);
  const std::uint32_t e = edge_between(capped, 20, 30);
  const auto quad = capped.edge_vertices(e);
  EXPECT_EQ(capped.can_flip(e), capped.valence(quad[2]) < 6 && capped.valence(quad[3]) < 6);
}

TEST(EdgeFlip, LowerValenceFlipsSpokesAndUndoRestores) {
  CollapseMesh mesh(test::wheel(12));
  const auto before = triangle_set(mesh);
  ASSERT_EQ(mesh.valence(0), 12u);
  std::vector<std::uint32_t> flipped;
  EXPECT_EQ(mesh.lower_valence(0, 4, nullptr, 0, flipped), 4);
  EXPECT_EQ(flipped.size(), 4u);
  EXPECT_EQ(mesh.valence(0), 8u);
  EXPECT_EQ(mesh.validate(), "");
  for (std::size_t k = flipped.size(); k-- > 0;) mesh.flip(flipped[k]);
  EXPECT_EQ(mesh.validate(), "");
  EXPECT_EQ(triangle_set(mesh), before);
  // Kept neighbours keep their edge to the centre.
  const std::uint32_t keep[2] = {1, 2};
  flipped.clear();
  mesh.lower_valence(0, 9, keep, 2, flipped);
  EXPECT_NE(mesh.find_edge(0, 1), CollapseMesh::kNone);
  EXPECT_NE(mesh.find_edge(0, 2), CollapseMesh::kNone);
  EXPECT_GE(mesh.valence(0), 3u);
  EXPECT_EQ(mesh.validate(), "");
}

TEST(EdgeFlip, FlipCapacityCountsFlippableSpokesAndZeroMeansNoFlip) {
  CollapseMesh wheel(test::wheel(12));
  // Every spoke is flippable; the centre may lose 12 - 3.
  EXPECT_EQ(wheel.flip_capacity(0, nullptr, 0), 9);
  // Spokes to kept vertices are not: 2 of 12 remain.
  const std::uint32_t keep[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  EXPECT_EQ(wheel.flip_capacity(0, keep, 10), 2);
  std::vector<std::uint32_t> flipped;
  EXPECT_LE(wheel.lower_valence(0, 9, keep, 10, flipped), 2);
  for (std::size_t k = flipped.size(); k-- > 0;) wheel.flip(flipped[k]);
  // With the valence limit at the ring's smallest valence, every spoke's
  // opposite vertices are full: no capacity, and lower_valence flips nothing.
  std::uint32_t smallest_ring_valence = 99;
  for (std::uint32_t v = 1; v <= 12; ++v) smallest_ring_valence = std::min(smallest_ring_valence, wheel.valence(v));
  CollapseRules rules;
  rules.max_valence = static_cast<int>(smallest_ring_valence);
  CollapseMesh full(test::wheel(12), rules);
  EXPECT_EQ(full.flip_capacity(0, nullptr, 0), 0);
  flipped.clear();
  EXPECT_EQ(full.lower_valence(0, 3, nullptr, 0, flipped), 0);
  EXPECT_EQ(full.validate(), "");
}

// --- (4.1)-(4.3) through the mesh, and the error propagation ---

// Reference (4.1)-(4.2) written out independently for the test; a boundary
// collapse's curve move (SimplifyOptions::boundary_curve_error) joins the
// maximum that the weight multiplies.
double reference_delta_error(const Vec3& d, const std::vector<Vec3>& c, double boundary_move = 0) {
  double e0 = 0, max_length = 0;
  Vec3 average;
  for (const Vec3& ci : c) {
    const Vec3 n = ci * (1.0 / norm(ci));
    e0 = std::max(e0, std::fabs(dot(d * 0.5, n)));
    average += n * (1.0 / double(c.size()));
    max_length = std::max(max_length, norm(ci));
  }
  average = average * (1.0 / norm(average));
  double min_projection = 1e300;
  for (const Vec3& ci : c) min_projection = std::min(min_projection, dot(ci, average));
  return std::pow(2.0 - min_projection / max_length, 16) * std::max({e0, 1e-8, boundary_move});
}

// The ring triangles' cross products after collapsing (vi, vj) to p, straight
// from the face list: faces with exactly one endpoint, that endpoint replaced
// by p, rotated to start at p.
std::vector<Vec3> cross_products_after_collapse(const PolygonMesh& mesh, std::uint32_t vi, std::uint32_t vj,
                                                const Vec3& p) {
  std::vector<Vec3> c;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* t = mesh.face_begin(f);
    int hits = 0, at = -1;
    for (int k = 0; k < 3; ++k)
      if (t[k] == vi || t[k] == vj) ++hits, at = k;
    if (hits != 1) continue;
    c.push_back(cross(mesh.positions[t[(at + 1) % 3]] - p, mesh.positions[t[(at + 2) % 3]] - p));
  }
  return c;
}

TEST(CollapseError, MeshEvaluationMatchesTheFormulasOnTheRingAfterCollapse) {
  PolygonMesh sphere = test::icosphere(2);
  test::jitter(sphere, 0.02, 7);
  const CollapseMesh mesh(sphere);
  std::size_t compared = 0;
  for (std::uint32_t e = 0; e < mesh.edge_slots(); ++e) {
    const Evaluation evaluation = mesh.evaluate(e);
    if (evaluation.legality != Legality::Legal) continue;
    const std::uint32_t h = mesh.edge_halfedge(e);
    const std::uint32_t vi = mesh.origin(h), vj = mesh.target(h);
    const Vec3 p = (sphere.positions[vi] + sphere.positions[vj]) * 0.5;
    const std::vector<Vec3> c = cross_products_after_collapse(sphere, vi, vj, p);
    const double expected = reference_delta_error(sphere.positions[vj] - sphere.positions[vi], c);
    EXPECT_NEAR(evaluation.delta_error, expected, 1e-9 * expected) << "edge " << e;
    EXPECT_EQ(evaluation.position, p);
    ++compared;
  }
  EXPECT_GT(compared, 100u);
}

TEST(CollapseError, AccumulatedErrorIsTheMaximumOfTheFiveDestroyedEdges) {
  PolygonMesh sphere = test::icosphere(2);
  test::jitter(sphere, 0.03, 11);
  CollapseMesh mesh(sphere);
  for (std::uint32_t e = 0; e < mesh.edge_slots(); ++e) {
    const Evaluation evaluation = mesh.evaluate(e);
    if (evaluation.geometry_computed) mesh.set_latest_delta_error(e, evaluation.delta_error);
  }
  // Two successive collapses: the second one sees non-zero E_acc.
  for (int round = 0; round < 2; ++round) {
    std::uint32_t e = 0;
    while (mesh.evaluate(e).legality != Legality::Legal) ++e;
    const Evaluation evaluation = mesh.evaluate(e);
    mesh.set_latest_delta_error(e, evaluation.delta_error);
    const std::uint32_t h = mesh.edge_halfedge(e);
    const std::uint32_t vi = mesh.origin(h), vj = mesh.target(h);
    const std::uint32_t a = mesh.origin(CollapseMesh::prev(h)), b = mesh.origin(CollapseMesh::prev(mesh.opposite(h)));
    double expected = mesh.error(e);
    for (std::uint32_t x : {a, b})
      for (std::uint32_t y : {vi, vj}) expected = std::max(expected, mesh.error(edge_between(mesh, x, y)));
    // E_acc before the collapse of the edges that will be around v.
    std::vector<std::pair<std::uint32_t, float>> before;
    for (std::uint32_t f = 0; f < mesh.edge_slots(); ++f) {
      if (!mesh.edge_alive(f)) continue;
      const std::uint32_t fh = mesh.edge_halfedge(f);
      const bool at_endpoint = mesh.origin(fh) == vi || mesh.target(fh) == vi || mesh.origin(fh) == vj ||
                               mesh.target(fh) == vj;
      if (at_endpoint) before.emplace_back(f, mesh.accumulated_error(f));
    }
    std::uint32_t removed[3], opposite[2];
    const std::uint32_t v = mesh.collapse(e, evaluation.position, removed, opposite);
    ASSERT_EQ(mesh.validate(), "");
    std::size_t around = 0;
    for (const auto& [f, old_acc] : before) {
      if (!mesh.edge_alive(f)) continue;
      ++around;
      EXPECT_FLOAT_EQ(mesh.accumulated_error(f), std::max(old_acc, float(expected)));
    }
    EXPECT_EQ(around, mesh.valence(v));
    EXPECT_GT(expected, 0.0);
  }
}

// --- the fan cache and the supplied squared norms are pure speed-ups ---

void expect_identical(const Evaluation& a, const Evaluation& b, std::uint32_t e) {
  EXPECT_EQ(a.legality, b.legality) << "edge " << e;
  EXPECT_EQ(a.geometry_computed, b.geometry_computed) << "edge " << e;
  // Bit-identical, not merely close: the queue order depends on them.
  EXPECT_EQ(a.delta_error, b.delta_error) << "edge " << e;
  EXPECT_EQ(a.position, b.position) << "edge " << e;
}

TEST(FanCache, SharedCacheGivesBitIdenticalEvaluationsAcrossCollapses) {
  // One cache reused over many collapses (the simplify() loop's pattern, with
  // boundary loops and the stencil of each collapse) against a fresh gather
  // for every evaluation.
  for (const double min_normal_dot : {0.0, 0.3, -0.5}) {
    PolygonMesh sphere = test::icosphere(3);
    test::jitter(sphere, 0.05, 3);
    // Open some holes: drop every 37th face (keeps the fans manifold).
    PolygonMesh holed;
    holed.positions = sphere.positions;
    for (std::size_t f = 0; f < sphere.face_count(); ++f)
      if (f % 37 != 5) holed.add_face({sphere.face_begin(f)[0], sphere.face_begin(f)[1], sphere.face_begin(f)[2]});
    ASSERT_NO_THROW(require_manifold(holed, "holed sphere"));
    CollapseRules rules;
    rules.min_normal_dot = min_normal_dot;
    CollapseMesh mesh(holed, rules);
    FanCache cache;
    std::size_t legal = 0, collapses = 0;
    std::vector<std::uint32_t> stencil;
    for (std::uint32_t e = 0; e < mesh.edge_slots() && collapses < 150; e += 3) {
      const Evaluation cached = mesh.evaluate(e, cache);
      expect_identical(cached, mesh.evaluate(e), e);
      if (cached.legality != Legality::Legal) continue;
      std::uint32_t removed[3], opposite[2];
      const std::uint32_t v = mesh.collapse(e, cached.position, removed, opposite);
      ++collapses;
      const std::uint32_t centres[3] = {v, opposite[0], opposite[1]};
      stencil.clear();
      mesh.gather_stencil(centres, 3, stencil);
      for (std::uint32_t s : stencil) {
        const Evaluation update = mesh.evaluate(s, cache);
        expect_identical(update, mesh.evaluate(s), s);
        if (update.legality == Legality::Legal) ++legal;
      }
    }
    ASSERT_EQ(mesh.validate(), "");
    EXPECT_GT(collapses, 60u);
    EXPECT_GT(legal, 500u);
  }
}

// A flat disc whose boundary is a circle: (4.1) gives every collapse there
// the clamped minimum, so only the boundary curve's move can tell a boundary
// collapse that keeps the circle from one that cuts into it.
TEST(CollapseError, BoundaryCollapseAlsoCountsTheMoveOfTheBoundaryCurve) {
  PolygonMesh disc = fan_triangulate(test::quad_grid(12, 12));
  for (Vec3& p : disc.positions) {  // the square [0, 12]^2 onto the disc of radius 6 (elliptical grid map)
    const double u = p.x / 6 - 1, v = p.y / 6 - 1;
    p = {6 * u * std::sqrt(1 - v * v / 2), 6 * v * std::sqrt(1 - u * u / 2), 0};
  }
  // The ring after the collapse and the boundary edges, from the face list.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edge_face;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edge_count;
  for (std::uint32_t f = 0; f < disc.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = disc.face_begin(f)[k], b = disc.face_begin(f)[(k + 1) % 3];
      edge_face[{std::min(a, b), std::max(a, b)}] = f;
      ++edge_count[{std::min(a, b), std::max(a, b)}];
    }
  const auto move_along = [&](std::uint32_t v, std::uint32_t other, const Vec3& p) {
    for (const auto& [edge, count] : edge_count) {
      if (count != 1 || (edge.first != v && edge.second != v)) continue;
      const std::uint32_t w = edge.first == v ? edge.second : edge.first;
      if (w == other) continue;
      const std::uint32_t* t = disc.face_begin(edge_face.at(edge));
      const Vec3 normal = cross(disc.positions[t[1]] - disc.positions[t[0]], disc.positions[t[2]] - disc.positions[t[0]]);
      const Vec3 m = normalized(cross(disc.positions[w] - disc.positions[v], normal));
      return std::fabs(dot(p - disc.positions[v], m));
    }
    ADD_FAILURE() << "no second boundary edge at " << v;
    return 0.0;
  };
  CollapseRules paper_rules;
  paper_rules.boundary_curve_error = false;
  const CollapseMesh mesh(disc), paper(disc, paper_rules);
  std::size_t boundary_compared = 0, interior_compared = 0;
  for (std::uint32_t e = 0; e < mesh.edge_slots(); ++e) {
    const Evaluation evaluation = mesh.evaluate(e), paper_evaluation = paper.evaluate(e);
    ASSERT_EQ(evaluation.legality, paper_evaluation.legality);
    if (evaluation.legality != Legality::Legal) continue;
    const std::uint32_t h = mesh.edge_halfedge(e);
    const std::uint32_t vi = mesh.origin(h), vj = mesh.target(h);
    const bool boundary_edge = edge_count.at({std::min(vi, vj), std::max(vi, vj)}) == 1;
    if (!boundary_edge) {
      EXPECT_EQ(evaluation.delta_error, paper_evaluation.delta_error);
      ++interior_compared;
      continue;
    }
    const Vec3 p = (disc.positions[vi] + disc.positions[vj]) * 0.5;
    const std::vector<Vec3> c = cross_products_after_collapse(disc, vi, vj, p);
    const Vec3 d = disc.positions[vj] - disc.positions[vi];
    const double move = std::max(move_along(vi, vj, p), move_along(vj, vi, p));
    EXPECT_GT(move, 1e-3) << "a chord of the circle moves the curve";
    EXPECT_NEAR(evaluation.delta_error, reference_delta_error(d, c, move), 1e-9 * evaluation.delta_error);
    EXPECT_NEAR(paper_evaluation.delta_error, reference_delta_error(d, c), 1e-9 * paper_evaluation.delta_error);
    EXPECT_GT(evaluation.delta_error, 1e4 * paper_evaluation.delta_error);
    ++boundary_compared;
  }
  EXPECT_GT(boundary_compared, 10u);
  EXPECT_GT(interior_compared, 100u);
}

TEST(CollapseError, SuppliedSquaredNormsGiveTheSameTerms) {
  const std::vector<Vec3> c = {{0.1, 0.2, 2}, {0.3, -0.1, 1.5}, {0, 0.4, 0.9}, {-0.2, 0.1, 1.1}};
  std::vector<double> squared;
  for (const Vec3& ci : c) squared.push_back(squared_norm(ci));
  const CollapseErrorTerms plain = collapse_error_terms({0.3, 0.1, 0.2}, c.data(), c.size());
  const CollapseErrorTerms supplied = collapse_error_terms({0.3, 0.1, 0.2}, c.data(), squared.data(), c.size());
  EXPECT_EQ(plain.delta_e0, supplied.delta_e0);
  EXPECT_EQ(plain.weight, supplied.weight);
  EXPECT_EQ(plain.delta_e, supplied.delta_e);
}

}  // namespace
}  // namespace isowave::simplify
