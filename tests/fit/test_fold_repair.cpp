// take_back_folding_moves (fit/fold_repair.h): moves that fold a face go back,
// the others stay.
#include <gtest/gtest.h>

#include <vector>

#include "isowave/fit/fold_repair.h"
#include "isowave/fit/wrap_level_mesh.h"
#include "isowave/transform/hierarchy.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

// A 6 x 6 quad grid (unit cells, vertex (i, j) at index 7 j + i) lying on the
// plane z = 4 of the field 10 - z: its normals point towards lower values.
struct GridOnPlane {
  Volume field = test::sampled_volume({12, 12, 12}, [](double, double, double z) { return 10.0 - z; });
  PolygonMesh grid = [] {
    PolygonMesh g = test::quad_grid(6, 6);
    for (Vec3& p : g.positions) p += Vec3{3, 3, 4};
    return g;
  }();
  WrapLevelMesh mesh = make_wrap_level_mesh(SubdivisionHierarchy(grid, 1), 0, grid.positions, field);
  static std::uint32_t id(int i, int j) { return static_cast<std::uint32_t>(7 * j + i); }
};

TEST(FoldRepair, AMoveThatFoldsGoesBackAndAHarmlessOneStays) {
  const GridOnPlane g;
  const std::vector<Vec3>& before = g.grid.positions;
  ASSERT_EQ(count_folded_faces(g.mesh, before, g.field, Orientation::TowardLower), 0u);
  std::vector<Vec3> after = before;
  after[g.id(4, 4)].x += 3.0;  // past its neighbour (5, 4): a face turns over
  after[g.id(1, 1)].z += 0.3;  // off the plane, no face turns over; no face shared with (4, 4)
  ASSERT_GT(count_folded_faces(g.mesh, after, g.field, Orientation::TowardLower), 0u);

  EXPECT_EQ(take_back_folding_moves(g.mesh, g.field, Orientation::TowardLower, before, after), 1u);
  EXPECT_EQ(count_folded_faces(g.mesh, after, g.field, Orientation::TowardLower), 0u);
  EXPECT_EQ(after[g.id(4, 4)], before[g.id(4, 4)]);
  EXPECT_EQ(after[g.id(1, 1)].z, before[g.id(1, 1)].z + 0.3);
}

TEST(FoldRepair, TwoMovesThatFoldTogetherBothGoBack) {
  // (2, 2) and (3, 2) swap sides; either move alone would not fold a face.
  const GridOnPlane g;
  const std::vector<Vec3>& before = g.grid.positions;
  std::vector<Vec3> after = before;
  after[g.id(2, 2)].x += 1.5;
  after[g.id(3, 2)].x -= 1.5;
  ASSERT_GT(count_folded_faces(g.mesh, after, g.field, Orientation::TowardLower), 0u);
  EXPECT_EQ(take_back_folding_moves(g.mesh, g.field, Orientation::TowardLower, before, after), 2u);
  EXPECT_EQ(after, before);
}

TEST(FoldRepair, FacesFoldedBeforeMayStayFolded) {
  // The grid turned over (normals against the field's orientation): every
  // face is folded before and after, so nothing goes back.
  const GridOnPlane g;
  const std::vector<Vec3>& before = g.grid.positions;
  std::vector<Vec3> after = before;
  after[g.id(3, 3)].z += 0.2;
  const std::size_t faces = g.mesh.face_count();
  ASSERT_EQ(count_folded_faces(g.mesh, before, g.field, Orientation::TowardHigher), faces);
  EXPECT_EQ(take_back_folding_moves(g.mesh, g.field, Orientation::TowardHigher, before, after), 0u);
  EXPECT_EQ(after[g.id(3, 3)].z, before[g.id(3, 3)].z + 0.2);
}

}  // namespace
}  // namespace isowave
