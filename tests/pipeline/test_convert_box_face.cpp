// convert_volume() on isosurfaces with specks on a box face: single samples
// of the face a little below the isovalue, surrounded by inside samples
// (the engine CT's z = 0 face has about a hundred). Each is a half droplet:
// a component less than a cell across whose boundary loop lies on the face.
// The base keeps it as one triangle; the fit used to shrink that loop to a
// point (the relaxation along it only shrinks it, and the attraction within
// the face does not restore it), so the decoded mesh had coincident vertices
// and faces with coincident corners.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "isowave/pipeline/convert.h"
#include "isowave/codec/statistics.h"
#include "isowave/extract/volume_io.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

struct DecodedMeshes {
  PolygonMesh base, fine;  // control meshes of levels 0 and L, as decoded
};

DecodedMeshes decode_all(const ConvertResult& result) {
  const IswDecoded decoded = decode_isw(result.bytes, "test");
  const std::vector<Vec3> points = reconstruct(decoded, decoded.ranked.size());
  return {decoded.base, decoded.hierarchy->control_mesh(decoded.hierarchy->levels(), points)};
}

// Edges (face sides) whose two ends have the same position.
std::size_t zero_length_edges(const PolygonMesh& mesh) {
  std::size_t count = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    const std::uint32_t size = mesh.face_size(f);
    for (std::uint32_t k = 0; k < size; ++k)
      count += mesh.positions[face[k]] == mesh.positions[face[(k + 1) % size]] ? 1 : 0;
  }
  return count;
}

// Faces with two corners at the same position.
std::size_t faces_with_coincident_corners(const PolygonMesh& mesh) {
  std::size_t count = 0;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    const std::uint32_t size = mesh.face_size(f);
    bool coincident = false;
    for (std::uint32_t a = 0; a < size; ++a)
      for (std::uint32_t b = a + 1; b < size; ++b) coincident |= mesh.positions[face[a]] == mesh.positions[face[b]];
    count += coincident ? 1 : 0;
  }
  return count;
}

// Vertices that share their position with another vertex.
std::size_t shared_positions(const PolygonMesh& mesh) {
  std::map<std::array<double, 3>, std::size_t> uses;
  for (const Vec3& p : mesh.positions) ++uses[{p.x, p.y, p.z}];
  std::size_t count = 0;
  for (const auto& [position, n] : uses) count += n > 1 ? n : 0;
  return count;
}

void expect_no_coincident_points(const ConvertResult& result) {
  const DecodedMeshes meshes = decode_all(result);
  EXPECT_EQ(zero_length_edges(meshes.base), 0u);
  EXPECT_EQ(faces_with_coincident_corners(meshes.base), 0u);
  EXPECT_EQ(faces_with_coincident_corners(meshes.fine), 0u);
  EXPECT_EQ(shared_positions(meshes.fine), 0u);
}

// Inside everywhere (105 on the face z = 0, 140 above it, as on the engine's
// face) but for a ball of lower values in the middle, and specks on the face:
// single samples at 99, 99.5 and 98, and a strip of three at 99; two face
// samples are exactly at the isovalue (inside, and no speck).
Volume speckled_face() {
  constexpr double kIso = 100;
  Volume volume = test::sampled_volume({24, 24, 10}, [](double x, double y, double z) {
    if (z > 0) return 140.0 - 80.0 * std::max(0.0, 1.0 - norm(Vec3{x - 12, y - 12, z - 5}) / 5.0);
    return 105.0;
  });
  const auto set = [&](std::size_t i, std::size_t j, double value) { volume.values[volume.index(i, j, 0)] = float(value); };
  set(4, 4, kIso - 1);
  set(19, 5, kIso - 0.5);
  set(5, 18, kIso - 2);
  for (std::size_t i = 15; i <= 17; ++i) set(i, 19, kIso - 1);
  set(9, 12, kIso);
  set(12, 3, kIso);
  return volume;
}

TEST(ConvertBoxFace, SpecksOnTheFaceDecodeWithoutCoincidentPoints) {
  const Volume volume = speckled_face();
  ConvertOptions options;
  options.prepare.extract.iso = 100;
  options.levels = 2;
  options.summary_percents = {100};
  const ConvertResult result = convert_volume(volume, "speckled face", options);
  ASSERT_GE(result.extraction.after.components, 5u);  // the ball and the specks
  expect_no_coincident_points(result);
}

// The engine CT (the volume the bug was found on): about 20 s.
TEST(ConvertBoxFace, EngineDecodesWithoutCoincidentPoints) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/engine_256x256x128.nrrd");
  ConvertOptions options;
  options.prepare.extract.iso = 100;
  options.summary_percents = {100};
  expect_no_coincident_points(convert_volume(read_volume(path), "engine", options));
}

}  // namespace
}  // namespace isowave
