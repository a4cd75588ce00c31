// Volume reading across the formats: the shared real volumes load with their
// documented dims, type and range; builtin fields, unknown extensions, missing
// files and scalar type names.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <ostream>
#include <string>

#include "isowave/core/error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/volume_io.h"
#include "support/test_meshes.h"
#include "volume_io_test_support.h"

namespace isowave {
namespace {

namespace fs = std::filesystem;
using namespace volume_io_test;

// ---------------------------------------------------------------------------
// Shared real data

struct SharedVolume {
  const char* file;
  std::array<std::size_t, 3> dims;
  ScalarType type;
  double iso;
  bool raw;
};

// From the table in ../shared/data/README.md.
const SharedVolume kShared[] = {
    {"miranda_256x256x256.nrrd", {256, 256, 256}, ScalarType::Float32, 1.5, false},
    {"hcci_oh_187x187x187.nrrd", {187, 187, 187}, ScalarType::Float32, 0.0003, false},
    {"csafe_heptane_151x151x151.nrrd", {151, 151, 151}, ScalarType::Float32, 50, false},
    {"engine_256x256x128.nrrd", {256, 256, 128}, ScalarType::Float32, 100, false},
    {"aneurism_256x256x256.nrrd", {256, 256, 256}, ScalarType::Float32, 100, false},
    {"embryo_256x256x256.nrrd", {256, 256, 256}, ScalarType::UInt8, 50, false},
    {"mri_head_256x256x256.nrrd", {256, 256, 256}, ScalarType::UInt8, 30, false},
    {"stent_128x128x256.nrrd", {128, 128, 256}, ScalarType::Int16, 300, false},
    {"neghip_66x66x66_uint8.raw", {66, 66, 66}, ScalarType::UInt8, 64, true},
    {"skull_64x64x64_float32.raw", {64, 64, 64}, ScalarType::Float32, 2.9, true},
    {"ironProt.vtk", {68, 68, 68}, ScalarType::UInt8, 128, false},
    {"carotid.vtk", {76, 49, 45}, ScalarType::Float32, 200, false},
    {"hydrogen.vti", {64, 64, 64}, ScalarType::Float32, 0.05, false},
    {"viscousfingers_050.vti", {64, 64, 64}, ScalarType::Float32, 30, false},
    {"viscousfingers_099.vti", {64, 64, 64}, ScalarType::Float32, 30, false},
    {"isabel_30.vti", {125, 125, 25}, ScalarType::Float64, 30, false},
};

void PrintTo(const SharedVolume& volume, std::ostream* os) { *os << volume.file; }

class SharedVolumes : public ::testing::TestWithParam<SharedVolume> {};

TEST_P(SharedVolumes, LoadsWithTheDocumentedDimsTypeAndRange) {
  const SharedVolume& info = GetParam();
  ISOWAVE_REQUIRE_SHARED_FILE(path, std::string("volumes/") + info.file);
  VolumeReadOptions options;
  if (info.raw) {
    options.dims = info.dims;
    options.type = info.type;
  }
  const Volume volume = read_volume(path, options);
  EXPECT_EQ(volume.dims, info.dims);
  EXPECT_EQ(volume.source_type, info.type);
  ASSERT_EQ(volume.values.size(), info.dims[0] * info.dims[1] * info.dims[2]);
  EXPECT_EQ(volume.nonfinite_count, count_nonfinite(volume.values));

  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (float v : volume.values) {
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  // The suggested isovalue must cut the field.
  EXPECT_LT(lo, info.iso) << info.file;
  EXPECT_GT(hi, info.iso) << info.file;
  // Integer samples are integers within their type's range.
  if (info.type == ScalarType::UInt8 || info.type == ScalarType::Int16) {
    const double tmin = info.type == ScalarType::UInt8 ? 0 : -32768, tmax = info.type == ScalarType::UInt8 ? 255 : 32767;
    EXPECT_GE(lo, tmin);
    EXPECT_LE(hi, tmax);
    EXPECT_TRUE(std::all_of(volume.values.begin(), volume.values.end(), [](float v) { return v == std::floor(v); }));
  }
  EXPECT_GT(volume.spacing.x, 0);
  EXPECT_GT(volume.spacing.y, 0);
  EXPECT_GT(volume.spacing.z, 0);
  const std::string name = info.file;
  if (name == "isabel_30.vti") {
    // README: spacing about 4.008, 4.008, 4.041.
    EXPECT_NEAR(volume.spacing.x, 4.008, 0.001);
    EXPECT_NEAR(volume.spacing.y, 4.008, 0.001);
    EXPECT_NEAR(volume.spacing.z, 4.041, 0.001);
  } else {
    // README: unit spacing unless stated.
    EXPECT_DOUBLE_EQ(volume.spacing.x, 1);
    EXPECT_DOUBLE_EQ(volume.spacing.y, 1);
    EXPECT_DOUBLE_EQ(volume.spacing.z, 1);
  }
  if (name == "carotid.vtk") {
    // The file's header says ORIGIN 100 80 1.
    EXPECT_DOUBLE_EQ(volume.origin.x, 100);
    EXPECT_DOUBLE_EQ(volume.origin.y, 80);
    EXPECT_DOUBLE_EQ(volume.origin.z, 1);
  }
}

INSTANTIATE_TEST_SUITE_P(VolumeIo, SharedVolumes, ::testing::ValuesIn(kShared),
                         [](const ::testing::TestParamInfo<SharedVolume>& param) {
                           std::string name = param.param.file;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

// builtin:NAME:N is the generated field of that name and size at unit
// spacing (extract/builtin_fields.h): the sphere R - |p - c| with
// R = 0.35 (N - 1) and c the box centre, computed here.
TEST(VolumeIo, BuiltinPrefixDispatches) {
  const Volume v = read_volume("builtin:sphere:16");
  ASSERT_EQ(v.dims, (std::array<std::size_t, 3>{16, 16, 16}));
  ASSERT_EQ(v.values.size(), 16u * 16 * 16);
  EXPECT_EQ(v.spacing, (Vec3{1, 1, 1}));
  EXPECT_EQ(v.origin, (Vec3{0, 0, 0}));
  const double centre = 7.5, radius = 0.35 * 15;
  for (std::size_t k = 0; k < 16; ++k)
    for (std::size_t j = 0; j < 16; ++j)
      for (std::size_t i = 0; i < 16; ++i) {
        const double r = norm(Vec3{i - centre, j - centre, k - centre});
        ASSERT_NEAR(v.at(i, j, k), radius - r, 1e-5) << i << " " << j << " " << k;
      }
  EXPECT_EQ(read_volume("builtin:torus:12").values, make_builtin_field("torus", 12).values);
  for (const char* bad : {"builtin:sphere:abc", "builtin:", "builtin:cube:16", "builtin:sphere:4"}) {
    try {
      read_volume(bad);
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument) << e.what();
    }
  }
}

TEST(VolumeIo, UnknownExtensionAndMissingFile) {
  TempDir dir;
  EXPECT_THROW(read_volume(dir.file("x.xyz")), Error);
  expect_error(dir.file("missing.nrrd"), {}, "cannot open", "missing file");
  fs::create_directories(dir.file("folder.nrrd"));
  expect_error(dir.file("folder.nrrd"), {}, "not a regular file", "directory");
}

TEST(VolumeIo, ParseScalarType) {
  EXPECT_EQ(parse_scalar_type("uint8"), ScalarType::UInt8);
  EXPECT_EQ(parse_scalar_type("int16"), ScalarType::Int16);
  EXPECT_EQ(parse_scalar_type("Float32"), ScalarType::Float32);
  EXPECT_EQ(parse_scalar_type("float64"), ScalarType::Float64);
  for (ScalarType t : kAllTypes) EXPECT_EQ(parse_scalar_type(to_string(t)), t);
  try {
    parse_scalar_type("complex64");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
  }
}

}  // namespace
}  // namespace isowave
