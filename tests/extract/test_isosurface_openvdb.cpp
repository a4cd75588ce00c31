// Isosurface extraction against an independent implementation (OpenVDB's
// tools::volumeToMesh, a dual method with one vertex per voxel) and the
// manifold contract on every shared volume at its README isovalue (these
// tests skip when ../shared/data is absent).
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "isosurface_checks.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

// Area of the convex polygon `polygon` clipped to the box [low, high]
// (Sutherland-Hodgman against the six planes).
double clipped_area(std::vector<openvdb::Vec3d> polygon, const openvdb::Vec3d& low, const openvdb::Vec3d& high) {
  for (int axis = 0; axis < 3 && !polygon.empty(); ++axis)
    for (int side = 0; side < 2 && !polygon.empty(); ++side) {
      // Keep points with sign * (p[axis] - bound) <= 0.
      const double bound = side ? high[axis] : low[axis];
      const double sign = side ? 1.0 : -1.0;
      std::vector<openvdb::Vec3d> kept;
      for (std::size_t i = 0; i < polygon.size(); ++i) {
        const openvdb::Vec3d& a = polygon[i];
        const openvdb::Vec3d& b = polygon[(i + 1) % polygon.size()];
        const double da = sign * (a[axis] - bound), db = sign * (b[axis] - bound);
        if (da <= 0) kept.push_back(a);
        if ((da < 0 && db > 0) || (da > 0 && db < 0)) kept.push_back(a + (b - a) * (da / (da - db)));
      }
      polygon = std::move(kept);
    }
  double area = 0;
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i)
    area += 0.5 * (polygon[i] - polygon[0]).cross(polygon[i + 1] - polygon[0]).length();
  return area;
}

// Area of OpenVDB's mesh of the same samples inside the same volume box.
// OpenVDB treats values below the isovalue as inside (the surface, and its
// area, is the same). Outside the dense copy every voxel has the background
// value, so OpenVDB would close the surface with caps where it meets the box;
// instead the samples are padded by one layer of copies of the face samples
// (the surface continues straight across the box face) and the polygons are
// clipped to the box.
double openvdb_area(const Volume& volume, double iso) {
  openvdb::initialize();
  const int nx = int(volume.dims[0]), ny = int(volume.dims[1]), nz = int(volume.dims[2]);
  std::vector<float> padded(std::size_t(nx + 2) * std::size_t(ny + 2) * std::size_t(nz + 2));
  for (int k = -1; k <= nz; ++k)
    for (int j = -1; j <= ny; ++j)
      for (int i = -1; i <= nx; ++i)
        padded[std::size_t(i + 1) +
               std::size_t(nx + 2) * (std::size_t(j + 1) + std::size_t(ny + 2) * std::size_t(k + 1))] =
            volume.at(std::size_t(std::clamp(i, 0, nx - 1)), std::size_t(std::clamp(j, 0, ny - 1)),
                      std::size_t(std::clamp(k, 0, nz - 1)));
  const openvdb::CoordBBox box(openvdb::Coord(-1, -1, -1), openvdb::Coord(nx, ny, nz));
  openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, padded.data());
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
  openvdb::tools::copyFromDense(dense, *grid, 0.0f);
  openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(1.0);
  transform->postScale(openvdb::Vec3d(volume.spacing.x, volume.spacing.y, volume.spacing.z));
  transform->postTranslate(openvdb::Vec3d(volume.origin.x, volume.origin.y, volume.origin.z));
  grid->setTransform(transform);
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grid, points, triangles, quads, iso, 0.0);

  const openvdb::Vec3d low(volume.origin.x, volume.origin.y, volume.origin.z);
  const openvdb::Vec3d high(volume.origin.x + volume.spacing.x * (nx - 1),
                            volume.origin.y + volume.spacing.y * (ny - 1),
                            volume.origin.z + volume.spacing.z * (nz - 1));
  const auto point = [&](unsigned index) { return openvdb::Vec3d(points[index]); };
  double area = 0;
  for (const openvdb::Vec3I& t : triangles) area += clipped_area({point(t[0]), point(t[1]), point(t[2])}, low, high);
  // Quads as two triangles (they need not be planar, so not clipped whole).
  for (const openvdb::Vec4I& q : quads) {
    area += clipped_area({point(q[0]), point(q[1]), point(q[2])}, low, high);
    area += clipped_area({point(q[0]), point(q[2]), point(q[3])}, low, high);
  }
  return area;
}

TEST(IsosurfaceOpenVdb, ClosedBuiltinSurfacesHaveTheSameArea) {
  for (const char* name : {"sphere", "torus", "genus3"}) {
    const Volume volume = make_builtin_field(name, 96);
    const PolygonMesh mesh = contour_volume(volume, 0.0);
    EXPECT_NEAR(surface_area(mesh) / openvdb_area(volume, 0.0), 1.0, 0.02) << name;
  }
}

struct SharedVolume {
  const char* file;
  double iso;
  VolumeReadOptions options;
};

std::vector<SharedVolume> shared_volumes() {
  VolumeReadOptions neghip;
  neghip.dims = {{66, 66, 66}};
  neghip.type = ScalarType::UInt8;
  VolumeReadOptions skull;
  skull.dims = {{64, 64, 64}};
  skull.type = ScalarType::Float32;
  return {{"volumes/miranda_256x256x256.nrrd", 1.5, {}},
          {"volumes/hcci_oh_187x187x187.nrrd", 0.0003, {}},
          {"volumes/csafe_heptane_151x151x151.nrrd", 50, {}},
          {"volumes/engine_256x256x128.nrrd", 100, {}},
          {"volumes/aneurism_256x256x256.nrrd", 100, {}},
          {"volumes/embryo_256x256x256.nrrd", 50, {}},
          {"volumes/mri_head_256x256x256.nrrd", 30, {}},
          {"volumes/stent_128x128x256.nrrd", 300, {}},
          {"volumes/neghip_66x66x66_uint8.raw", 64, neghip},
          {"volumes/skull_64x64x64_float32.raw", 2.9, skull},
          {"volumes/ironProt.vtk", 128, {}},
          {"volumes/carotid.vtk", 200, {}},
          {"volumes/hydrogen.vti", 0.05, {}},
          {"volumes/viscousfingers_050.vti", 30, {}},
          {"volumes/viscousfingers_099.vti", 30, {}},
          {"volumes/isabel_30.vti", 30, {}}};
}

// Where the surface is smooth at the voxel scale the two methods agree
// closely. On noisy scans (embryo, stent, miranda, ...) marching cubes gives
// 5-15% more area than OpenVDB's dual mesh: a blob around one inside sample
// is an octahedron with vertices on the six crossed edges (area 6.9 t^2 for
// crossings at distance t) in marching cubes but a cube through the cells'
// averaged crossing points (area 2.7 t^2) in OpenVDB, so those volumes are
// not compared.
TEST(IsosurfaceOpenVdb, SharedVolumesHaveTheSameAreaAsOpenVdb) {
  int compared = 0;
  for (const SharedVolume& shared : shared_volumes()) {
    const std::string name = shared.file;
    if (name != "volumes/hydrogen.vti" && name != "volumes/skull_64x64x64_float32.raw" &&
        name != "volumes/engine_256x256x128.nrrd" && name != "volumes/viscousfingers_050.vti" &&
        name != "volumes/viscousfingers_099.vti")
      continue;
    const std::string path = test::shared_data_file(shared.file);
    if (path.empty()) GTEST_SKIP() << "shared data file " << shared.file << " not found (../shared/data absent)";
    const Volume volume = read_volume(path, shared.options);
    const double area = surface_area(contour_volume(volume, shared.iso));
    EXPECT_NEAR(area / openvdb_area(volume, shared.iso), 1.0, 0.02) << shared.file;
    ++compared;
  }
  EXPECT_EQ(compared, 5);
}

// Every shared volume at its README isovalue: a consistently oriented
// 2-manifold with its boundary on the box, normals toward lower values.
TEST(IsosurfaceShared, EveryVolumeGivesAnOrientedManifold) {
  for (const SharedVolume& shared : shared_volumes()) {
    SCOPED_TRACE(shared.file);
    const std::string path = test::shared_data_file(shared.file);
    if (path.empty()) GTEST_SKIP() << "shared data file " << shared.file << " not found (../shared/data absent)";
    const Volume volume = read_volume(path, shared.options);
    const PolygonMesh mesh = contour_volume(volume, shared.iso);
    ASSERT_GT(mesh.face_count(), 1000u);
    ASSERT_NO_THROW(require_manifold(mesh, shared.file));
    test::expect_boundary_on_box(volume, mesh, shared.file);
    EXPECT_GT(test::fraction_toward_lower(volume, mesh), 0.99);
  }
}

}  // namespace
}  // namespace isowave
