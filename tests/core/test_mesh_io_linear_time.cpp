// The text mesh readers run in time linear in the file: see
// support/linear_time.h.
#include <string>

#include <gtest/gtest.h>

#include "isowave/core/mesh_io.h"
#include "support/linear_time.h"

namespace isowave {
namespace {

// `corners` indices cycling over vertices 1, 2, 3 (1-based), space-separated.
std::string cycling_indices(std::size_t bytes, const char* const (&forms)[3], std::size_t& corners) {
  std::string out;
  for (corners = 0; out.size() < bytes; ++corners) out += std::string(" ") + forms[corners % 3];
  return out;
}

// An OBJ file of comments and unknown lines (half the bytes), then one face
// line holding the other half: corners cycling over three vertices, as
// v/vt/vn, v//vn and negative indices.
TEST(MeshReaderLinearTime, ObjLongFaceLine) {
  std::size_t corners = 0;
  test::expect_linear_time(".obj", [&](std::size_t bytes) {
    std::string text;
    for (std::size_t k = 0; text.size() < bytes / 2; ++k) text += "# comment " + std::to_string(k) + "\nvt 0 0\n";
    text += "v 0 0 0\nv 1 0 0\nv 0 1 0\nf";
    static const char* const kForms[3] = {"1/1/1", "2//1", "-1"};
    return text + cycling_indices(bytes / 2, kForms, corners) + "\n";
  }, [&](const std::string& path) {
    const PolygonMesh mesh = read_mesh(path);
    EXPECT_EQ(mesh.vertex_count(), 3u);
    ASSERT_EQ(mesh.face_count(), 1u);
    EXPECT_EQ(mesh.face_size(0), corners);
  });
}

// An ASCII PLY file whose header is half comments and properties of an
// extra element, and whose body is that element's values and one face with a
// list of the remaining bytes' worth of indices.
TEST(MeshReaderLinearTime, AsciiPlyLongHeaderAndList) {
  std::size_t corners = 0;
  test::expect_linear_time(".ply", [&](std::size_t bytes) {
    std::string header = "ply\nformat ascii 1.0\nelement extra 1\n";
    std::string extra;
    for (std::size_t k = 0; header.size() < bytes / 4; ++k) {
      header += "comment " + std::to_string(k) + "\nproperty float p" + std::to_string(k) + "\n";
      extra += "1 ";
    }
    header += "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
              "element face 1\nproperty list uint int vertex_indices\nend_header\n";
    static const char* const kForms[3] = {"0", "1", "2"};
    const std::string list = cycling_indices(bytes / 2, kForms, corners);
    return header + extra + "\n0 0 0\n1 0 0\n0 1 0\n" + std::to_string(corners) + list + "\n";
  }, [&](const std::string& path) {
    const PolygonMesh mesh = read_mesh(path);
    EXPECT_EQ(mesh.vertex_count(), 3u);
    ASSERT_EQ(mesh.face_count(), 1u);
    EXPECT_EQ(mesh.face_size(0), corners);
  });
}

}  // namespace
}  // namespace isowave
