// The .isw file: round trips within the quantization tolerance, exact
// progressive truncation, stable re-encoding, statistics that match an
// independent recomputation, and hostile bytes (every truncation point,
// random corruption) that never crash or over-allocate.
#include <cmath>
#include <cstring>
#include <random>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "codec_test_data.h"
#include "isw_test_sections.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/error.h"

namespace isowave {
namespace {

using test::sample_metadata;

// A genus-2 slab with one sharp vertex: sharp flags are coded with the base mesh.
PolygonMesh slab_with_sharp_vertex(std::uint32_t sharp_vertex) {
  PolygonMesh base = test::genus_slab(2);
  base.sharp.assign(base.vertex_count(), 0);
  base.sharp[sharp_vertex] = 1;
  return base;
}

struct Encoded {
  test::CodedSurface surface;
  std::string bytes;
  double step;
};

Encoded encode_sample(PolygonMesh base, int levels, double step = 1e-3) {
  Encoded e{test::make_coded_surface(std::move(base), levels, 0.05, 9), {}, step};
  IswEncodeOptions options;
  options.major_version = 1;
  options.step = step;
  e.bytes = encode_isw(e.surface.base, levels, e.surface.coefficients, sample_metadata(), options);
  return e;
}

TEST(IswFormat, FullDecodeMatchesTheFittedMeshWithinTheQuantizationTolerance) {
  const PolygonMesh base = slab_with_sharp_vertex(3);
  const Encoded e = encode_sample(base, 3);
  const IswDecoded d = decode_isw(e.bytes, "test.isw");
  EXPECT_FALSE(d.truncated);
  EXPECT_EQ(d.chunks_decoded, d.chunks_total);
  EXPECT_EQ(d.metadata.text("source"), "generated");
  EXPECT_EQ(d.base.face_vertices, base.face_vertices);
  EXPECT_EQ(d.base.sharp, base.sharp);
  // Every coefficient within half a step of its class per component.
  for (std::size_t i = 0; i < d.coefficients.size(); ++i) {
    const double step = d.step / d.class_weights[static_cast<std::size_t>(coefficient_class(*d.hierarchy, i))];
    for (int axis = 0; axis < 3; ++axis)
      ASSERT_LE(std::abs(d.coefficients[i][axis] - e.surface.coefficients[i][axis]), 0.5 * step * (1 + 1e-9)) << i;
  }
  // The full reconstruction: RMSE about step / 2 (each class adds the same error).
  const std::vector<Vec3> full = reconstruct(d, d.ranked.size());
  const PointErrors errors = point_errors(full, e.surface.fine, full.size());
  EXPECT_LT(errors.rms, e.step);
  std::printf("[ report ] %zu fine vertices, %zu bytes = %.2f bits per fine vertex, RMSE %.3g for step %.3g\n",
              full.size(), e.bytes.size(), 8.0 * e.bytes.size() / full.size(), errors.rms, e.step);
}

TEST(IswFormat, FileWhoseEveryCoefficientIsNonZeroDecodesCompletely) {
  // A step far below the coefficients' size: none quantizes to zero, so the
  // last chunk reaches the decode limit exactly and END must still be read.
  const Encoded e = encode_sample(test::genus_slab(1), 2, 1e-5);
  const IswDecoded d = decode_isw(e.bytes, "test.isw");
  ASSERT_EQ(d.ranked.size(), d.coefficients_total);
  ASSERT_EQ(d.coefficients_total, d.hierarchy->fine_vertex_count() - d.hierarchy->vertex_count(0));
  EXPECT_FALSE(d.truncated) << d.truncation_note;
  EXPECT_EQ(d.chunks_decoded, d.chunks_total);
}

TEST(IswFormat, DecodeReusesAMatchingHierarchyAndIgnoresAnotherOne) {
  const Encoded e = encode_sample(test::genus_slab(2), 2);
  const IswDecoded built = decode_isw(e.bytes, "test.isw");
  IswDecodeOptions options;
  options.hierarchy = std::make_shared<const SubdivisionHierarchy>(e.surface.base, 2);
  const IswDecoded reused = decode_isw(e.bytes, "test.isw", options);
  EXPECT_EQ(reused.hierarchy, options.hierarchy);
  EXPECT_EQ(reused.coefficients, built.coefficients);
  EXPECT_EQ(reused.ranked, built.ranked);
  // Another level count, or another base mesh: the decoder builds its own.
  options.hierarchy = std::make_shared<const SubdivisionHierarchy>(e.surface.base, 1);
  EXPECT_NE(decode_isw(e.bytes, "test.isw", options).hierarchy, options.hierarchy);
  options.hierarchy = std::make_shared<const SubdivisionHierarchy>(test::genus_slab(1), 2);
  const IswDecoded other = decode_isw(e.bytes, "test.isw", options);
  EXPECT_NE(other.hierarchy, options.hierarchy);
  EXPECT_EQ(other.coefficients, built.coefficients);
}

TEST(IswFormat, ExpectedDecodeEqualsTheDecodeOfTheFile) {
  const test::CodedSurface surface = test::make_coded_surface(slab_with_sharp_vertex(5), 3, 0.05, 9);
  const auto hierarchy = std::make_shared<const SubdivisionHierarchy>(surface.base, 3);
  IswEncodeOptions options;
  options.major_version = 1;
  options.step = 1e-3;
  options.class_weights = wavelet_norms(*hierarchy);
  std::vector<std::uint32_t> ranked;
  const std::string bytes = encode_isw(*hierarchy, surface.coefficients, sample_metadata(), options, &ranked);
  const IswDecoded decoded = decode_isw(bytes, "test.isw");
  EXPECT_EQ(ranked, decoded.ranked);
  const std::vector<Vec3> stored =
      quantize_coefficients(*hierarchy, surface.coefficients, options.step, options.class_weights);
  const IswDecoded expected = expected_decode(hierarchy, stored, ranked, bytes, "test.isw");
  EXPECT_EQ(expected.hierarchy, hierarchy);
  EXPECT_EQ(expected.ranked, decoded.ranked);
  EXPECT_EQ(expected.coefficients, decoded.coefficients);
  EXPECT_EQ(expected.base.positions, decoded.base.positions);
  EXPECT_EQ(expected.metadata.values, decoded.metadata.values);
  EXPECT_EQ(expected.chunks_decoded, decoded.chunks_decoded);
  ASSERT_EQ(expected.sections.size(), decoded.sections.size());
  for (std::size_t k = 0; k < expected.sections.size(); ++k) {
    EXPECT_EQ(expected.sections[k].tag, decoded.sections[k].tag);
    EXPECT_EQ(expected.sections[k].offset, decoded.sections[k].offset);
    EXPECT_EQ(expected.sections[k].bytes, decoded.sections[k].bytes);
    EXPECT_EQ(expected.sections[k].coefficients, decoded.sections[k].coefficients);
  }
  // So the statistics are the same as from the decode.
  const std::vector<RateDistortionRow> from_expected = rate_distortion(expected, {100, 20, 5}, &surface.fine);
  const std::vector<RateDistortionRow> from_decode = rate_distortion(decoded, {100, 20, 5}, &surface.fine);
  ASSERT_EQ(from_expected.size(), from_decode.size());
  for (std::size_t k = 0; k < from_expected.size(); ++k) {
    EXPECT_EQ(from_expected[k].rms, from_decode[k].rms);
    EXPECT_EQ(from_expected[k].bytes, from_decode[k].bytes);
  }
  // Counts that do not match, or another hierarchy, are not this file.
  EXPECT_THROW(expected_decode(hierarchy, stored, {}, bytes, "test.isw"), Error);
  const auto other = std::make_shared<const SubdivisionHierarchy>(surface.base, 2);
  EXPECT_THROW(expected_decode(other, stored, ranked, bytes, "test.isw"), Error);
}

TEST(IswFormat, BaseOnlyDecodeIsTheSubdividedBaseMesh) {
  const Encoded e = encode_sample(test::mixed_disk(), 3);
  IswDecodeOptions options;
  options.max_percent = 0;
  const IswDecoded d = decode_isw(e.bytes, "test.isw", options);
  EXPECT_TRUE(d.ranked.empty());
  EXPECT_FALSE(d.truncated);
  const std::vector<Vec3> ours = reconstruct(d, 0);
  const std::vector<Vec3> expected = subdivide(*e.surface.hierarchy, e.surface.base.positions);
  const double base_step = d.step / d.class_weights[0];
  // S is an average of base points: the error stays within the base quantization.
  EXPECT_LE(point_errors(ours, expected, expected.size()).max, std::sqrt(3.0) * 0.5 * base_step * (1 + 1e-9));
}

TEST(IswFormat, ReconstructionInTheDecodedArrayEqualsTheCopyingOne) {
  const PolygonMesh base = slab_with_sharp_vertex(3);
  const Encoded e = encode_sample(base, 3);
  const IswDecoded d = decode_isw(e.bytes, "test.isw");
  ASSERT_GT(d.ranked.size(), 100u);
  for (int level : {-1, 1, 2, 3})
    for (std::size_t keep : {std::size_t{0}, std::size_t{7}, d.ranked.size() / 2, d.ranked.size()}) {
      SCOPED_TRACE("level " + std::to_string(level) + ", keep " + std::to_string(keep));
      const std::vector<Vec3> expected = reconstruct(d, keep, level);
      IswDecoded taken = d;
      const std::vector<Vec3> got = take_reconstruction(taken, keep, level);
      EXPECT_TRUE(got == expected);
      EXPECT_TRUE(taken.coefficients.empty());
      EXPECT_EQ(taken.hierarchy, d.hierarchy);
      EXPECT_EQ(taken.ranked, d.ranked);
    }
}

TEST(IswFormat, ReencodingADecodedFileIsStable) {
  const Encoded e = encode_sample(test::genus_slab(1), 3);
  const IswDecoded d = decode_isw(e.bytes, "test.isw");
  IswEncodeOptions options;
  options.major_version = 1;
  options.step = d.step;
  const std::string again = encode_isw(d.base, d.levels, d.coefficients, d.metadata, options);
  EXPECT_EQ(again, e.bytes);
}

TEST(IswFormat, PartialDecodesKeepTheMostImportantCoefficients) {
  const Encoded e = encode_sample(test::genus_slab(2), 3);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  const std::vector<double> importance_full = importance(*full.hierarchy, full.coefficients, full.class_weights);
  for (std::uint64_t keep : {1ull, 17ull, 500ull, 2000ull}) {
    IswDecodeOptions options;
    options.max_coefficients = keep;
    const IswDecoded part = decode_isw(e.bytes, "test.isw", options);
    ASSERT_EQ(part.ranked.size(), std::min<std::size_t>(keep, full.ranked.size()));
    // Kept coefficients are exactly the full decode's top `keep`.
    double weakest_kept = 1e300;
    for (std::uint32_t i : part.ranked) {
      ASSERT_TRUE(part.coefficients[i] == full.coefficients[i]);
      weakest_kept = std::min(weakest_kept, importance_full[i]);
    }
    std::vector<std::uint8_t> kept(full.coefficients.size(), 0);
    for (std::uint32_t i : part.ranked) kept[i] = 1;
    for (std::size_t i = full.hierarchy->vertex_count(0); i < kept.size(); ++i)
      if (!kept[i]) {
        ASSERT_TRUE(part.coefficients[i] == Vec3{});
        ASSERT_LE(importance_full[i], weakest_kept);
      }
  }
}

TEST(IswFormat, StatisticsMatchAnIndependentRecomputation) {
  const Encoded e = encode_sample(test::genus_slab(2), 3);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  const std::vector<RateDistortionRow> rows = rate_distortion(full, {20, 10, 5});
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_TRUE(rows.back().is_base);
  const std::vector<Vec3> reference = reconstruct(full, full.ranked.size());
  for (const RateDistortionRow& row : rows) {
    // Decode the file again at that percentage and compare the two meshes here.
    IswDecodeOptions options;
    options.max_percent = row.is_base ? 0 : row.percent;
    const IswDecoded part = decode_isw(e.bytes, "test.isw", options);
    std::vector<Vec3> points = part.coefficients;
    synthesize(*part.hierarchy, points);
    double sum = 0, worst = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double dx = points[i].x - reference[i].x, dy = points[i].y - reference[i].y, dz = points[i].z - reference[i].z;
      sum += dx * dx + dy * dy + dz * dz;
      worst = std::max(worst, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    EXPECT_NEAR(row.rms, std::sqrt(sum / points.size()), 1e-12) << row.percent;
    EXPECT_NEAR(row.max, worst, 1e-12) << row.percent;
    // A reader needs no more than the bytes the row reports to decode it.
    if (!row.is_base) {
      IswDecodeOptions prefix_options;
      prefix_options.max_coefficients = row.wavelet_coefficients;
      const IswDecoded prefix = decode_isw(e.bytes.substr(0, row.bytes), "prefix.isw", prefix_options);
      EXPECT_EQ(prefix.ranked.size(), std::min<std::size_t>(row.wavelet_coefficients, full.ranked.size()));
    }
  }
  // Errors grow as fewer coefficients are kept.
  EXPECT_LE(rows[0].rms, rows[1].rms);
  EXPECT_LE(rows[1].rms, rows[2].rms);
  EXPECT_LE(rows[2].rms, rows[3].rms);
}

TEST(IswFormat, StatisticsTakeKnownErrorsOfEveryCoefficientOnlyForFullRows) {
  const Encoded e = encode_sample(test::genus_slab(2), 3);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  const std::vector<Vec3>& reference = e.surface.fine;
  // What convert measures before encoding: the quantized coefficients, synthesized.
  std::vector<Vec3> quantized = quantize_coefficients(*full.hierarchy, e.surface.coefficients, full.step, full.class_weights);
  EXPECT_EQ(quantized, full.coefficients);
  synthesize(*full.hierarchy, quantized);
  const PointErrors measured = point_errors(quantized, reference, quantized.size());
  const std::vector<double> percents{100, 20, 5};
  const std::vector<RateDistortionRow> computed = rate_distortion(full, percents, &reference);
  const std::vector<RateDistortionRow> reused = rate_distortion(full, percents, &reference, &measured);
  ASSERT_EQ(computed.size(), reused.size());
  for (std::size_t r = 0; r < computed.size(); ++r) {
    EXPECT_EQ(computed[r].rms, reused[r].rms) << r;
    EXPECT_EQ(computed[r].max, reused[r].max) << r;
    EXPECT_EQ(computed[r].bytes, reused[r].bytes) << r;
    EXPECT_EQ(computed[r].kept, reused[r].kept) << r;
  }
  // Rows that drop coefficients never take the given errors.
  const PointErrors wrong{123.0, 456.0};
  const std::vector<RateDistortionRow> misled = rate_distortion(full, percents, &reference, &wrong);
  EXPECT_EQ(misled[0].rms, 123.0);
  for (std::size_t r = 1; r < misled.size(); ++r) EXPECT_EQ(misled[r].rms, computed[r].rms) << r;
}

TEST(IswFormat, EncodingIsTheSameOnOneThread) {
  const test::CodedSurface s = test::make_coded_surface(test::genus_slab(3), 3, 0.05, 4);
  IswEncodeOptions options;
  options.major_version = 1;
  options.step = 1e-3;
  const std::string parallel = encode_isw(*s.hierarchy, s.coefficients, sample_metadata(), options);
  std::string serial;
  {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    serial = encode_isw(*s.hierarchy, s.coefficients, sample_metadata(), options);
  }
  EXPECT_EQ(parallel, serial);
  EXPECT_GT(decode_isw(parallel, "test.isw").chunks_total, 3u);
}

TEST(IswFormat, ManyCoefficientsAreRankedByImportanceThenIndex) {
  // Enough coefficients for the ranking's radix sort (the small files of the
  // other tests take the comparison sort).
  const test::CodedSurface s = test::make_coded_surface(test::genus_slab(3), 5, 0.05, 6);
  IswEncodeOptions options;
  options.major_version = 1;
  options.step = 1e-6;
  const IswDecoded d = decode_isw(encode_isw(*s.hierarchy, s.coefficients, sample_metadata(), options), "test.isw");
  ASSERT_GT(d.ranked.size(), 1u << 16);
  const std::vector<double> weight = importance(*d.hierarchy, d.coefficients, d.class_weights);
  for (std::size_t r = 1; r < d.ranked.size(); ++r) {
    const std::uint32_t a = d.ranked[r - 1], b = d.ranked[r];
    ASSERT_TRUE(weight[a] > weight[b] || (weight[a] == weight[b] && a < b)) << r;
  }
}

TEST(IswFormat, EveryTruncationFailsCleanlyOrDecodesTheCompleteChunks) {
  const Encoded e = encode_sample(test::cube(), 2, 1e-2);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  ASSERT_GT(full.chunks_total, 1u);
  std::size_t partial = 0, errors = 0;
  for (std::size_t length = 0; length < e.bytes.size(); ++length) {
    try {
      const IswDecoded d = decode_isw(e.bytes.substr(0, length), "cut.isw");
      // Only a cut inside the coefficient chunks decodes, and it says so.
      ++partial;
      EXPECT_TRUE(d.truncated) << length;
      EXPECT_FALSE(d.truncation_note.empty());
      EXPECT_LE(d.chunks_decoded, d.chunks_total);
      for (std::uint32_t i : d.ranked) EXPECT_TRUE(d.coefficients[i] == full.coefficients[i]);
    } catch (const Error& error) {
      ++errors;
      const std::string message = error.what();
      EXPECT_EQ(error.kind(), ErrorKind::Format) << message;
      EXPECT_NE(message.find("cut.isw"), std::string::npos);
      // It says where the file ends: in its header or at a named section.
      bool named = message.find("file header") != std::string::npos || message.find("empty file") != std::string::npos;
      for (const char* tag : {"META", "BASE", "QUAN", "BPTS", "CHNK", "END"})
        named = named || message.find(std::string("section ") + tag) != std::string::npos;
      EXPECT_TRUE(named) << length << ": " << message;
    }
  }
  EXPECT_GT(partial, 0u);
  EXPECT_GT(errors, 0u);
}

TEST(IswFormat, CorruptedBytesNeverCrash) {
  const Encoded e = encode_sample(test::pentagonal_prism(), 2, 1e-2);
  std::mt19937 rng(1);
  std::size_t rejected = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::string bytes = e.bytes;
    const int flips = 1 + static_cast<int>(rng() % 3);
    for (int k = 0; k < flips; ++k) bytes[rng() % bytes.size()] ^= static_cast<char>(1 + rng() % 255);
    try {
      decode_isw(bytes, "corrupt.isw");
    } catch (const Error&) {
      ++rejected;
    }
  }
  // CRC-32 catches every corruption of section contents.
  EXPECT_GT(rejected, 2900u);
}

TEST(IswFormat, HostileHeadersAreRejectedBeforeAllocating) {
  const Encoded e = encode_sample(test::cube(), 1, 1e-2);
  // Bad magic and unknown major version.
  std::string bad = e.bytes;
  bad[1] = 'X';
  EXPECT_THROW(decode_isw(bad, "x.isw"), Error);
  bad = e.bytes;
  bad[8] = 9;
  try {
    decode_isw(bad, "x.isw");
    ADD_FAILURE();
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::Unsupported);
  }
  // A section claiming an enormous size.
  bad = e.bytes;
  const std::uint64_t huge = 1ull << 62;
  std::memcpy(bad.data() + 16 + 4, &huge, 8);
  EXPECT_THROW(decode_isw(bad, "x.isw"), Error);
}

// `bytes` with a section `tag` holding `payload` (valid sizes and CRCs)
// inserted before the section at index `before` (0: META).
std::string with_section_inserted(const std::string& bytes, std::size_t before, const std::string& tag,
                                  const std::string& payload) {
  std::vector<std::string> parts = test::split_sections(bytes);
  parts.insert(parts.begin() + 1 + static_cast<std::ptrdiff_t>(before), test::make_section(tag, payload));
  return test::join(parts);
}

TEST(IswFormat, SectionsOfALaterMinorVersionAreSkipped) {
  // docs/FORMAT.md: readers accept any minor version, which may add sections.
  const Encoded e = encode_sample(test::cube(), 2, 1e-2);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  for (const std::size_t before : {std::size_t{0}, std::size_t{2}, std::size_t{4}, std::size_t{5}}) {
    SCOPED_TRACE(before);
    const IswDecoded d = decode_isw(with_section_inserted(e.bytes, before, "NEWS", "future payload"), "new.isw");
    EXPECT_FALSE(d.truncated);
    ASSERT_EQ(d.coefficients.size(), full.coefficients.size());
    for (std::size_t i = 0; i < d.coefficients.size(); ++i) ASSERT_TRUE(d.coefficients[i] == full.coefficients[i]);
    EXPECT_EQ(d.sections.size(), full.sections.size() + 1);
  }
  // A known section out of its place stays an error.
  EXPECT_THROW(decode_isw(with_section_inserted(e.bytes, 5, "QUAN", "x"), "bad.isw"), Error);
  // The header's version is reported as the file has it.
  std::string minor5 = e.bytes;
  minor5[10] = 5;
  EXPECT_EQ(decode_isw(minor5, "minor.isw").minor_version, 5);
  EXPECT_EQ(decode_isw(minor5, "minor.isw").major_version, 1);
}

TEST(IswFormat, BaseMeshTheHierarchyCannotRefineIsAFormatErrorNamingTheSection) {
  // A disk of 65,536 triangles around vertex 0: a hierarchy of 0 levels takes
  // it, but refinement stores a vertex's faces in 16 bits. The encoder cannot
  // write such a file with levels (it builds the hierarchy first), so the
  // 0-level file's QUAN section is made to claim one level, with valid CRCs.
  constexpr std::uint32_t kRing = 65536;
  PolygonMesh fan;
  fan.positions.push_back({0, 0, 0});
  for (std::uint32_t i = 0; i < kRing; ++i) {
    const double angle = 2 * 3.14159265358979323846 * i / kRing;
    fan.positions.push_back({std::cos(angle), std::sin(angle), 0});
  }
  for (std::uint32_t i = 0; i < kRing; ++i) fan.add_face({0u, 1 + i, 1 + (i + 1) % kRing});
  IswEncodeOptions options;
  options.major_version = 1;
  options.step = 1e-3;
  const std::string level0 = encode_isw(fan, 0, fan.positions, sample_metadata(), options);
  ASSERT_EQ(decode_isw(level0, "fan.isw").base.face_count(), kRing);
  std::string quan;  // step, levels, classes, per-class weights, coefficient count, chunk count
  const double weights[3] = {1, 1, 1};
  const std::uint32_t levels = 1, classes = 3, chunks = 0;
  const std::uint64_t coefficients = 0;
  quan.append(reinterpret_cast<const char*>(&options.step), 8);
  quan.append(reinterpret_cast<const char*>(&levels), 4);
  quan.append(reinterpret_cast<const char*>(&classes), 4);
  quan.append(reinterpret_cast<const char*>(weights), sizeof weights);
  quan.append(reinterpret_cast<const char*>(&coefficients), 8);
  quan.append(reinterpret_cast<const char*>(&chunks), 4);
  const std::string level1 = test::with_section_payload(level0, "QUAN", quan);
  try {
    decode_isw(level1, "fan.isw");
    ADD_FAILURE() << "decoded a base mesh that cannot be refined";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::Format);
    const std::string message = error.what();
    EXPECT_NE(message.find("fan.isw"), std::string::npos) << message;
    EXPECT_NE(message.find("BASE"), std::string::npos) << message;
    EXPECT_NE(message.find("65535"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace isowave
