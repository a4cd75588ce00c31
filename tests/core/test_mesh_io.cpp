// Mesh files: exact round trips, agreement with OpenMesh's readers on the real
// meshes, and hostile input (truncation at every byte, byte flips, bad counts
// and indices) that must give a clear error and never a crash.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include <csignal>
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "isowave/core/error.h"
#include "isowave/core/atomic_file.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh.h"
#include "isowave/core/mesh_io.h"
#include "support/test_meshes.h"

namespace isowave {
namespace {

namespace fs = std::filesystem;

class MeshIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = fs::temp_directory_path() / ("isowave_mesh_io_" + std::to_string(::getpid()) + "_" +
                                              ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }
  std::string path(const std::string& name) const { return (directory_ / name).string(); }
  void write_text(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
  }
  std::string read_bytes(const std::string& name) const {
    std::ifstream in(path(name), std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  fs::path directory_;
};

PolygonMesh sample_mesh() {
  PolygonMesh mesh = test::mixed_disk();
  mesh.sharp.assign(mesh.vertex_count(), 0);
  mesh.sharp[0] = mesh.sharp[7] = 1;
  mesh.positions[3] = {1.0 / 3.0, -2.5e-7, 12345.678901234567};
  return mesh;
}

void expect_same_topology(const PolygonMesh& a, const PolygonMesh& b) {
  EXPECT_EQ(a.face_offsets, b.face_offsets);
  EXPECT_EQ(a.face_vertices, b.face_vertices);
}

TEST_F(MeshIoTest, RoundTripsEveryFormat) {
  const PolygonMesh mesh = sample_mesh();
  for (const char* name : {"a.ply", "b.obj", "c.off"})
    for (bool ascii : {false, true})
      for (bool exact : {false, true}) {
        MeshWriteOptions options;
        options.ascii = ascii;
        options.double_precision = exact;
        write_mesh(path(name), mesh, options);
        const PolygonMesh back = read_mesh(path(name));
        SCOPED_TRACE(std::string(name) + (ascii ? " ascii" : " binary") + (exact ? " double" : " float"));
        expect_same_topology(mesh, back);
        ASSERT_EQ(back.vertex_count(), mesh.vertex_count());
        for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
          for (int k = 0; k < 3; ++k) {
            const double tolerance = exact ? 0.0 : 1e-7 * std::max(1.0, std::abs(mesh.positions[v][k]));
            EXPECT_NEAR(back.positions[v][k], mesh.positions[v][k], tolerance);
          }
        if (std::string(name) == "a.ply") {
          EXPECT_EQ(back.sharp, mesh.sharp);
        }
      }
}

TEST_F(MeshIoTest, WritesAtomicallyAndLeavesNoTemporaryFiles) {
  write_mesh(path("m.ply"), sample_mesh());
  write_mesh(path("m.ply"), test::cube());  // replaces
  EXPECT_EQ(read_mesh(path("m.ply")).vertex_count(), 8u);
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(directory_)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "m.ply");
  }
  EXPECT_EQ(files, 1u);
  EXPECT_THROW(write_mesh(path("missing_dir/m.ply"), test::cube()), Error);
  EXPECT_THROW(write_mesh(path("m.stl"), test::cube()), Error);
}

// Reads a file with OpenMesh and returns its faces as index lists rotated to
// start at the smallest index (OpenMesh may start a face elsewhere).
std::vector<std::vector<std::uint32_t>> canonical_faces(const PolygonMesh& mesh) {
  std::vector<std::vector<std::uint32_t>> faces;
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    std::vector<std::uint32_t> face(mesh.face_begin(f), mesh.face_begin(f) + mesh.face_size(f));
    std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
    faces.push_back(face);
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

TEST(MeshIoSharedData, AgreesWithOpenMeshOnRealMeshes) {
  for (const char* name : {"meshes/armadillo.off", "meshes/double_torus_quads.off", "meshes/rocker_arm_genus1.obj",
                           "meshes/elephant_106holes.off"}) {
    ISOWAVE_REQUIRE_SHARED_FILE(file, name);
    SCOPED_TRACE(name);
    const PolygonMesh ours = read_mesh(file);
    OpenMesh::PolyMesh_ArrayKernelT<> reference;
    ASSERT_TRUE(OpenMesh::IO::read_mesh(reference, file));
    ASSERT_EQ(ours.vertex_count(), reference.n_vertices());
    ASSERT_EQ(ours.face_count(), reference.n_faces());
    for (auto vh : reference.vertices()) {
      const auto p = reference.point(vh);
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(ours.positions[vh.idx()][k], p[k], 1e-6 * std::max(1.0, std::abs(double(p[k]))));
    }
    PolygonMesh reference_faces;
    for (auto fh : reference.faces()) {
      std::vector<std::uint32_t> face;
      for (auto vh : reference.fv_range(fh)) face.push_back(static_cast<std::uint32_t>(vh.idx()));
      reference_faces.add_face(face.data(), face.size());
    }
    EXPECT_EQ(canonical_faces(ours), canonical_faces(reference_faces));
  }
}

// Every prefix of a valid file, and random single-byte corruptions, must load
// as a valid mesh or raise isowave::Error; never crash or over-allocate.
void expect_hostile_input_is_safe(const std::string& file_path, const std::string& bytes) {
  const auto try_read = [&](const std::string& data) {
    std::ofstream(file_path, std::ios::binary | std::ios::trunc).write(data.data(), static_cast<std::streamsize>(data.size()));
    try {
      const PolygonMesh mesh = read_mesh(file_path);
      for (std::uint32_t v : mesh.face_vertices) ASSERT_LT(v, mesh.vertex_count());
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(file_path), std::string::npos) << error.what();
    }
  };
  for (std::size_t length = 0; length < bytes.size(); ++length) try_read(bytes.substr(0, length));
  std::mt19937 rng(7);
  for (int trial = 0; trial < 400; ++trial) {
    std::string corrupted = bytes;
    corrupted[rng() % corrupted.size()] = static_cast<char>(rng());
    try_read(corrupted);
  }
}

TEST_F(MeshIoTest, TruncatedAndCorruptedFilesFailCleanly) {
  const PolygonMesh mesh = sample_mesh();
  for (const char* name : {"t.ply", "t.obj", "t.off"})
    for (bool ascii : {false, true}) {
      MeshWriteOptions options;
      options.ascii = ascii;
      write_mesh(path(name), mesh, options);
      const std::string bytes = read_bytes(name);
      expect_hostile_input_is_safe(path(std::string("hostile_") + name), bytes);
    }
}

TEST_F(MeshIoTest, MalformedFilesNameTheProblem) {
  const auto error_of = [&](const std::string& name, const std::string& text) -> std::string {
    write_text(name, text);
    try {
      read_mesh(path(name));
    } catch (const Error& error) {
      return error.what();
    }
    return "no error";
  };
  const std::string ply_header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  EXPECT_NE(error_of("a.ply", ply_header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").find("out of range"), std::string::npos);
  EXPECT_NE(error_of("b.ply", ply_header + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").find("non-finite"), std::string::npos);
  EXPECT_NE(error_of("c.ply", ply_header + "0 0 0\n1 0 0\n").find("c.ply"), std::string::npos);
  EXPECT_NE(error_of("d.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                              "property float y\nproperty float z\nend_header\n")
                .find("more than the file can hold"),
            std::string::npos);
  EXPECT_NE(error_of("e.ply", ply_header + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n").find("at least 3"), std::string::npos);
  EXPECT_NE(error_of("f.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n").find("references vertex 5"),
            std::string::npos);
  EXPECT_NE(error_of("g.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").find("truncated"), std::string::npos);
  EXPECT_NE(error_of("h.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n").find("line 4"), std::string::npos);
  EXPECT_NE(error_of("i.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").find("out of range"), std::string::npos);
  EXPECT_NE(error_of("j.off", "PLY\n").find("not an OFF file"), std::string::npos);
  try {
    read_mesh(path("does_not_exist.ply"));
    ADD_FAILURE() << "no error for a missing file";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::Io);
  }
}

TEST_F(MeshIoTest, ReadsObjVariants) {
  // Slashes, negative indices and unrelated lines.
  write_text("v.obj", "# comment\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvn 0 0 1\nv 0 1 0\n"
                      "f 1/1/1 2//1 3/2\nf -4 -2 -1\n");
  const PolygonMesh mesh = read_mesh(path("v.obj"));
  ASSERT_EQ(mesh.face_count(), 2u);
  EXPECT_EQ(std::vector<std::uint32_t>(mesh.face_begin(1), mesh.face_begin(1) + 3), (std::vector<std::uint32_t>{0, 2, 3}));
}

}  // namespace
}  // namespace isowave

namespace isowave {
namespace {

TEST_F(MeshIoTest, InterruptedWritersLeaveNothingBehind) {
  // What the signal handler of the isowave command does on SIGINT/SIGTERM.
  {
    AtomicFileWriter writer(path("out.isw"));
    writer.write("partial data");
    remove_uncommitted_temporary_files();
    std::size_t files = 0;
    for (const auto& entry : fs::directory_iterator(directory_)) files += entry.path().empty() ? 0 : 1;
    EXPECT_EQ(files, 0u);
  }
  EXPECT_FALSE(fs::exists(path("out.isw")));
  // A committed file is not touched.
  AtomicFileWriter done(path("done.isw"));
  done.write("complete");
  done.commit();
  remove_uncommitted_temporary_files();
  EXPECT_TRUE(fs::exists(path("done.isw")));
  // An existing file is kept when the writer may not overwrite it.
  AtomicFileWriter refused(path("done.isw"), false);
  refused.write("other");
  EXPECT_THROW(refused.commit(), Error);
  EXPECT_EQ(read_bytes("done.isw"), "complete");
}

// A process killed outright (SIGKILL: no handler runs) in the middle of a
// write leaves neither the output nor a temporary file, where the file
// system gives unnamed files (O_TMPFILE; otherwise the writer falls back to a
// named temporary, which only SIGINT and SIGTERM clean up).
TEST_F(MeshIoTest, KilledWriterLeavesNothingBehind) {
  const int probe = open(directory_.c_str(), O_TMPFILE | O_WRONLY, 0600);
  if (probe < 0 || access("/proc/self/fd", X_OK) != 0) GTEST_SKIP() << "no O_TMPFILE here";
  close(probe);
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    AtomicFileWriter writer(path("killed.isw"));
    writer.write(std::string(1 << 20, 'x'));
    (void)!write(ready[1], "w", 1);
    pause();
    std::_Exit(1);
  }
  char byte = 0;
  ASSERT_EQ(read(ready[0], &byte, 1), 1);
  kill(child, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  close(ready[0]);
  close(ready[1]);
  for (const auto& entry : fs::directory_iterator(directory_)) ADD_FAILURE() << "left " << entry.path();
  // The same writer, committed, makes the file (and only it), replacing an
  // older one or, when it may not overwrite, refusing without a trace.
  std::ofstream(path("killed.isw")) << "old";
  AtomicFileWriter writer(path("killed.isw"));
  writer.write("new");
  writer.commit();
  AtomicFileWriter refused(path("killed.isw"), false);
  refused.write("other");
  EXPECT_THROW(refused.commit(), Error);
  EXPECT_EQ(read_bytes("killed.isw"), "new");
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(directory_)) ++files;
  EXPECT_EQ(files, 1u);
}

// A small surface far from the origin (georeferenced grids) or at float's
// range limits is written in double, in every format, and reads back as it
// was; an ordinary mesh stays float.
TEST_F(MeshIoTest, CoordinatesFloatWouldLoseAreWrittenAsDouble) {
  const PolygonMesh grid = test::quad_grid(5, 4);
  const std::pair<double, Vec3> cases[] = {
      {1.0, {0, 0, 0}}, {1.0, {500000, 4000000, 0}}, {1e-300, {0, 0, 0}}, {1e300, {0, 0, 0}}};
  for (const auto& [scale, offset] : cases) {
    PolygonMesh mesh = grid;
    for (Vec3& p : mesh.positions) p = scale * (0.01 * p + Vec3{0.001, 0.002, 0.003}) + offset;
    const bool far = offset.y != 0 || scale != 1.0;
    EXPECT_EQ(float_loses_geometry(mesh), far) << scale << " " << offset.y;
    for (const char* name : {"m.ply", "m.obj", "m.off"}) {
      for (const bool ascii : {false, true}) {
        MeshWriteOptions options;
        options.ascii = ascii;
        write_mesh(path(name), mesh, options);
        const PolygonMesh back = read_mesh(path(name));
        ASSERT_EQ(back.vertex_count(), mesh.vertex_count());
        for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
          for (int k = 0; k < 3; ++k)
            ASSERT_NEAR(back.positions[v][k], mesh.positions[v][k], far ? 1e-12 * std::abs(mesh.positions[v][k]) : 1e-6)
                << name << " scale " << scale << " offset " << offset.y;
      }
      std::remove(path(name).c_str());
    }
  }
}

// Replacing a file keeps what the user set on it: its permissions, and a
// symbolic link in its place (the file the link names gets the new data).
TEST_F(MeshIoTest, ReplacedFilesKeepPermissionsAndSymbolicLinks) {
  std::ofstream(path("private.isw")) << "old";
  ASSERT_EQ(chmod(path("private.isw").c_str(), 0600), 0);
  AtomicFileWriter writer(path("private.isw"));
  writer.write("new");
  writer.commit();
  EXPECT_EQ(read_bytes("private.isw"), "new");
  EXPECT_EQ(fs::status(path("private.isw")).permissions() & fs::perms::all, fs::perms::owner_read | fs::perms::owner_write);
  fs::create_symlink(path("private.isw"), path("link.isw"));
  AtomicFileWriter through_link(path("link.isw"));
  through_link.write("newer");
  through_link.commit();
  EXPECT_TRUE(fs::is_symlink(path("link.isw")));
  EXPECT_EQ(read_bytes("private.isw"), "newer");
}

// The binary PLY layout byte by byte: header, little-endian float32 x y z
// and the uchar sharp flag per vertex, then per face a uchar count and int32
// indices.
TEST_F(MeshIoTest, BinaryPlyBytesFollowTheFormatExactly) {
  PolygonMesh mesh;
  mesh.positions = {{0, 1, 2}, {0.5, -1.25, 3}, {1e10, -0.0, 7}, {4, 5, 6}};
  mesh.sharp = {0, 1, 0, 0};
  mesh.add_face({0, 1, 2});
  mesh.add_face({0, 2, 3, 1});
  write_mesh(path("exact.ply"), mesh);
  std::string expected =
      "ply\nformat binary_little_endian 1.0\ncomment written by isowave\nelement vertex 4\n"
      "property float x\nproperty float y\nproperty float z\nproperty uchar sharp\nelement face 2\n"
      "property list uchar int vertex_indices\nend_header\n";
  const auto append = [&](const auto& value) { expected.append(reinterpret_cast<const char*>(&value), sizeof value); };
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    for (int k = 0; k < 3; ++k) append(static_cast<float>(mesh.positions[v][k]));
    append(static_cast<std::uint8_t>(mesh.sharp[v]));
  }
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    append(static_cast<std::uint8_t>(mesh.face_size(f)));
    for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) append(static_cast<std::int32_t>(mesh.face_begin(f)[k]));
  }
  EXPECT_EQ(read_bytes("exact.ply"), expected);
}

// More vertices and faces than one block of the parallel writer (and more
// bytes than the writer hands to disk at once): every block lands in order.
TEST_F(MeshIoTest, LargeBinaryPlyRoundTripsAcrossWriterBlocks) {
  PolygonMesh mesh = test::quad_grid(700, 400);
  ASSERT_GT(mesh.vertex_count(), std::size_t{1} << 18);
  ASSERT_GT(mesh.face_count(), std::size_t{1} << 17);
  mesh.face_vertices.push_back(5);  // one pentagon among the quads shifts the later face records
  mesh.face_offsets.back() += 1;
  for (MeshWriteOptions options : {MeshWriteOptions{false, false}, MeshWriteOptions{false, true}}) {
    write_mesh(path("large.ply"), mesh, options);
    const PolygonMesh back = read_mesh(path("large.ply"));
    expect_same_topology(mesh, back);
    ASSERT_EQ(back.vertex_count(), mesh.vertex_count());
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
      ASSERT_EQ(back.positions[v], mesh.positions[v]) << v;  // grid coordinates are exact in float
  }
}

TEST_F(MeshIoTest, LargeAtomicWritesArriveWhole) {
  std::string data(40u << 20, '\0');
  std::mt19937 rng(5);
  for (char& c : data) c = static_cast<char>(rng());
  AtomicFileWriter writer(path("big.bin"));
  for (std::size_t offset = 0; offset < data.size(); offset += 3u << 20)
    writer.write(data.data() + offset, std::min<std::size_t>(3u << 20, data.size() - offset));
  writer.commit();
  EXPECT_TRUE(read_bytes("big.bin") == data);
}

// A write that fails part way (here: the file size limit, as a full disk
// would) throws and leaves the user's existing file as it was, also when the
// failure is transient (the limit is lifted right after the 16 MiB point,
// where the writer flushes to start writeback). In a child process, so that
// the limit does not reach the rest of the test run.
TEST_F(MeshIoTest, FailedLargeWriteKeepsTheExistingFile) {
  std::ofstream(path("keep.bin"), std::ios::binary) << "the user's data";
  constexpr int kBlocksTo16MiB = 16 * 1024;
  for (const bool transient : {false, true}) {
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      std::signal(SIGXFSZ, SIG_IGN);
      rlimit size_limit{(rlim_t{16} << 20) - 10240, RLIM_INFINITY};
      setrlimit(RLIMIT_FSIZE, &size_limit);
      const std::string block(1024, 'x');
      try {
        AtomicFileWriter writer(path("keep.bin"));
        for (int k = 0; k < 40 * 1024; ++k) {
          writer.write(block.data(), block.size());
          if (transient && k + 1 == kBlocksTo16MiB) {
            size_limit.rlim_cur = RLIM_INFINITY;
            setrlimit(RLIMIT_FSIZE, &size_limit);
          }
        }
        writer.commit();
      } catch (const Error&) {
        std::_Exit(0);
      }
      std::_Exit(1);
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << (transient ? "transient" : "lasting") << " failure not reported";
    EXPECT_EQ(read_bytes("keep.bin"), "the user's data");
  }
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(directory_)) ++files;
  EXPECT_EQ(files, 1u) << "a temporary file was left behind";
}

// Validation runs in parallel but names the first offender, as a scan would.
TEST(ValidateIndices, NamesTheFirstOffenderOfALargeMesh) {
  PolygonMesh mesh = test::quad_grid(500, 400);
  const auto message = [&] {
    try {
      validate_indices(mesh, "grid");
    } catch (const Error& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(), "no error");
  mesh.face_vertices[700000] = 9000000;
  mesh.face_vertices[300001] = 8000000;
  EXPECT_NE(message().find("index 8000000 is out of range"), std::string::npos) << message();
  mesh.face_vertices[700000] = mesh.face_vertices[300001] = 0;
  mesh.positions[150000].y = std::nan("");
  mesh.positions[90000].x = std::numeric_limits<double>::infinity();
  EXPECT_NE(message().find("vertex 90000 has a non-finite"), std::string::npos) << message();
}

TEST(HugePages, FreshReserveGivesAnEmptyVectorWithRoom) {
  std::vector<double> values{1, 2, 3};
  reserve_fresh_on_huge_pages(values, 3u << 20);
  EXPECT_TRUE(values.empty());
  EXPECT_GE(values.capacity(), 3u << 20);
  const double* data = values.data();
  values.assign(3u << 20, 2.5);
  EXPECT_EQ(values.data(), data);  // no reallocation
  reserve_fresh_on_huge_pages(values, 1000);  // room enough: keeps the buffer
  EXPECT_TRUE(values.empty());
  EXPECT_EQ(values.data(), data);
}


// List counts and indices stored as floats are range-checked before any
// integer cast: NaN, 1e30 and fractions are malformed, never undefined
// behaviour (UBSan's float-cast-overflow in the sanitizer build) nor, as a
// NaN-long list in the vertex element was, silently accepted.
TEST_F(MeshIoTest, FloatListCountsAndIndicesOutOfRangeAreMalformed) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto ply = [](const std::string& vertex_list, const std::string& face_list) {
    return "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           "property float z\n" + vertex_list + "element face 1\n" + face_list + "end_header\n";
  };
  const auto bytes = [](std::initializer_list<float> values) {
    std::string out;
    for (const float v : values) out.append(reinterpret_cast<const char*>(&v), sizeof v);
    return out;
  };
  const std::string points = bytes({0, 0, 0}) + bytes({1, 0, 0}) + bytes({0, 1, 0});
  const std::string float_faces = "property list float float vertex_indices\n";
  // A face's count or index: NaN, huge, fractional.
  for (const float count : {nan, 1e30f, 2.5f}) {
    SCOPED_TRACE(count);
    write_text("count.ply", ply("", float_faces) + points + bytes({count, 0, 1, 2}));
    EXPECT_THROW(read_mesh(path("count.ply")), Error);
  }
  for (const float index : {nan, 1e30f, -1.0f, 0.5f}) {
    SCOPED_TRACE(index);
    write_text("index.ply", ply("", float_faces) + points + bytes({3, 0, 1, index}));
    EXPECT_THROW(read_mesh(path("index.ply")), Error);
  }
  // A list in the vertex element, and one in another element, of NaN length.
  std::string with_vertex_list = ply("property list float float extra\n", float_faces);
  std::string body;
  for (int v = 0; v < 3; ++v) body += bytes({float(v), 0, 0, nan});
  write_text("vertex_list.ply", with_vertex_list + body + bytes({3, 0, 1, 2}));
  EXPECT_THROW(read_mesh(path("vertex_list.ply")), Error);
  const std::string other = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                            "property float y\nproperty float z\nelement face 1\n"
                            "property list uchar int vertex_indices\nelement extra 1\n"
                            "property list float float values\nend_header\n";
  std::string face(1, char(3));
  for (const std::int32_t i : {0, 1, 2}) face.append(reinterpret_cast<const char*>(&i), 4);
  write_text("other.ply", other + points + face + bytes({nan}));
  EXPECT_THROW(read_mesh(path("other.ply")), Error);
  // The same files with valid numbers read (the test's own layout is right).
  write_text("valid.ply", ply("", float_faces) + points + bytes({3, 0, 1, 2}));
  EXPECT_EQ(read_mesh(path("valid.ply")).face_count(), 1u);
}

}  // namespace
}  // namespace isowave
