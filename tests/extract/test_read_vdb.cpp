// The OpenVDB reader: float and double grids, every compression, malformed
// inputs (each an Error naming the file), and truncation / byte-flip sweeps.
#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/extract/volume_io.h"
#include "volume_io_test_support.h"

namespace isowave {
namespace {

using namespace volume_io_test;

// VDB

void init_vdb() {
  static bool done = false;
  if (!done) openvdb::initialize();
  done = true;
}

openvdb::math::Transform::Ptr scale_translate() {
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  m.setToScale(openvdb::Vec3d(0.5, 0.25, 2));
  m.setTranslation(openvdb::Vec3d(1, 2, 3));
  return openvdb::math::Transform::createLinearTransform(m);
}

// A float grid with voxels in [2,6]x[-3,1]x[10,13] (one of them inactive), an
// active 8^3 tile, plus a vec3 grid written first and a double grid.
struct VdbFixture {
  std::vector<float> expected_float;  // dense over the active bbox
  std::vector<float> expected_double;
  std::array<std::size_t, 3> dims_float{}, dims_double{};
  Vec3 origin_float, origin_double;
};

VdbFixture write_vdb(const std::string& path) {
  init_vdb();
  VdbFixture f;
  auto vectors = openvdb::Vec3SGrid::create();
  vectors->setName("velocity");
  vectors->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));

  auto grid = openvdb::FloatGrid::create(-7.5f);
  grid->setName("density");
  grid->setTransform(scale_translate());
  auto acc = grid->getAccessor();
  std::mt19937 rng(5);
  std::normal_distribution<float> dist(0, 10);
  for (int z = 10; z <= 13; ++z)
    for (int y = -3; y <= 1; ++y)
      for (int x = 2; x <= 6; ++x) acc.setValue(openvdb::Coord(x, y, z), dist(rng));
  acc.setValueOff(openvdb::Coord(4, -1, 11), 99.0f);  // inactive: reads as the background
  grid->tree().addTile(1, openvdb::Coord(8, 0, 8), 42.0f, true);  // 8^3 active tile at [8,15]x[0,7]x[8,15]

  // Expected dense over [2,15]x[-3,7]x[8,15].
  const openvdb::Coord lo(2, -3, 8), hi(15, 7, 15);
  f.dims_float = {14, 11, 8};
  const openvdb::Vec3d o = scale_translate()->indexToWorld(lo);
  f.origin_float = {o.x(), o.y(), o.z()};
  auto probe = grid->getConstAccessor();
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const openvdb::Coord c(x, y, z);
        f.expected_float.push_back(probe.isValueOn(c) ? probe.getValue(c) : -7.5f);
      }

  auto dgrid = openvdb::DoubleGrid::create(0.25);
  dgrid->setName("pressure");
  dgrid->setTransform(openvdb::math::Transform::createLinearTransform(2.0));
  auto dacc = dgrid->getAccessor();
  f.dims_double = {3, 2, 2};
  f.origin_double = {-2, 0, 2};
  for (int z = 1; z <= 2; ++z)
    for (int y = 0; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x) {
        const double v = 0.1 * x + 1e-3 * y + 10 * z;
        dacc.setValue(openvdb::Coord(x, y, z), v);
        f.expected_double.push_back(static_cast<float>(v));
      }
  openvdb::GridPtrVec grids{vectors, grid, dgrid};
  openvdb::io::File(path).write(grids);
  return f;
}

TEST(VolumeIo, VdbFloatAndDoubleGrids) {
  TempDir dir;
  const std::string path = dir.file("grids.vdb");
  const VdbFixture f = write_vdb(path);

  const Volume v = read_volume(path);  // default: the first float/double grid
  expect_geometry(v, f.dims_float, {0.5, 0.25, 2}, f.origin_float, "density");
  EXPECT_EQ(v.source_type, ScalarType::Float32);
  expect_values(v, f.expected_float, "density");
  // The inactive voxel (4,-1,11) holds 99 in the tree but reads as the background.
  EXPECT_EQ(v.at(4 - 2, -1 + 3, 11 - 8), -7.5f);
  EXPECT_EQ(v.at(8 - 2, 0 + 3, 8 - 8), 42.0f);

  VolumeReadOptions options;
  options.grid = "pressure";
  const Volume d = read_volume(path, options);
  expect_geometry(d, f.dims_double, {2, 2, 2}, f.origin_double, "pressure");
  EXPECT_EQ(d.source_type, ScalarType::Float64);
  expect_values(d, f.expected_double, "pressure");

  options.grid = "velocity";
  expect_error(path, options, "velocity", "vec3 grid");
  options.grid = "nope";
  expect_error(path, options, "missing grid 'nope'", "missing grid");
}

// Every compression setting, half floats, the inactive-value encodings and an
// instanced grid, against OpenVDB's own reader of the same file.
template <typename GridT>
typename GridT::Ptr varied_grid(bool half) {
  using V = typename GridT::ValueType;
  auto grid = GridT::create(V(2));
  grid->setSaveFloatAsHalf(half);
  grid->setTransform(scale_translate());
  auto acc = grid->getAccessor();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> dist(-5, 5);
  // Leaf A: inactive values background and -background (mask, no stored inactive values).
  for (int i = 0; i < 40; ++i) acc.setValue(openvdb::Coord(i % 8, (i / 8) % 8, 0), V(dist(rng)));
  acc.setValueOff(openvdb::Coord(1, 7, 3), V(-2));
  // Leaf B: two other inactive values (mask and two inactive values).
  for (int i = 0; i < 30; ++i) acc.setValue(openvdb::Coord(8 + i % 8, i / 8, 1), V(dist(rng)));
  acc.setValueOff(openvdb::Coord(9, 5, 5), V(0.75));
  acc.setValueOff(openvdb::Coord(10, 5, 5), V(-1.5));
  // Leaf C: many distinct inactive values (no mask compression possible).
  for (int i = 0; i < 20; ++i) acc.setValue(openvdb::Coord(16 + i % 8, i / 8, 2), V(dist(rng)));
  for (int i = 0; i < 6; ++i) acc.setValueOff(openvdb::Coord(16 + i, 7, 7), V(10 + i));
  // Leaf D: one inactive value (no mask, one inactive value).
  for (int i = 0; i < 10; ++i) acc.setValue(openvdb::Coord(-8 + i % 8, -8 + i / 8, -8), V(dist(rng)));
  acc.setValueOff(openvdb::Coord(-7, -2, -5), V(3.25));
  // An active tile at the first internal level and one at the second.
  grid->tree().addTile(1, openvdb::Coord(24, 0, 0), V(7), true);
  grid->tree().addTile(2, openvdb::Coord(128, 0, 0), V(-3), true);
  return grid;
}

template <typename GridT>
std::vector<float> reference_dense(const std::string& path, const std::string& name, const Volume& shape) {
  openvdb::io::File file(path);
  file.open(false);
  auto grid = openvdb::gridPtrCast<GridT>(file.readGrid(name));
  file.close();
  const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
  EXPECT_EQ(shape.dims, (std::array<std::size_t, 3>{std::size_t(box.dim().x()), std::size_t(box.dim().y()),
                                                    std::size_t(box.dim().z())}));
  std::vector<float> out;
  auto acc = grid->getConstAccessor();
  for (int z = box.min().z(); z <= box.max().z(); ++z)
    for (int y = box.min().y(); y <= box.max().y(); ++y)
      for (int x = box.min().x(); x <= box.max().x(); ++x) {
        const openvdb::Coord c(x, y, z);
        out.push_back(static_cast<float>(acc.isValueOn(c) ? acc.getValue(c) : grid->background()));
      }
  return out;
}

TEST(VolumeIo, VdbCompressionVariants) {
  init_vdb();
  TempDir dir;
  const std::uint32_t settings[] = {
      openvdb::io::COMPRESS_NONE, openvdb::io::COMPRESS_ZIP, openvdb::io::COMPRESS_ACTIVE_MASK,
      openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK, openvdb::io::COMPRESS_BLOSC,
      openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK};
  int n = 0;
  for (std::uint32_t compression : settings) {
    for (bool half : {false, true}) {
      const std::string path = dir.file("c" + std::to_string(n++) + ".vdb");
      auto f = varied_grid<openvdb::FloatGrid>(half);
      f->setName("f");
      auto d = varied_grid<openvdb::DoubleGrid>(half);
      d->setName("d");
      auto instance = f->copyGrid();  // shares f's tree: written as an instance
      instance->setName("instance");
      openvdb::io::File file(path);
      file.setCompression(compression);
      file.write(openvdb::GridPtrVec{f, d, openvdb::ConstPtrCast<openvdb::GridBase>(instance)});
      const std::string label = path + " compression " + std::to_string(compression) + (half ? " half" : "");
      for (const char* name : {"f", "d", "instance"}) {
        VolumeReadOptions options;
        options.grid = name;
        try {
          const Volume v = read_volume(path, options);
          const std::vector<float> expected = std::string(name) == "d"
                                                  ? reference_dense<openvdb::DoubleGrid>(path, name, v)
                                                  : reference_dense<openvdb::FloatGrid>(path, name, v);
          expect_values(v, expected, label + " grid " + name);
          EXPECT_EQ(v.source_type, std::string(name) == "d" ? ScalarType::Float64 : ScalarType::Float32);
        } catch (const Error& e) {
          ADD_FAILURE() << label << " grid " << name << ": " << e.what();
        }
      }
    }
  }
}

TEST(VolumeIo, VdbRejectsRotatedTransform) {
  init_vdb();
  TempDir dir;
  const std::string path = dir.file("rotated.vdb");
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  m.setToRotation(openvdb::math::Z_AXIS, 0.3);
  grid->setTransform(openvdb::math::Transform::createLinearTransform(m));
  grid->tree().setValue(openvdb::Coord(1, 2, 3), 1.0f);
  openvdb::io::File(path).write(openvdb::GridPtrVec{grid});
  expect_error(path, {}, "rotated", "rotated transform");
}

TEST(VolumeIo, VdbMalformed) {
  TempDir dir;
  const std::string good_path = dir.file("good.vdb");
  write_vdb(good_path);
  const Bytes good = read_file(good_path);
  const std::string path = dir.file("bad.vdb");
  write_file(path, Bytes(good.begin(), good.begin() + static_cast<long>(good.size() / 2)));
  expect_error(path, {}, "truncated", "truncated vdb");
  write_file(path, std::string("definitely not a vdb file"));
  expect_error(path, {}, "not an OpenVDB file", "not vdb");
  Bytes bad_version = good;
  bad_version[8] = 0x10;  // file version 16
  write_file(path, bad_version);
  expect_error(path, {}, "version", "bad version");

  // Only a vec3 grid: no scalar grid to read.
  init_vdb();
  auto vectors = openvdb::Vec3SGrid::create();
  vectors->setName("velocity");
  vectors->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));
  openvdb::io::File(path).write(openvdb::GridPtrVec{vectors});
  expect_error(path, {}, "missing field", "no scalar grid");

  // An empty float grid.
  auto empty = openvdb::FloatGrid::create(1.0f);
  empty->setName("empty");
  openvdb::io::File(path).write(openvdb::GridPtrVec{empty});
  expect_error(path, {}, "no active voxels", "empty grid");

  // A root tile makes the active box 4096^3: far too large for a dense copy.
  auto huge = openvdb::FloatGrid::create(1.0f);
  huge->setName("huge");
  huge->tree().addTile(3, openvdb::Coord(0, 0, 0), 2.0f, true);
  huge->tree().setValue(openvdb::Coord(100000, 0, 0), 1.0f);
  openvdb::io::File(path).write(openvdb::GridPtrVec{huge});
  expect_error(path, {}, "too large", "absurd dims");
}

// A float grid named "density" with the given active voxels (value 1).
openvdb::FloatGrid::Ptr float_grid(const std::vector<openvdb::Coord>& voxels) {
  init_vdb();
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  for (const auto& v : voxels) grid->tree().setValue(v, 1.0f);
  return grid;
}

void write_grid(const std::string& path, const openvdb::FloatGrid::Ptr& grid, std::uint32_t compression) {
  openvdb::io::File file(path);
  file.setCompression(compression);
  file.write(openvdb::GridPtrVec{grid});
}

// The start of the first zlib chunk (int64 size, then the stream) in `bytes`.
std::size_t first_zip_chunk(const Bytes& bytes) {
  for (std::size_t i = 0; i + 10 <= bytes.size(); ++i) {
    std::int64_t n = 0;
    std::memcpy(&n, &bytes[i], 8);
    const unsigned header = bytes[i + 8] * 256u + bytes[i + 9];
    if (n > 2 && static_cast<std::uint64_t>(n) <= bytes.size() - i - 8 && bytes[i + 8] == 0x78 && header % 31 == 0)
      return i;
  }
  return bytes.size();
}

// OpenVDB 10 leaks the root child it is reading when a topology chunk fails
// to decompress: the walk must reject such a file before OpenVDB reads it.
TEST(VolumeIo, VdbCorruptTopologyChunkRejectedBeforeOpenVdb) {
  TempDir dir;
  const std::string path = dir.file("zip.vdb");
  write_grid(path, float_grid({openvdb::Coord(1, 2, 3)}), openvdb::io::COMPRESS_ZIP);
  Bytes bytes = read_file(path);
  // The first chunk holds the 32^3 internal node's values. Its first deflate
  // block gets type 3 (invalid): nothing decompresses.
  const std::size_t chunk = first_zip_chunk(bytes);
  ASSERT_LT(chunk, bytes.size());
  bytes[chunk + 10] |= 0x06;
  write_file(path, bytes);
  // OpenVDB itself throws on this file (the path that leaks).
  EXPECT_ANY_THROW({
    openvdb::io::File file(path);
    file.open();
    file.readGrid("density");
  });
  expect_error(path, {}, "topology chunk does not decompress", "corrupt topology chunk");
}

// Two root children at one origin: OpenVDB keeps the second (leaking the
// first), so the file would read as another volume. The first child holds
// only a tile, so the leaf count still matches the data blocks.
TEST(VolumeIo, VdbRepeatedRootOriginRejected) {
  TempDir dir;
  const std::string path = dir.file("twice.vdb");
  auto grid = float_grid({openvdb::Coord(4101, 3, 2)});
  grid->tree().addTile(1, openvdb::Coord(8, 8, 8), 1.0f, true);
  write_grid(path, grid, openvdb::io::COMPRESS_NONE);
  Bytes bytes = read_file(path);
  const std::int32_t second[3] = {4096, 0, 0}, first[3] = {0, 0, 0};
  const auto* pattern = reinterpret_cast<const std::uint8_t*>(second);
  const auto at = std::search(bytes.begin(), bytes.end(), pattern, pattern + 12);
  ASSERT_NE(at, bytes.end());
  ASSERT_EQ(std::search(at + 1, bytes.end(), pattern, pattern + 12), bytes.end());
  std::memcpy(&*at, first, 12);
  write_file(path, bytes);
  expect_error(path, {}, "two entries at one origin", "repeated root origin");
}

// OpenVDB reads values as halves when the grid's is_saved_as_half_float
// entry says so; the walk follows the grid type's _HalfFloat suffix. A file
// where the two disagree reads as the type says (it used to reach OpenVDB's
// failing decompression, which leaked, or to read garbage).
TEST(VolumeIo, VdbHalfFlagFollowsTheGridType) {
  TempDir dir;
  const std::string path = dir.file("flag.vdb");
  for (const bool half : {true, false}) {
    SCOPED_TRACE(half);
    auto grid = float_grid({openvdb::Coord(1, 2, 3), openvdb::Coord(2, 2, 3)});
    grid->setSaveFloatAsHalf(half);
    write_grid(path, grid, openvdb::io::COMPRESS_ZIP);
    const Volume expected = read_volume(path);
    Bytes bytes = read_file(path);
    // The entry: name, "bool", size 1, value. A half grid's loses its name, a full one's says true.
    const std::string entry = std::string(openvdb::GridBase::META_SAVE_HALF_FLOAT) + std::string("\x04\0\0\0bool\x01\0\0\0", 12);
    const auto at = std::search(bytes.begin(), bytes.end(), entry.begin(), entry.end());
    ASSERT_NE(at, bytes.end());
    if (half) at[0] = 'X';
    else at[static_cast<long>(entry.size())] = 1;
    write_file(path, bytes);
    const Volume read = read_volume(path);
    EXPECT_EQ(read.dims, expected.dims);
    EXPECT_EQ(read.values, expected.values);
  }
}

TEST(VolumeIoSweep, Vdb) {
  // The smallest useful VDB file (one leaf, ~10 kB: the internal nodes' masks).
  init_vdb();
  TempDir dir;
  const std::string path = dir.file("s.vdb");
  auto grid = openvdb::FloatGrid::create(-1.0f);
  grid->setName("density");
  grid->setTransform(scale_translate());
  for (int x = 0; x < 4; ++x) grid->tree().setValue(openvdb::Coord(x, x % 2, 1), 0.5f * x);
  grid->tree().setValueOff(openvdb::Coord(5, 5, 5), 3.0f);
  // Default (Blosc + active mask), zip, none, and half floats.
  const std::uint32_t settings[] = {openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK,
                                    openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK,
                                    openvdb::io::COMPRESS_NONE, openvdb::io::COMPRESS_BLOSC};
  for (std::uint32_t compression : settings) {
    grid->setSaveFloatAsHalf(compression == openvdb::io::COMPRESS_BLOSC);
    openvdb::io::File file(path);
    file.setCompression(compression);
    file.write(openvdb::GridPtrVec{grid});
    sweep(path, {}, "vdb compression " + std::to_string(compression));
  }
}

}  // namespace
}  // namespace isowave
