// View-dependent refinement (codec/view.h, issue #48 item 2): the camera's
// JSON read strictly; a nearer camera refines every face in view at least as
// much; faces outside the frustum (checked against a pinhole projection
// written here) stay base faces and faces with a point in the image are never
// culled; the mesh is crack-free (no directed edge twice, no boundary edge
// beyond the full decode's).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "codec_test_data.h"
#include "isowave/codec/region.h"
#include "isowave/codec/view.h"
#include "isowave/core/error.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {
namespace {

struct ViewCase {
  test::CodedSurface surface;
  IswDecoded decoded;
  std::vector<Vec3> fine;
};

// A jittered 20 x 20 grid (unit edges, near z = 0) at 3 levels.
const ViewCase& view_case() {
  static const ViewCase c = [] {
    ViewCase out{test::make_coded_surface(test::quad_grid(20, 20), 3, 0.2, 5), {}, {}};
    out.decoded.hierarchy = std::make_shared<const SubdivisionHierarchy>(out.surface.base, 3);
    out.decoded.levels = 3;
    out.decoded.coefficients = out.surface.coefficients;
    out.decoded.class_weights = std::vector<double>(7, 1.0);
    out.fine = out.surface.fine;
    return out;
  }();
  return c;
}

Camera camera_at(const Vec3& position, const Vec3& target, double fov = 60) {
  Camera c;
  c.position = position;
  c.target = target;
  c.up = {0, 1, 0};
  c.fov_degrees = fov;
  c.width = 800;
  c.height = 600;
  return c;
}

TEST(View, ReadsTheCameraStrictly) {
  const Camera c = parse_camera(
      R"({"position": [1, 2, 3], "target":[0,0,0], "up":[0,0,1], "fov": 45, "viewport": [1920, 1080]})", "cam.json");
  EXPECT_EQ(c.position, (Vec3{1, 2, 3}));
  EXPECT_EQ(c.up, (Vec3{0, 0, 1}));
  EXPECT_EQ(c.fov_degrees, 45);
  EXPECT_EQ(c.width, 1920);
  EXPECT_EQ(c.height, 1080);
  const std::string good = R"("target":[0,0,0],"up":[0,0,1],"fov":45,"viewport":[640,480])";
  for (const std::string& bad : {
           std::string("{") + good + "}",                                       // no position
           std::string(R"({"position":[1,2,3],)") + good + R"(,"zoom":2})",     // an unknown key
           std::string(R"({"position":[1,2],)") + good + "}",                   // two numbers
           std::string(R"({"position":[1,2,"a"],)") + good + "}",              // not a number
           std::string(R"({"position":[1,2,3],)") + good + "} x",               // text after it
           std::string(R"({"position":[1,2,3],"position":[1,2,3],)") + good + "}",  // twice
           std::string(R"({"position":[0,0,0],)") + good + "}",                 // at its target
           std::string(R"({"position":[0,0,5],)") + good + "}",                 // up along the view
           std::string(R"({"position":[1,2,3],"target":[0,0,0],"up":[0,0,1],"fov":180,"viewport":[640,480]})"),
           std::string(R"({"position":[1,2,3],"target":[0,0,0],"up":[0,0,1],"fov":45,"viewport":[640.5,480]})"),
           std::string(R"({"position":[1,2,3],"target":[0,0,0],"up":[0,0,1],"fov":45,"viewport":[0,480]})"),
           std::string(""), std::string("[1,2,3]")}) {
    try {
      parse_camera(bad, "cam.json");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const Error& error) {
      EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos) << error.what();
    }
  }
}

// Looking straight down from above the grid's middle (90 degrees): every face in view.
TEST(View, ANearerCameraRefinesEveryFaceAtLeastAsMuch) {
  const ViewCase& c = view_case();
  const ViewLevels far = view_face_levels(c.decoded, c.fine, camera_at({10, 10, 40}, {10, 10, 0}, 90), 1.0);
  const ViewLevels near = view_face_levels(c.decoded, c.fine, camera_at({10, 10, 15}, {10, 10, 0}, 90), 1.0);
  EXPECT_EQ(far.culled, 0u);
  EXPECT_EQ(near.culled, 0u);
  for (std::size_t f = 0; f < far.levels.size(); ++f) EXPECT_GE(near.levels[f], far.levels[f]) << f;
  const auto sum = [](const ViewLevels& v) { return std::accumulate(v.levels.begin(), v.levels.end(), 0); };
  EXPECT_GT(sum(near), sum(far));
  // Coarser as the pixel error grows: everything at the base for a huge one.
  const ViewLevels coarse = view_face_levels(c.decoded, c.fine, camera_at({10, 10, 15}, {10, 10, 0}, 90), 1e9);
  EXPECT_EQ(sum(coarse), 0);
  const ViewLevels fine = view_face_levels(c.decoded, c.fine, camera_at({10, 10, 15}, {10, 10, 0}, 90), 1e-9);
  EXPECT_EQ(sum(fine), 3 * static_cast<int>(fine.levels.size()));
}

// Whether p projects into the image of a look-at pinhole camera.
bool in_image(const Camera& c, const Vec3& p) {
  const Vec3 d = normalized(c.target - c.position), r = normalized(cross(d, c.up)), u = cross(r, d);
  const Vec3 v = p - c.position;
  const double z = dot(v, d);
  if (z <= 0) return false;
  const double f = 0.5 * c.height / std::tan(c.fov_degrees * 3.14159265358979323846 / 360);
  const double x = f * dot(v, r) / z, y = f * dot(v, u) / z;
  return std::abs(x) <= 0.5 * c.width && std::abs(y) <= 0.5 * c.height;
}

TEST(View, FacesOutsideTheFrustumStayBaseFacesAndFacesInViewAreKept) {
  const ViewCase& c = view_case();
  const SubdivisionHierarchy& h = *c.decoded.hierarchy;
  for (const Camera& camera : {camera_at({4, 4, 6}, {4, 4, 0}, 30), camera_at({-5, 10, 2}, {0, 10, 1}, 40)}) {
    const ViewLevels v = view_face_levels(c.decoded, c.fine, camera, 0.01);
    EXPECT_GT(v.culled, v.levels.size() / 4);
    EXPECT_LT(v.culled, v.levels.size());
    std::size_t culled = 0;
    for (std::size_t f = 0; f < v.levels.size(); ++f) {
      bool seen = false;
      for_each_fine_point(h, f, [&](std::size_t p) { return !(seen = in_image(camera, c.fine[p])); });
      if (seen) {
        EXPECT_EQ(v.levels[f], 3) << "face " << f << " is in view";
      }
      culled += !seen && v.levels[f] == 0;
    }
    EXPECT_GE(culled, v.culled);
  }
  // Looking away: everything culled.
  const ViewLevels away = view_face_levels(c.decoded, c.fine, camera_at({10, 10, 5}, {10, 10, 50}), 1.0);
  EXPECT_EQ(away.culled, away.levels.size());
}

// A closed surface: a sphere of radius 5 around the origin over a 96-face
// base (the cube's level-2 control mesh), outward, at 2 levels.
ViewCase sphere_case() {
  const SubdivisionHierarchy cube(test::cube(), 2);
  PolygonMesh base = cube.control_mesh(2, subdivide(cube, test::cube().positions));
  const auto on_sphere = [](Vec3 p) { return normalized(p - Vec3{0.5, 0.5, 0.5}) * 5.0; };
  for (Vec3& p : base.positions) p = on_sphere(p);
  ViewCase out;
  out.decoded.hierarchy = std::make_shared<const SubdivisionHierarchy>(base, 2);
  out.decoded.levels = 2;
  out.fine = subdivide(*out.decoded.hierarchy, base.positions);
  for (Vec3& p : out.fine) p = on_sphere(p);
  out.decoded.coefficients = out.fine;
  analyze(*out.decoded.hierarchy, out.decoded.coefficients);
  out.decoded.class_weights = std::vector<double>(5, 1.0);
  return out;
}

// Back faces (BackFaces::Cull): a culled face's finest polygons all face
// away from the eye (Newell normal against the direction from the eye to
// their centroid, computed here from the fine control mesh), most of the
// far side is culled, and without Cull nothing is culled for facing away.
TEST(View, CulledBackFacesFaceAwayAndOnlyThey) {
  const ViewCase c = sphere_case();
  const SubdivisionHierarchy& h = *c.decoded.hierarchy;
  const PolygonMesh mesh = h.control_mesh(2, c.fine);
  for (const Vec3 eye : {Vec3{0, 0, 20}, Vec3{14, -9, 3}}) {
    const Camera camera = camera_at(eye, {0, 0, 0}, 60);
    const ViewLevels refined = view_face_levels(c.decoded, c.fine, camera, 0.01);
    EXPECT_EQ(refined.back_facing, 0u);
    const ViewLevels v = view_face_levels(c.decoded, c.fine, camera, 0.01, BackFaces::Cull);
    // From 4 radii away 62.5% of the sphere faces away (cos = 1/4 at the
    // horizon); the cone test is conservative but catches most of it.
    EXPECT_GT(v.back_facing, v.levels.size() * 2 / 5);
    EXPECT_LE(v.back_facing, v.levels.size() * 5 / 8);
    for (std::size_t f = 0; f < h.base().face_count(); ++f) {
      std::vector<std::uint8_t> mine(c.fine.size(), 0);
      for_each_fine_point(h, f, [&](std::size_t p) { return (mine[p] = 1); });
      bool away = true;
      for (std::size_t q = 0; q < mesh.face_count(); ++q) {
        const std::uint32_t* corner = mesh.face_begin(q);
        const std::uint32_t n = mesh.face_size(q);
        if (!std::all_of(corner, corner + n, [&](std::uint32_t p) { return mine[p] != 0; })) continue;
        Vec3 normal{}, centroid{};
        for (std::uint32_t k = 0; k < n; ++k) {
          normal = normal + cross(mesh.positions[corner[k]], mesh.positions[corner[(k + 1) % n]]);
          centroid = centroid + mesh.positions[corner[k]] * (1.0 / n);
        }
        away = away && dot(normal, centroid - eye) > 0;
      }
      if (v.levels[f] == 0 && refined.levels[f] > 0) {
        EXPECT_TRUE(away) << "face " << f << " is culled but faces the eye";
      }
    }
  }
}

// The view case as a 2.2 file of small groups, in the test directory.
std::string write_view_file(const std::string& name) {
  const ViewCase& c = view_case();
  IswEncodeOptions encode;
  encode.step = 1e-4;
  encode.group_nodes = 2048;
  const std::string path = ::testing::TempDir() + name;
  write_isw(path, encode_isw(*c.surface.hierarchy, c.surface.coefficients, test::sample_metadata(), encode), true);
  return path;
}

// A view decode of a 2.2 file reads the groups its frustum needs: every face
// with a point in the image gets the level and the points of the whole
// file's decode, from fewer bytes.
TEST(View, AViewReadsTheGroupsItsFrustumNeedsAndMatchesTheWholeFileInView) {
  const std::string path = write_view_file("view.isw");
  const Camera camera = camera_at({5, 5, 5}, {5, 5, 0}, 40);
  IswDecodeOptions options;
  options.frustum = camera;
  const IswDecoded whole = read_isw(path), part = read_isw(path, options);
  EXPECT_LT(part.stream.groups_decoded, part.stream.groups / 2);
  EXPECT_LT(part.file_bytes_read, whole.file_bytes_read * 2 / 3);
  const auto fine_of = [](const IswDecoded& d) {
    std::vector<Vec3> fine = d.coefficients;
    synthesize(*d.hierarchy, fine);
    return fine;
  };
  const std::vector<Vec3> whole_fine = fine_of(whole), part_fine = fine_of(part);
  const ViewLevels a = view_face_levels(whole, whole_fine, camera, 0.5), b = view_face_levels(part, part_fine, camera, 0.5);
  std::size_t in_view = 0;
  for (std::size_t f = 0; f < a.levels.size(); ++f) {
    bool seen = false;
    for_each_fine_point(*whole.hierarchy, f, [&](std::size_t p) { return !(seen = in_image(camera, whole_fine[p])); });
    if (!seen) continue;
    ++in_view;
    EXPECT_EQ(b.levels[f], a.levels[f]) << f;
    for_each_fine_point(*whole.hierarchy, f, [&](std::size_t p) {
      EXPECT_LT(norm(part_fine[p] - whole_fine[p]), 1e-9) << p;
      return true;
    });
  }
  EXPECT_GT(in_view, 10u);
}

// One camera's mesh decoded over a patch (ViewScope::Patch, decode --view)
// is the whole hierarchy's: the same faces and levels, the same points in
// the frustum, from the groups its frustum needs and without the whole
// hierarchy; a ViewRefiner refuses such a decode.
TEST(View, AViewOverAPatchGivesTheWholeHierarchysMesh) {
  const std::string path = write_view_file("view_patch.isw");
  for (const Camera& camera : {camera_at({5, 5, 5}, {5, 5, 0}, 40), camera_at({2, 3, 1.5}, {6, 6, 0}, 60)}) {
    IswDecodeOptions options;
    options.frustum = camera;
    const IswDecoded whole = read_isw(path, options);
    options.view_scope = IswDecodeOptions::ViewScope::Patch;
    const IswDecoded part = read_isw(path, options);
    ASSERT_TRUE(part.patch);
    EXPECT_FALSE(part.hierarchy);
    EXPECT_EQ(part.stream.groups_decoded, whole.stream.groups_decoded);
    EXPECT_EQ(part.file_bytes_read, part.stream.offset + part.stream.decoded);
    for (const BackFaces back : {BackFaces::Refine, BackFaces::Cull}) {
      ViewLevels a, b;
      const PolygonMesh expected = view_mesh(whole, camera, 0.5, &a, back), mesh = view_mesh(part, camera, 0.5, &b, back);
      EXPECT_EQ(b.levels, a.levels);
      EXPECT_EQ(b.culled, a.culled);
      EXPECT_EQ(b.back_facing, a.back_facing);
      EXPECT_EQ(mesh.face_vertices, expected.face_vertices);
      ASSERT_EQ(mesh.positions.size(), expected.positions.size());
      std::size_t in_view = 0;
      for (std::size_t v = 0; v < mesh.positions.size(); ++v)
        if (!camera.box_outside(expected.positions[v], expected.positions[v])) {
          ++in_view;
          EXPECT_LT(norm(mesh.positions[v] - expected.positions[v]), 1e-9) << v;
        }
      EXPECT_GT(in_view, 100u);
    }
    EXPECT_THROW(ViewRefiner{part}, Error);
  }
  // A camera looking away from the surface: no group read, the base mesh.
  IswDecodeOptions away;
  away.frustum = camera_at({5, 5, 5}, {5, 5, 50}, 30);
  away.view_scope = IswDecodeOptions::ViewScope::Patch;
  const IswDecoded none = read_isw(path, away);
  EXPECT_EQ(none.stream.groups_decoded, 0u);
  ViewLevels levels;
  EXPECT_EQ(view_mesh(none, *away.frustum, 0.5, &levels).face_vertices, none.base.face_vertices);
  EXPECT_EQ(levels.culled, none.base.face_count());
}

// The interactive refiner: its patches make up the mesh, and after a camera
// move the faces it does not name keep their patches.
TEST(View, TheRefinerNamesEveryPatchAMoveChanges) {
  const ViewCase& c = view_case();
  ViewRefiner refiner(c.decoded);
  const auto patches = [&] {
    std::vector<std::vector<std::uint32_t>> out(refiner.levels().levels.size());
    for (std::size_t f = 0; f < out.size(); ++f) {
      std::vector<std::uint32_t> offsets;
      refiner.patch(f, offsets, out[f]);
      out[f].insert(out[f].end(), offsets.begin(), offsets.end());  // the corners, then the ends
    }
    return out;
  };
  const Camera first = camera_at({3, 3, 4}, {8, 8, 0}), second = camera_at({4, 3, 4}, {9, 9, 0});
  const std::vector<std::uint32_t> initial = refiner.set_view(first, 0.5);
  EXPECT_FALSE(initial.empty());
  // The patches, renumbered to the vertices they use, are mesh().
  const PolygonMesh mesh = refiner.mesh();
  PolygonMesh joined;
  joined.face_offsets = {0};
  for (std::size_t f = 0; f < refiner.levels().levels.size(); ++f) {
    std::vector<std::uint32_t> offsets, corners;
    refiner.patch(f, offsets, corners);
    std::uint32_t begin = 0;
    for (const std::uint32_t end : offsets) {
      joined.add_face(corners.data() + begin, end - begin);
      begin = end;
    }
  }
  std::vector<std::uint32_t> used(refiner.points().size(), UINT32_MAX);
  for (const std::uint32_t v : joined.face_vertices) used[v] = 0;
  for (std::uint32_t v = 0, next = 0; v < used.size(); ++v)
    if (used[v] == 0) {
      used[v] = next++;
      joined.positions.push_back(refiner.points()[v]);
    }
  for (std::uint32_t& v : joined.face_vertices) v = used[v];
  EXPECT_EQ(joined.face_offsets, mesh.face_offsets);
  EXPECT_EQ(joined.face_vertices, mesh.face_vertices);
  EXPECT_EQ(joined.positions, mesh.positions);
  // A move: the levels of view_face_levels(), and only the named patches differ.
  const auto before = patches();
  const std::vector<std::uint32_t> changed = refiner.set_view(second, 0.5);
  EXPECT_EQ(refiner.levels().levels, view_face_levels(c.decoded, c.fine, second, 0.5).levels);
  const auto after = patches();
  std::size_t differ = 0;
  for (std::size_t f = 0; f < after.size(); ++f) {
    const bool named = std::binary_search(changed.begin(), changed.end(), static_cast<std::uint32_t>(f));
    differ += after[f] != before[f];
    if (!named) {
      EXPECT_EQ(after[f], before[f]) << "face " << f << " changed unnamed";
    }
  }
  EXPECT_GT(differ, 0u);
  EXPECT_LT(changed.size(), after.size());
  EXPECT_TRUE(refiner.set_view(second, 0.5).empty());
}

TEST(View, TheMeshIsCrackFree) {
  const ViewCase& c = view_case();
  ViewLevels levels;
  const PolygonMesh mesh = view_mesh(c.decoded, camera_at({3, 3, 4}, {8, 8, 0}), 0.5, &levels);
  ASSERT_GT(std::count(levels.levels.begin(), levels.levels.end(), 0), 0);
  ASSERT_GT(std::count(levels.levels.begin(), levels.levels.end(), 3), 0);
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* v = mesh.face_begin(f);
    const std::size_t n = mesh.face_size(f);
    for (std::size_t k = 0; k < n; ++k) ++directed[{v[k], v[(k + 1) % n]}];
  }
  // Every directed edge once; a boundary edge (no reverse) only on the grid's border.
  std::size_t boundary = 0;
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    if (!directed.count({edge.second, edge.first})) {
      ++boundary;
      const Vec3 &a = mesh.positions[edge.first], &b = mesh.positions[edge.second];
      const auto on_border = [](const Vec3& p) { return p.x < 0.5 || p.y < 0.5 || p.x > 19.5 || p.y > 19.5; };
      EXPECT_TRUE(on_border(a) && on_border(b)) << edge.first << " " << edge.second;
    }
  }
  EXPECT_GT(boundary, 0u);
}

}  // namespace
}  // namespace isowave
