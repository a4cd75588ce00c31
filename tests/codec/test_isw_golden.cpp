// The golden .isw files: tests/codec/data/golden_1_0.isw, golden_2_0.isw,
// golden_2_1.isw, golden_2_2.isw and golden_2_2_counts.isw (2.2 with PCNT)
// were written by the format 1.0, 2.0, 2.1 and 2.2 encoders from the surface that
// golden_surface() defines, and every later reader must decode them to that surface. Its expected values
// come from the generator below, not from a decode: base topology, sharp
// flags and metadata exactly, base control points and coefficients within
// half their quantization step. The generator uses only integer arithmetic
// and decimal constants, so it gives the same values on every platform.
//
// Regenerate only with a new format version (and keep the old files, whose
// tests must keep passing): ISOWAVE_WRITE_GOLDEN_1_0=PATH (or _2_0, _2_1, _2_2, _2_2_COUNTS) codec_tests
// --gtest_filter='IswGolden.*' writes that version's file to PATH.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/region.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {
namespace {

constexpr int kLevels = 2;
constexpr double kStep = 1e-3;
constexpr double kDetail = 0.2;

struct GoldenSurface {
  PolygonMesh base;                // positions are the base control points
  std::vector<Vec3> coefficients;  // coarse to fine: base control points, then wavelet coefficients
  IswMetadata metadata;
};

// A value in [-1, 1) from the coefficient index and axis (a multiplicative
// hash in 32-bit unsigned arithmetic: the same everywhere).
double signed_hash(std::uint32_t index, std::uint32_t axis) {
  const std::uint32_t h = (index + 1u) * 2654435761u ^ (axis + 1u) * 40503u * 2246822519u;
  return double((h >> 8) & 0xffffu) / 32768.0 - 1.0;
}

// A pentagonal prism with one side split into two triangles (faces of 3, 4
// and 5 sides), vertex 7 sharp, 2 levels: 10 base vertices, 120 wavelet
// coefficients of sizes kDetail / 2^level.
GoldenSurface golden_surface() {
  GoldenSurface s;
  const double ring[5][2] = {{1.0, 0.0}, {0.31, 0.95}, {-0.81, 0.59}, {-0.81, -0.59}, {0.31, -0.95}};
  for (const double z : {-0.5, 0.5})
    for (const auto& xy : ring) s.base.positions.push_back({xy[0], xy[1], z});
  s.base.add_face({4, 3, 2, 1, 0});
  s.base.add_face({5, 6, 7, 8, 9});
  s.base.add_face({0, 1, 6});
  s.base.add_face({0, 6, 5});
  for (std::uint32_t i = 1; i < 5; ++i) s.base.add_face({i, (i + 1) % 5, (i + 1) % 5 + 5, i + 5});
  s.base.sharp.assign(10, 0);
  s.base.sharp[7] = 1;
  const SubdivisionHierarchy hierarchy(s.base, kLevels);
  s.coefficients.resize(hierarchy.fine_vertex_count());
  for (std::size_t i = 0; i < s.base.vertex_count(); ++i) s.coefficients[i] = s.base.positions[i];
  for (std::size_t i = s.base.vertex_count(); i < s.coefficients.size(); ++i) {
    const double size = kDetail / double(1 << hierarchy.level_of_index(i));
    const auto index = static_cast<std::uint32_t>(i);
    s.coefficients[i] = {size * signed_hash(index, 0), size * signed_hash(index, 1), size * signed_hash(index, 2)};
  }
  s.metadata.values["source"] = "golden pentagonal prism";
  s.metadata.values["isovalue"] = "0.5";
  s.metadata.values["cell_size"] = "0.05";
  return s;
}

std::string golden_path(const char* name = "golden_1_0.isw") {
  return std::string(ISOWAVE_CODEC_TEST_DATA_DIR) + "/" + name;
}

// What every version keeps exactly: metadata, levels, step, base topology and
// sharp flags, and one value per fine control point.
void expect_generator_headers(const IswDecoded& d, const GoldenSurface& expected) {
  EXPECT_EQ(d.metadata.values, expected.metadata.values);
  EXPECT_EQ(d.levels, kLevels);
  EXPECT_DOUBLE_EQ(d.step, kStep);
  EXPECT_EQ(d.base.face_offsets, expected.base.face_offsets);
  EXPECT_EQ(d.base.face_vertices, expected.base.face_vertices);
  EXPECT_EQ(d.base.sharp, expected.base.sharp);
  ASSERT_EQ(d.coefficients.size(), expected.coefficients.size());
}

TEST(IswGolden, Format10FileDecodesToItsGenerator) {
  const GoldenSurface expected = golden_surface();
  if (const char* out = std::getenv("ISOWAVE_WRITE_GOLDEN_1_0")) {
    IswEncodeOptions options;
    options.major_version = 1;
    options.step = kStep;
    std::ofstream(out, std::ios::binary)
        << encode_isw(expected.base, kLevels, expected.coefficients, expected.metadata, options);
    GTEST_SKIP() << "wrote " << out;
  }
  const IswDecoded d = read_isw(golden_path());
  EXPECT_EQ(d.major_version, 1);
  EXPECT_EQ(d.minor_version, 0);
  EXPECT_FALSE(d.truncated);
  EXPECT_EQ(d.chunks_decoded, d.chunks_total);
  expect_generator_headers(d, expected);
  if (HasFatalFailure()) return;
  // The file's class weights are today's wavelet norms of its hierarchy.
  const std::vector<double> norms = wavelet_norms(*d.hierarchy);
  ASSERT_EQ(d.class_weights.size(), norms.size());
  for (std::size_t c = 0; c < norms.size(); ++c) EXPECT_NEAR(d.class_weights[c], norms[c], 1e-9 * norms[c]) << c;
  // Every value within half of its class's step per component (the base
  // control points are class 0).
  for (std::size_t i = 0; i < d.coefficients.size(); ++i) {
    const double step = kStep / d.class_weights[static_cast<std::size_t>(coefficient_class(*d.hierarchy, i))];
    for (int axis = 0; axis < 3; ++axis)
      ASSERT_LE(std::abs(d.coefficients[i][axis] - expected.coefficients[i][axis]), 0.5 * step * (1 + 1e-9))
          << "value " << i << " axis " << axis;
  }
  EXPECT_EQ(d.ranked.size(), expected.coefficients.size() - expected.base.vertex_count());
}

TEST(IswGolden, Format10FileDecodesTheMostImportantCoefficientsFirst) {
  const GoldenSurface expected = golden_surface();
  IswDecodeOptions options;
  options.max_percent = 20;
  const IswDecoded d = read_isw(golden_path(), options);
  const std::size_t base = expected.base.vertex_count();
  ASSERT_EQ(d.ranked.size(), coefficients_for_percent(*d.hierarchy, 20));
  ASSERT_LT(d.ranked.size(), expected.coefficients.size() - base);
  // Importance is the generator's magnitude times the class weight; every
  // decoded coefficient is at least as important as every one left out, up
  // to the quantization of both.
  const auto importance = [&](std::size_t i) {
    const double weight = d.class_weights[static_cast<std::size_t>(coefficient_class(*d.hierarchy, i))];
    return norm(expected.coefficients[i]) * weight;
  };
  std::vector<std::uint8_t> decoded(expected.coefficients.size(), 0);
  double least_decoded = INFINITY;
  for (const std::uint32_t i : d.ranked) {
    ASSERT_GE(i, base);
    decoded[i] = 1;
    least_decoded = std::min(least_decoded, importance(i));
  }
  const double tolerance = std::sqrt(3.0) * kStep;
  for (std::size_t i = base; i < expected.coefficients.size(); ++i) {
    if (decoded[i]) continue;
    EXPECT_LE(importance(i), least_decoded + tolerance) << i;
    EXPECT_EQ(d.coefficients[i], Vec3{}) << i;
  }
}

// Version 2 (embedded planes in local frames): the golden file decodes to the
// generator within its quantizer's bounds, and every byte count of it past
// its headers decodes.
constexpr double kTangentialFactor = 4;

// Writes a version 2 golden file to the path in environment variable `env`
// when it is set (returns true: the test then skips); `frame_step` 0 is the
// encoder's automatic one.
bool write_golden_2(const char* env, const GoldenSurface& expected, int minor, double frame_step,
                    std::size_t group_nodes = 0) {
  const char* out = std::getenv(env);
  if (!out) return false;
  IswEncodeOptions options;
  options.major_version = 2;
  options.minor_version = minor;
  options.step = kStep;
  options.tangential_factor = kTangentialFactor;
  options.frame_step = frame_step;
  options.group_nodes = group_nodes;
  std::ofstream(out, std::ios::binary)
      << encode_isw(expected.base, kLevels, expected.coefficients, expected.metadata, options);
  return true;
}

// A version 2.`minor` golden file, whole, against its generator: a dead-zone
// quantizer, so every component within one step of its class (k steps along
// the surface), whatever the frame; base control points in world axes.
IswDecoded expect_golden_2(const char* name, const GoldenSurface& expected, int minor) {
  IswDecoded d = read_isw(golden_path(name));
  EXPECT_EQ(d.major_version, 2);
  EXPECT_EQ(d.minor_version, minor);
  EXPECT_FALSE(d.truncated);
  EXPECT_EQ(d.stream.planes_decoded, d.stream.planes);
  EXPECT_DOUBLE_EQ(d.stream.tangential_factor, kTangentialFactor);
  expect_generator_headers(d, expected);
  if (::testing::Test::HasFatalFailure()) return d;
  for (std::size_t i = 0; i < d.coefficients.size(); ++i) {
    const int cls = coefficient_class(*d.hierarchy, i);
    const double step = kStep / d.class_weights[static_cast<std::size_t>(cls)];
    const double bound = cls == 0 ? std::sqrt(3.0) * step : std::sqrt(1 + 2 * kTangentialFactor * kTangentialFactor) * step;
    EXPECT_LE(norm(d.coefficients[i] - expected.coefficients[i]), bound * (1 + 1e-9)) << name << " value " << i;
  }
  return d;
}

TEST(IswGolden, Format20FileDecodesToItsGenerator) {
  const GoldenSurface expected = golden_surface();
  if (write_golden_2("ISOWAVE_WRITE_GOLDEN_2_0", expected, 0, 0)) GTEST_SKIP() << "wrote the 2.0 golden file";
  expect_golden_2("golden_2_0.isw", expected, 0);
}

// Every byte count of a golden file's stream decodes, as a truncated file.
void expect_every_byte_decodes(const char* name) {
  std::ifstream in(golden_path(name), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const IswDecoded full = decode_isw(bytes, "golden");
  ASSERT_GT(full.stream.bytes, 0u);
  for (std::uint64_t n = full.stream.offset; n < bytes.size(); ++n) {
    const IswDecoded d = decode_isw(bytes.substr(0, n), "cut");
    ASSERT_TRUE(d.truncated) << n;
    ASSERT_LE(d.stream.decoded, n - full.stream.offset) << n;
  }
}

TEST(IswGolden, Format20FileDecodesAtEveryByteOfItsStream) { expect_every_byte_decodes("golden_2_0.isw"); }

// Version 2.1 (non-normal flags): the same surface with two coefficients in
// three (those of index not divisible by 3) along the normals of their local
// frames, as isw_frame_normals() gives them for the frame step below (the
// frames are part of the format). The others stay free 3-vectors.
constexpr double kFrameStep21 = 0.02;

GoldenSurface golden_surface_21() {
  GoldenSurface s = golden_surface();
  const SubdivisionHierarchy hierarchy(s.base, kLevels);
  const std::vector<Vec3> normals = isw_frame_normals(hierarchy, s.base.positions, kFrameStep21);
  for (std::size_t i = s.base.vertex_count(); i < s.coefficients.size(); ++i)
    if (i % 3 != 0) s.coefficients[i] = normals[i] * dot(normals[i], s.coefficients[i]);
  return s;
}

TEST(IswGolden, Format21FileDecodesToItsGenerator) {
  const GoldenSurface expected = golden_surface_21();
  if (write_golden_2("ISOWAVE_WRITE_GOLDEN_2_1", expected, 1, kFrameStep21)) GTEST_SKIP() << "wrote the 2.1 golden file";
  const IswDecoded d = expect_golden_2("golden_2_1.isw", expected, 1);
  if (HasFailure()) return;
  EXPECT_DOUBLE_EQ(d.stream.frame_step, kFrameStep21);
  // A normal coefficient decodes with no tangential part at all.
  const SubdivisionHierarchy hierarchy(expected.base, kLevels);
  const std::vector<Vec3> normals = isw_frame_normals(hierarchy, expected.base.positions, kFrameStep21);
  for (std::size_t i = d.base.vertex_count(); i < d.coefficients.size(); ++i) {
    if (i % 3 == 0) continue;
    const Vec3 tangential = d.coefficients[i] - normals[i] * dot(normals[i], d.coefficients[i]);
    ASSERT_LE(norm(tangential), 1e-12) << "value " << i;
  }
}

TEST(IswGolden, Format21FileDecodesAtEveryByteOfItsStream) { expect_every_byte_decodes("golden_2_1.isw"); }

// Version 2.2 (groups by space, GIDX): 2.1's surface in groups of at most 48
// tree nodes where the Morton order's cells allow. A region decode of the
// file equals the whole decode at every fine control point the box holds
// (on a surface of seven base faces every group is in reach of any region:
// tests/codec/test_random_access.cpp shows regions that read fewer).
TEST(IswGolden, Format22FileDecodesToItsGeneratorAndByRegion) {
  const GoldenSurface expected = golden_surface_21();
  if (write_golden_2("ISOWAVE_WRITE_GOLDEN_2_2", expected, 2, kFrameStep21, 48))
    GTEST_SKIP() << "wrote the 2.2 golden file";
  const IswDecoded d = expect_golden_2("golden_2_2.isw", expected, 2);
  if (HasFailure()) return;
  EXPECT_GE(d.stream.groups, 3u);
  IswDecodeOptions options;
  options.region = make_region({-10, -10, -10, 10, 10, 0.2}, false, "region");
  const IswDecoded part = read_isw(golden_path("golden_2_2.isw"), options);
  EXPECT_EQ(part.file_bytes_read, part.stream.offset + part.stream.decoded);
  ASSERT_TRUE(part.patch);
  const PolygonMesh whole = region_mesh(d, *options.region, 0), mine = region_mesh(part, *options.region, 0);
  EXPECT_EQ(mine.face_vertices, whole.face_vertices);
  ASSERT_EQ(mine.positions.size(), whole.positions.size());
  std::size_t inside = 0;
  for (std::size_t v = 0; v < whole.positions.size(); ++v)
    if (options.region->contains(whole.positions[v])) {
      ++inside;
      EXPECT_LT(norm(mine.positions[v] - whole.positions[v]), 1e-12) << v;
    }
  EXPECT_GT(inside, 0u);
}

TEST(IswGolden, Format22FileDecodesAtEveryByteOfItsStream) { expect_every_byte_decodes("golden_2_2.isw"); }

// The 2.2 file with plane counts (PCNT, written since session 37; the file
// above predates them): the same surface; the counts are the non-zero
// coefficients a decode has at each plane end; a percentage reads a prefix
// of whole planes and decodes as from memory.
TEST(IswGolden, Format22FileWithPlaneCountsDecodesToItsGeneratorAndReadsAPrefix) {
  const GoldenSurface expected = golden_surface_21();
  if (write_golden_2("ISOWAVE_WRITE_GOLDEN_2_2_COUNTS", expected, 2, kFrameStep21, 48))
    GTEST_SKIP() << "wrote the 2.2 golden file with plane counts";
  const IswDecoded d = expect_golden_2("golden_2_2_counts.isw", expected, 2);
  if (HasFailure()) return;
  ASSERT_EQ(d.stream.plane_counts.size(), d.stream.plane_ends.size());
  IswDecodeOptions options;
  options.order = IswOrder::Index;
  for (std::size_t k = 0; k < d.stream.plane_ends.size(); ++k) {
    options.max_stream_bytes = d.stream.plane_ends[k];
    const IswDecoded prefix = read_isw(golden_path("golden_2_2_counts.isw"), options);
    std::size_t nonzero = 0;
    for (std::size_t i = prefix.base.vertex_count(); i < prefix.coefficients.size(); ++i)
      nonzero += prefix.coefficients[i] == Vec3{} ? 0 : 1;
    EXPECT_EQ(d.stream.plane_counts[k], nonzero) << "plane end " << k;
  }
  IswDecodeOptions percent;
  percent.max_percent = 10;
  const IswDecoded part = read_isw(golden_path("golden_2_2_counts.isw"), percent);
  EXPECT_LT(part.file_bytes_read, part.file_bytes);
  EXPECT_EQ(part.file_bytes_read, part.stream.offset + part.stream.decoded);
  std::ifstream in(golden_path("golden_2_2_counts.isw"), std::ios::binary);
  EXPECT_EQ(part.coefficients, decode_isw(std::string((std::istreambuf_iterator<char>(in)), {}), "golden", percent).coefficients);
}

}  // namespace
}  // namespace isowave
