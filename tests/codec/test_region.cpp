// Region-of-interest reconstruction (codec/region.h, issue #48 item 1)
// against the synthesis itself: inside the region the points equal the full
// decode's, an entry the region does not need moves no point inside it when
// perturbed (and one it needs moves some), and the outside keeps the ranked
// coefficients asked for.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "codec_test_data.h"
#include "isowave/codec/region.h"
#include "isowave/core/error.h"

namespace isowave {
namespace {

struct RegionCase {
  test::CodedSurface surface;
  IswDecoded decoded;
  RegionOfInterest region;
};

// A jittered 20 x 20 grid (unit edges) at 3 levels, the region a 3 x 3 box
// near a corner, the ranked order by decreasing magnitude.
RegionCase make_case() {
  RegionCase c{test::make_coded_surface(test::quad_grid(20, 20), 3, 0.2, 7), {}, {}};
  const SubdivisionHierarchy& h = *c.surface.hierarchy;
  c.decoded.hierarchy = std::make_shared<const SubdivisionHierarchy>(c.surface.base, 3);
  c.decoded.levels = 3;
  c.decoded.coefficients = c.surface.coefficients;
  c.decoded.class_weights.assign(7, 1.0);
  const std::size_t base = h.vertex_count(0), n = h.fine_vertex_count();
  c.decoded.ranked.resize(n - base);
  std::iota(c.decoded.ranked.begin(), c.decoded.ranked.end(), std::uint32_t(base));
  std::sort(c.decoded.ranked.begin(), c.decoded.ranked.end(), [&](std::uint32_t a, std::uint32_t b) {
    return squared_norm(c.surface.coefficients[a]) > squared_norm(c.surface.coefficients[b]);
  });
  c.region = parse_region("2.5,2.5,-10,5.5,5.5,10", false, "--roi");
  return c;
}

std::vector<Vec3> synthesized(const SubdivisionHierarchy& h, std::vector<Vec3> data) {
  synthesize(h, data);
  data.resize(h.fine_vertex_count());
  return data;
}

TEST(Region, InsideEqualsTheFullDecodeAndOutsideTheBaseSurface) {
  const RegionCase c = make_case();
  const SubdivisionHierarchy& h = *c.decoded.hierarchy;
  const RegionReconstruction r = reconstruct_region(c.decoded, c.region, 0);
  ASSERT_GT(r.inside_points, 50u);
  ASSERT_LT(r.inside_points, h.fine_vertex_count() / 10);
  // The base mesh's surface alone: every coefficient zero.
  std::vector<Vec3> coarse_data = c.decoded.coefficients;
  std::fill(coarse_data.begin() + static_cast<std::ptrdiff_t>(h.vertex_count(0)), coarse_data.end(), Vec3{});
  const std::vector<Vec3> coarse = synthesized(h, coarse_data);
  std::size_t inside = 0, far_outside = 0;
  for (std::size_t v = 0; v < h.fine_vertex_count(); ++v) {
    const Vec3& p = c.surface.fine[v];
    if (c.region.contains(p)) {
      ++inside;
      EXPECT_LT(std::sqrt(squared_norm(r.fine[v] - p)), 1e-12) << v;
    }
    // Ten base edges from the box, beyond any lifted wavelet's reach: the base mesh's surface.
    const bool far = p.x > 15.5 || p.y > 15.5;
    if (far) {
      ++far_outside;
      EXPECT_LT(std::sqrt(squared_norm(r.fine[v] - coarse[v])), 1e-12) << v;
    }
  }
  EXPECT_EQ(inside, r.inside_points);
  EXPECT_GT(far_outside, h.fine_vertex_count() / 4);
  EXPECT_LT(r.kept_coefficients, c.decoded.ranked.size() / 5);
}

// Exactness both ways, against synthesis: perturbing an entry the region does
// not need moves no point inside it; perturbing one it needs moves some.
TEST(Region, NeededEntriesAreExactlyThoseTheRegionsPointsDependOn) {
  const RegionCase c = make_case();
  const SubdivisionHierarchy& h = *c.decoded.hierarchy;
  const std::vector<std::uint8_t> needed = entries_for_region(h, c.surface.fine, c.region);
  const std::vector<Vec3> full = synthesized(h, c.decoded.coefficients);
  std::size_t checked_needed = 0, checked_free = 0;
  for (std::size_t k = 0; k < h.fine_vertex_count(); k += 37) {
    std::vector<Vec3> data = c.decoded.coefficients;
    data[k] += Vec3{0.3, -0.2, 0.5};
    const std::vector<Vec3> moved = synthesized(h, data);
    double inside_move = 0;
    for (std::size_t v = 0; v < h.fine_vertex_count(); ++v)
      if (c.region.contains(full[v])) inside_move = std::max(inside_move, std::sqrt(squared_norm(moved[v] - full[v])));
    if (needed[k]) {
      ++checked_needed;
      EXPECT_GT(inside_move, 1e-9) << "entry " << k << " is needed but moves nothing inside";
    } else {
      ++checked_free;
      EXPECT_EQ(inside_move, 0.0) << "entry " << k << " moves a point inside but was left out";
    }
  }
  EXPECT_GT(checked_needed, 5u);
  EXPECT_GT(checked_free, 5u);
}

TEST(Region, TheOutsideKeepsTheRankedCoefficientsAskedFor) {
  const RegionCase c = make_case();
  const SubdivisionHierarchy& h = *c.decoded.hierarchy;
  const RegionReconstruction all = reconstruct_region(c.decoded, c.region, c.decoded.ranked.size());
  for (std::size_t v = 0; v < h.fine_vertex_count(); ++v)
    EXPECT_LT(std::sqrt(squared_norm(all.fine[v] - c.surface.fine[v])), 1e-12) << v;
  const RegionReconstruction some = reconstruct_region(c.decoded, c.region, 100);
  const RegionReconstruction none = reconstruct_region(c.decoded, c.region, 0);
  EXPECT_GT(some.kept_coefficients, none.kept_coefficients);
  EXPECT_LE(some.kept_coefficients, none.kept_coefficients + 100);
}

// The magnifying glass: with a falloff the coefficients kept outside lie
// nearer the region than by importance alone; a falloff far wider than the
// surface keeps what importance alone keeps.
TEST(Region, AFalloffKeepsTheOutsideDetailNearTheRegion) {
  RegionCase c = make_case();
  const SubdivisionHierarchy& h = *c.decoded.hierarchy;
  const std::vector<Vec3> full = synthesized(h, c.decoded.coefficients);
  const auto kept_distance = [&](double falloff) {
    c.region.falloff = falloff;
    const RegionReconstruction none = reconstruct_region(c.decoded, c.region, 0);
    const RegionReconstruction some = reconstruct_region(c.decoded, c.region, 300);
    EXPECT_EQ(some.kept_coefficients, none.kept_coefficients + 300) << falloff;
    double sum = 0;
    std::size_t count = 0;
    // The moved fine points outside: where the kept outside detail acts.
    for (std::size_t v = 0; v < h.fine_vertex_count(); ++v)
      if (norm(some.fine[v] - none.fine[v]) > 1e-12) {
        sum += c.region.distance(full[v]);
        ++count;
      }
    return std::make_pair(sum / static_cast<double>(std::max<std::size_t>(count, 1)), some.fine);
  };
  const auto [plain, plain_fine] = kept_distance(0);
  const auto [near, near_fine] = kept_distance(1.5);
  const auto [wide, wide_fine] = kept_distance(1e6);
  EXPECT_LT(near, 0.6 * plain);
  EXPECT_EQ(wide_fine, plain_fine);
}

// The decode's mesh with nothing kept outside: the region's base faces at the
// finest level keep every fine point inside, the others are whole base faces.
TEST(Region, TheAdaptiveMeshKeepsEveryPointInsideAndFewOutside) {
  const RegionCase c = make_case();
  const SubdivisionHierarchy& h = *c.decoded.hierarchy;
  RegionReconstruction r;
  const PolygonMesh mesh = region_mesh(c.decoded, c.region, 0, &r);
  const std::vector<int> levels = region_face_levels(h, reconstruct_region(c.decoded, c.region, 0).fine, c.region, 0);
  std::size_t inside = 0;
  for (const Vec3& p : mesh.positions) inside += c.region.contains(p);
  EXPECT_EQ(inside, r.inside_points);
  const std::size_t fine_faces = static_cast<std::size_t>(std::count(levels.begin(), levels.end(), 3));
  EXPECT_GT(fine_faces, 0u);
  EXPECT_LT(fine_faces, levels.size() / 4);
  EXPECT_LT(mesh.vertex_count(), h.fine_vertex_count() / 4);
}

TEST(Region, ParsesBoxesAndBallsAndRefusesAnythingElse) {
  const RegionOfInterest box = parse_region("3,2,1,0,5,-1", false, "--roi");
  EXPECT_TRUE(box.contains({1, 3, 0}));
  EXPECT_FALSE(box.contains({4, 3, 0}));
  const RegionOfInterest ball = parse_region("1,1,1,2", true, "--roi-sphere");
  EXPECT_TRUE(ball.contains({2.9, 1, 1}));
  EXPECT_FALSE(ball.contains({3.1, 1, 1}));
  for (const char* bad : {"", "1,2,3", "1,2,3,4,5,6,7", "1,2,x,4,5,6", "1,2,3,4,5,nan", "1,,3,4,5,6", "1,2,3,4,5,6e"})
    EXPECT_THROW(parse_region(bad, false, "--roi"), Error) << bad;
  for (const char* bad : {"1,2,3,0", "1,2,3,-1", "1,2,3", "1,2,3,inf"})
    EXPECT_THROW(parse_region(bad, true, "--roi-sphere"), Error) << bad;
}

}  // namespace
}  // namespace isowave
