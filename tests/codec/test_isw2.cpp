// The .isw 2.0 and 2.1 files (embedded bit planes in local frames, issue #34): the
// quantizer's bounds on every coefficient, at the whole stream and at every
// prefix; error falling plane by plane; file cuts and stream limits that
// agree; the encoder's size limit and rate table; `--percent` on top of the
// stream; hostile packets, damaged sections and sections out of order; 2.1
// (non-normal flags) decoding as 2.0 does.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include <gtest/gtest.h>

#include "codec_test_data.h"
#include "isw_test_sections.h"
#include "isowave/codec/base_order.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/error.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {
namespace {

using test::sample_metadata;

struct Encoded {
  test::CodedSurface surface;
  IswEncodeOptions options;
  std::string bytes;
};

Encoded encode_sample(PolygonMesh base, int levels, double step, double tangential_factor = 4,
                      int minor_version = kIswMinorVersion) {
  Encoded e{test::make_coded_surface(std::move(base), levels, 0.05, 9), {}, {}};
  e.options.step = step;
  e.options.tangential_factor = tangential_factor;
  e.options.minor_version = minor_version;
  e.bytes = encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), e.options);
  return e;
}

// The largest error of a value of class c whose components are known to
// within `steps` of its (normal) step: the tangential ones k times that,
// base control points in world axes.
double bound(const IswDecoded& d, int cls, double steps, double tangential_factor) {
  const double step = steps * d.step / d.class_weights[static_cast<std::size_t>(cls)];
  return (cls == 0 ? std::sqrt(3.0) : std::sqrt(1 + 2 * tangential_factor * tangential_factor)) * step * (1 + 1e-9);
}

// Sum of squared, weighted errors of the decoded values.
double weighted_error(const IswDecoded& d, const std::vector<Vec3>& truth) {
  double sum = 0;
  const CoefficientClasses classes(*d.hierarchy);
  for (std::size_t i = 0; i < truth.size(); ++i)
    sum += squared_norm(d.coefficients[i] - truth[i]) * std::pow(d.class_weights[static_cast<std::size_t>(classes.of(i))], 2);
  return sum;
}

TEST(IswFormat2, WholeStreamIsWithinTheDeadZoneQuantizersBound) {
  for (const double k : {1.0, 4.0, 16.0}) {
    const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-3, k);
    const IswDecoded d = decode_isw(e.bytes, "test.isw");
    EXPECT_EQ(d.major_version, 2);
    EXPECT_FALSE(d.truncated);
    EXPECT_EQ(d.stream.planes_decoded, d.stream.planes);
    const CoefficientClasses classes(*d.hierarchy);
    for (std::size_t i = 0; i < d.coefficients.size(); ++i)
      ASSERT_LE(norm(d.coefficients[i] - e.surface.coefficients[i]), bound(d, classes.of(i), 1, k)) << k << " " << i;
    // The base mesh decoded is the base control points decoded.
    for (std::size_t v = 0; v < d.base.vertex_count(); ++v) ASSERT_EQ(d.base.positions[v], d.coefficients[v]);
  }
}

TEST(IswFormat2, EveryPrefixDecodesWithinTheBoundOfItsLastCompletePlane) {
  const Encoded e = encode_sample(test::cube(), 2, 1e-3);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  const CoefficientClasses classes(*full.hierarchy);
  ASSERT_GT(full.stream.planes, 4);
  for (std::uint64_t n = full.stream.offset; n <= e.bytes.size(); ++n) {
    const IswDecoded d = decode_isw(e.bytes.substr(0, n), "cut.isw");
    ASSERT_EQ(d.coefficients.size(), full.coefficients.size());
    // Planes above the last complete one are known (all magnitudes are
    // below 2^(top + 1)): each component within 2^low steps.
    const int low = full.stream.top_plane + 1 - d.stream.planes_decoded;
    for (std::size_t i = 0; i < d.coefficients.size(); ++i)
      ASSERT_LE(norm(d.coefficients[i] - e.surface.coefficients[i]),
                bound(d, classes.of(i), std::ldexp(1.0, low), e.options.tangential_factor))
          << "prefix " << n << " value " << i;
    // The same prefix of the stream alone decodes the same values.
    IswDecodeOptions limit;
    limit.max_stream_bytes = n > full.stream.offset ? n - full.stream.offset : 0;
    if (n >= full.stream.offset + full.stream.bytes) continue;
    const IswDecoded same = decode_isw(e.bytes, "limit.isw", limit);
    ASSERT_EQ(same.coefficients, d.coefficients) << n;
  }
}

TEST(IswFormat2, ErrorFallsAtEveryPlaneBoundary) {
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-4);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  double previous = INFINITY;
  for (std::size_t k = 0; k < full.stream.plane_ends.size(); ++k) {
    IswDecodeOptions limit;
    limit.max_stream_bytes = full.stream.plane_ends[k];
    const IswDecoded d = decode_isw(e.bytes, "limit.isw", limit);
    // A plane's empty packets at the end of the bytes are complete too.
    EXPECT_EQ(d.stream.planes_decoded, static_cast<int>(k + 1)) << limit.max_stream_bytes;
    const double error = weighted_error(d, e.surface.coefficients);
    EXPECT_LT(error, previous) << limit.max_stream_bytes;
    previous = error;
  }
}

TEST(IswFormat2, PlaneValuesAreWhatEachPlaneEndDecodesTo) {
  // Two groups of the tree (2^17 nodes each): each plane is four packets.
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-4);
  for (const std::uint64_t max_bytes : {std::uint64_t{0}, std::uint64_t{e.bytes.size() / 2}}) {
    SCOPED_TRACE("max_bytes " + std::to_string(max_bytes));
    IswEncodeOptions options = e.options;
    options.max_bytes = max_bytes;
    IswPlaneValues planes;
    const std::string file = encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), options, planes);
    EXPECT_EQ(file, max_bytes ? encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), options)
                              : e.bytes);
    // The planes the file holds whole.
    std::vector<std::uint64_t> whole = stream_plane_ends(e.bytes);
    const IswDecoded cut = decode_isw(file, "cut.isw");
    whole.resize(static_cast<std::size_t>(cut.stream.planes_decoded));
    ASSERT_EQ(planes.plane_ends(), whole);
    ASSERT_GE(planes.plane_ends().size(), 5u);
    std::vector<Vec3> values;
    for (std::size_t k = 0; k < planes.plane_ends().size(); ++k) {
      IswDecodeOptions limit;
      limit.max_stream_bytes = planes.plane_ends()[k];
      planes.coefficients_at(k, values);
      ASSERT_EQ(values, decode_isw(file, "limit.isw", limit).coefficients) << "plane end " << k;
    }
  }
  IswEncodeOptions version1 = e.options;
  version1.major_version = 1;
  IswPlaneValues planes;
  EXPECT_THROW(encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), version1, planes), Error);
}

TEST(IswFormat2, SizeLimitCutsTheStreamAndRateTableChoosesThePrefix) {
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-4);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  IswEncodeOptions options = e.options;
  options.max_bytes = full.stream.offset + full.stream.bytes / 3;
  const std::string cut = encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), options);
  EXPECT_LE(cut.size(), options.max_bytes);
  EXPECT_GT(cut.size(), options.max_bytes - 16);
  const IswDecoded d = decode_isw(cut, "cut.isw");
  EXPECT_FALSE(d.truncated);  // cut by its encoder, not damaged
  EXPECT_LT(d.stream.planes_decoded, full.stream.planes);
  options.max_bytes = 100;
  EXPECT_THROW(encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), options), Error);

  // A rate table: decode --max-error takes the first row within the error.
  IswRewrite rewrite;
  rewrite.rate_table = {{full.stream.plane_ends[2], 0.3}, {full.stream.plane_ends[4], 0.1}, {full.stream.bytes, 0.01}};
  const std::string tabled = rewrite_isw(e.bytes, rewrite);
  IswDecodeOptions within;
  within.max_error_cells = 0.2 / 0.05;  // sample_metadata()'s cell
  const IswDecoded chosen = decode_isw(tabled, "tabled.isw", within);
  EXPECT_EQ(chosen.stream.rate_table.size(), 3u);
  EXPECT_EQ(chosen.stream.decoded, full.stream.plane_ends[4]);
  within.max_error_cells = 0.001 / 0.05;  // no row reaches it: the whole stream
  EXPECT_EQ(decode_isw(tabled, "tabled.isw", within).stream.decoded, full.stream.bytes);
}

std::size_t nonzero_wavelets(const IswDecoded& d) {
  std::size_t n = 0;
  for (std::size_t i = d.hierarchy->vertex_count(0); i < d.coefficients.size(); ++i) n += d.coefficients[i] == Vec3{} ? 0 : 1;
  return n;
}

// PCNT as docs/FORMAT.md gives it: u32 rows, a u64 each.
std::vector<std::uint64_t> plane_counts(const std::string& file) {
  const std::string payload = test::payload_of(file, "PCNT");
  std::uint32_t rows = 0;
  std::memcpy(&rows, payload.data(), 4);
  std::vector<std::uint64_t> counts(rows);
  for (std::uint32_t k = 0; k < rows; ++k) std::memcpy(&counts[k], payload.data() + 4 + 8 * k, 8);
  return counts;
}

// What a coefficient limit `keep` reads (docs/FORMAT.md, "Percentages"),
// with the counts found by decoding each plane end: the fewest planes past
// the one that makes the keep-th coefficient significant whose quantization
// error (keep + base) 4^p is at most a tenth of the dropped coefficients'
// 2.25 x 4^b each.
IswDecoded prefix_for(const std::string& file, std::size_t keep) {
  const IswDecoded full = decode_isw(file, "test.isw");
  const std::vector<std::uint64_t>& ends = full.stream.plane_ends;
  IswDecodeOptions options;
  options.order = IswOrder::Index;
  std::vector<double> counts;
  for (const std::uint64_t end : ends) {
    options.max_stream_bytes = end;
    counts.push_back(static_cast<double>(nonzero_wavelets(decode_isw(file, "test.isw", options))));
  }
  const auto plane_of = [&](std::size_t k) { return full.stream.top_plane - static_cast<int>(k); };
  std::size_t first = 0;
  while (first < counts.size() && counts[first] < static_cast<double>(keep)) ++first;
  options.max_stream_bytes = UINT64_MAX;
  if (first < counts.size()) {
    double dropped = 2.25 * (counts[first] - static_cast<double>(keep)) * std::pow(4.0, plane_of(first));
    for (std::size_t k = first + 1; k < counts.size(); ++k)
      dropped += 2.25 * (counts[k] - counts[k - 1]) * std::pow(4.0, plane_of(k));
    const double kept = static_cast<double>(keep + full.hierarchy->vertex_count(0));
    for (std::size_t k = first + 1; k + 1 < counts.size(); ++k)
      if (kept * std::pow(4.0, plane_of(k)) <= dropped / 10) {
        options.max_stream_bytes = ends[k];
        break;
      }
  }
  return decode_isw(file, "test.isw", options);
}

TEST(IswFormat2, PlaneCountsAreTheNonZeroCoefficientsAtEachPlaneEnd) {
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-4);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  const std::vector<std::uint64_t> counts = plane_counts(e.bytes);
  ASSERT_EQ(counts.size(), full.stream.plane_ends.size());
  ASSERT_EQ(counts.size(), static_cast<std::size_t>(full.stream.top_plane + 1));
  IswDecodeOptions options;
  options.order = IswOrder::Index;
  for (std::size_t k = 0; k < counts.size(); ++k) {
    options.max_stream_bytes = full.stream.plane_ends[k];
    EXPECT_EQ(counts[k], nonzero_wavelets(decode_isw(e.bytes, "test.isw", options))) << "plane end " << k;
  }
  EXPECT_EQ(counts.back(), full.coefficients_total);
}

TEST(IswFormat2, PercentKeepsTheMostImportantOfThePlanesItNeeds) {
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-4);
  for (const double percent : {0.0, 3.0, 10.0, 40.0}) {
    IswDecodeOptions options;
    options.max_percent = percent;
    const IswDecoded d = decode_isw(e.bytes, "test.isw", options);
    const std::size_t keep = coefficients_for_percent(*d.hierarchy, percent);
    ASSERT_EQ(d.ranked.size(), keep);
    const IswDecoded reference = prefix_for(e.bytes, keep);
    EXPECT_EQ(d.stream.decoded, reference.stream.decoded) << percent << "%";
    EXPECT_EQ(stream_bytes_for_keep(decode_isw(e.bytes, "test.isw"), keep), d.stream.decoded) << percent << "%";
    const CoefficientClasses classes(*d.hierarchy);
    const auto importance = [&](std::size_t i) {
      return norm(reference.coefficients[i]) * d.class_weights[static_cast<std::size_t>(classes.of(i))];
    };
    double least_kept = INFINITY;
    std::vector<std::uint8_t> kept(d.coefficients.size(), 0);
    for (std::uint32_t i : d.ranked) {
      kept[i] = 1;
      least_kept = std::min(least_kept, importance(i));
      ASSERT_EQ(d.coefficients[i], reference.coefficients[i]);
    }
    for (std::size_t i = classes.base(); i < d.coefficients.size(); ++i)
      if (!kept[i]) {
        ASSERT_LE(importance(i), least_kept) << i;
        ASSERT_EQ(d.coefficients[i], Vec3{}) << i;
      }
  }
  // Without PCNT (as 2.1 files) a limit ranks the whole stream.
  IswDecodeOptions options;
  options.max_percent = 10;
  const std::string without = test::join([&] {
    std::vector<std::string> parts = test::split_sections(e.bytes);
    parts.erase(std::remove_if(parts.begin(), parts.end(), [](const std::string& p) { return test::section_tag(p) == "PCNT"; }),
                parts.end());
    return parts;
  }());
  EXPECT_EQ(decode_isw(without, "test.isw", options).stream.decoded, decode_isw(e.bytes, "test.isw").stream.decoded);
}

TEST(IswFormat2, PlaneCountsThatDisagreeWithTheStreamAreFormatErrors) {
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-4);
  const std::vector<std::uint64_t> counts = plane_counts(e.bytes);
  const auto with_counts = [&](const std::vector<std::uint64_t>& rows) {
    std::string payload(4, '\0');
    const auto n = static_cast<std::uint32_t>(rows.size());
    std::memcpy(payload.data(), &n, 4);
    for (const std::uint64_t r : rows) payload.append(reinterpret_cast<const char*>(&r), 8);
    return test::with_section_payload(e.bytes, "PCNT", payload);
  };
  IswDecodeOptions options;  // with or without a limit
  std::vector<std::uint64_t> decreasing = counts, short_table = counts, too_many = counts;
  std::swap(decreasing[1], decreasing.back());
  short_table.pop_back();
  too_many.back() = 1u << 30;
  for (const auto& [rows, what] : {std::pair{decreasing, "decrease"}, std::pair{short_table, "does not match PCNT"},
                                   std::pair{too_many, "does not match PCNT"}}) {
    for (const double percent : {100.0, 10.0}) {
      options.max_percent = percent;
      try {
        decode_isw(with_counts(rows), "test.isw", options);
        ADD_FAILURE() << what;
      } catch (const Error& error) {
        EXPECT_EQ(error.kind(), ErrorKind::Format);
        EXPECT_NE(std::string(error.what()).find(what), std::string::npos) << error.what();
      }
    }
  }
}

TEST(IswFormat2, PercentKeepsWhatTheChosenOracleKeeps) {
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-4);
  const std::size_t keep = coefficients_for_percent(*decode_isw(e.bytes, "test.isw").hierarchy, 10);
  const IswDecoded read = prefix_for(e.bytes, keep);
  IswDecodeOptions options;
  options.max_percent = 10;
  // Magnitude: no kept coefficient smaller than one left out.
  options.oracle = Oracle::Magnitude;
  const IswDecoded by_magnitude = decode_isw(e.bytes, "test.isw", options);
  ASSERT_EQ(by_magnitude.ranked.size(), keep);
  double least_kept = INFINITY, most_dropped = 0;
  for (std::size_t i = read.hierarchy->vertex_count(0); i < read.coefficients.size(); ++i)
    if (by_magnitude.coefficients[i] == Vec3{}) most_dropped = std::max(most_dropped, norm(read.coefficients[i]));
    else least_kept = std::min(least_kept, norm(read.coefficients[i]));
  EXPECT_LE(most_dropped, least_kept);
  // Greedy: keep_greedy's choice over what was read.
  options.oracle = Oracle::Greedy;
  const IswDecoded by_greedy = decode_isw(e.bytes, "test.isw", options);
  std::vector<Vec3> expected = read.coefficients;
  EXPECT_EQ(by_greedy.ranked, keep_greedy(*read.hierarchy, expected, keep));
  EXPECT_EQ(by_greedy.coefficients, expected);
}

// Whatever its packets hold, a decode keeps every component below 2^(top + 1)
// steps, as the plane decoder alone does (test_bitplane_coder.cpp): from the
// frame base for base control points, from zero for the others.
TEST(IswFormat2, RandomPacketsOfAValidFileDecodeWithinTheTopPlanesBound) {
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-4);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  const CoefficientClasses classes(*full.hierarchy);
  IswDecodeOptions no_planes;
  no_planes.max_stream_bytes = 0;
  const std::vector<Vec3> frame_base = decode_isw(e.bytes, "base.isw", no_planes).base.positions;
  const double steps = std::ldexp(1.0, full.stream.top_plane + 1);
  // The packets follow the PLNS header and the packet table.
  const IswSectionInfo& planes = full.sections[full.sections.size() - 2];
  ASSERT_EQ(planes.tag, "PLNS");
  std::string payload = test::payload_of(e.bytes, "PLNS");
  const std::size_t first = static_cast<std::size_t>(full.stream.offset - planes.offset - 16);
  ASSERT_EQ(payload.size() - first, full.stream.bytes);
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    for (std::size_t k = first; k < payload.size(); ++k) payload[k] = static_cast<char>(rng() & 0xFF);
    const IswDecoded d = decode_isw(test::with_section_payload(e.bytes, "PLNS", payload), "noise.isw");
    ASSERT_EQ(d.stream.top_plane, full.stream.top_plane);
    for (std::size_t i = 0; i < d.coefficients.size(); ++i) {
      const int cls = classes.of(i);
      const Vec3 origin = cls == 0 ? frame_base[i] : Vec3{};
      ASSERT_LE(norm(d.coefficients[i] - origin), bound(d, cls, steps, e.options.tangential_factor))
          << "trial " << trial << " value " << i;
    }
  }
}

TEST(IswFormat2, DamagedSectionsAreFormatErrorsAndCutHeadersToo) {
  const Encoded e = encode_sample(test::cube(), 2, 1e-3);
  const IswDecoded full = decode_isw(e.bytes, "test.isw");
  // Cut before the base control points are whole: an error; after them the
  // base mesh alone decodes.
  const IswSectionInfo& base_points = full.sections[3];
  ASSERT_EQ(base_points.tag, "BPTS");
  for (std::uint64_t n = 0; n < base_points.offset + base_points.bytes; n += 7)
    EXPECT_THROW(decode_isw(e.bytes.substr(0, n), "cut.isw"), Error) << n;
  // CRC-32s cover every section's tag, size and payload, and PLNS's flags
  // name the planes' coding, which the header's minor version (bytes 10 and
  // 11, outside every CRC) must agree with: any changed byte is an error.
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    std::string bytes = e.bytes;
    const std::size_t at = trial < 4 ? 10 + static_cast<std::size_t>(trial % 2) : rng() % bytes.size();
    bytes[at] ^= static_cast<char>(trial < 4 ? trial / 2 + 1 : 1 + rng() % 255);
    try {
      decode_isw(bytes, "damaged.isw");
      ADD_FAILURE() << "byte " << at << " changed, and the file decoded";
    } catch (const Error& error) {
      EXPECT_TRUE(error.kind() == ErrorKind::Format || error.kind() == ErrorKind::Unsupported) << error.what();
    }
  }
}

// Expects a one-line Error(Format) naming the file and `section`, from a
// whole decode and, with `headers_too`, from one of the headers (which lists
// the other sections).
void expect_format_error(const std::string& bytes, const std::string& section, const std::string& what,
                         bool headers_too = true) {
  for (const bool headers_only : {false, true}) {
    if (headers_only && !headers_too) continue;
    SCOPED_TRACE(what + (headers_only ? ", headers only" : ""));
    IswDecodeOptions options;
    options.headers_only = headers_only;
    try {
      decode_isw(bytes, "order.isw", options);
      ADD_FAILURE() << "decoded";
    } catch (const Error& error) {
      const std::string message = error.what();
      EXPECT_EQ(error.kind(), ErrorKind::Format) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      EXPECT_EQ(message.rfind("order.isw: section ", 0), 0u) << message;
      EXPECT_NE(message.find("section " + section), std::string::npos) << message;
    }
  }
}

// docs/FORMAT.md: after BPTS, optionally RDTB, then GIDX (2.2), optionally
// PCNT, PLNS and END, each once. Any other order or repetition is an error,
// and costs no second decode; a 2.2 stream without its GIDX is one too.
TEST(IswFormat2, RepeatedOrMisplacedStreamSectionsAreFormatErrors) {
  const Encoded e = encode_sample(test::cube(), 2, 1e-3);
  IswRewrite rewrite;
  rewrite.rate_table = {{0, 0.5}};
  std::vector<std::string> parts = test::split_sections(rewrite_isw(e.bytes, rewrite));
  ASSERT_EQ(parts.size(), 10u);  // the file header, META, BASE, QUAN, BPTS, RDTB, GIDX, PCNT, PLNS, END
  const std::string counts = parts[7];
  parts.erase(parts.begin() + 7);
  const std::string head = parts[0] + parts[1] + parts[2] + parts[3] + parts[4];
  const std::string &rdtb = parts[5], &index = parts[6], &planes = parts[7], &end = parts[8];
  ASSERT_EQ(test::section_tag(rdtb) + test::section_tag(index) + test::section_tag(counts) + test::section_tag(planes) +
                test::section_tag(end),
            "RDTBGIDXPCNTPLNSEND ");
  EXPECT_EQ(decode_isw(head + index + counts + planes + end, "counts.isw").coefficients,
            decode_isw(head + index + planes + end, "no_counts.isw").coefficients);
  expect_format_error(head + counts + index + planes + end, "GIDX", "PCNT before GIDX");
  expect_format_error(head + index + counts + counts + planes + end, "PCNT", "PCNT twice");
  expect_format_error(head + index + planes + counts + end, "PCNT", "PCNT after PLNS");
  // Complete and empty: top plane -1, 2.1's coding, 1 group, 3 segments, no packets.
  const std::string no_packets = test::make_section("PLNS", std::string("\xff\x02\x01\x03\x00", 5));
  const std::string unknown = test::make_section("NEWS", "a later minor version's");

  const IswDecoded full = decode_isw(head + index + planes + end, "full.isw");
  for (const std::string& valid :
       {head + rdtb + index + planes + end, head + unknown + index + unknown + planes + unknown + end})
    EXPECT_EQ(decode_isw(valid, "valid.isw").coefficients, full.coefficients);

  expect_format_error(head + index + planes + planes + end, "PLNS", "PLNS twice");
  expect_format_error(head + rdtb + index + planes + planes + planes + end, "PLNS", "PLNS three times");
  expect_format_error(head + index + planes + no_packets + end, "PLNS", "an empty PLNS after the stream");
  expect_format_error(head + index + planes + unknown + planes.substr(0, planes.size() / 2), "PLNS",
                      "a second PLNS, cut");
  expect_format_error(head + index + planes + rdtb + end, "RDTB", "RDTB after PLNS");
  expect_format_error(head + index + rdtb + planes + end, "RDTB", "RDTB after GIDX");
  expect_format_error(head + rdtb + rdtb + index + planes + end, "RDTB", "RDTB twice");
  expect_format_error(head + index + index + planes + end, "GIDX", "GIDX twice");
  expect_format_error(head + planes + index + end, "PLNS", "GIDX after PLNS (PLNS lacks it)", false);
  expect_format_error(head + planes + end, "PLNS", "a 2.2 PLNS without GIDX", false);
  expect_format_error(head + rdtb + index + end, "END", "no PLNS");
  expect_format_error(head + end + planes, "END", "END before PLNS");
  expect_format_error(head + index + planes + parts[4] + end, "BPTS", "BPTS in the stream");
}

// docs/FORMAT.md, PLNS: LEB128 values of at most 64 bits. The group count
// (1) written in ten bytes decodes as in one; ten bytes holding 2^64 + 1 are
// an error, not 1 wrapped around.
TEST(IswFormat2, PacketTableValuesOf64BitsOrMoreAreFormatErrors) {
  const Encoded e = encode_sample(test::cube(), 2, 1e-3);
  const std::string planes = test::payload_of(e.bytes, "PLNS");
  ASSERT_EQ(planes[2], 1);  // top plane, flags, then one group in one byte
  const auto with_groups = [&](char last) {
    const std::string groups = "\x81" + std::string(8, '\x80') + last;  // 1 + last x 2^63
    return test::with_section_payload(e.bytes, "PLNS", planes.substr(0, 2) + groups + planes.substr(3));
  };
  EXPECT_EQ(decode_isw(with_groups('\x00'), "long.isw").coefficients, decode_isw(e.bytes, "test.isw").coefficients);
  expect_format_error(with_groups('\x02'), "PLNS", "2^64 + 1", false);
  expect_format_error(with_groups('\x7f'), "PLNS", "127 x 2^63 + 1", false);
}

// The packet count is checked against the bytes left before the table is
// read (or allocated): every size takes a byte at least. The largest table
// the counts allow (32 planes, 32 segments, 64 groups: 65,536 sizes) in 100
// bytes is an error; cut by the file's end, the stream holds no packet.
TEST(IswFormat2, PacketCountBeyondTheBytesLeftIsRejectedBeforeTheTable) {
  const Encoded e = encode_sample(test::cube(), 2, 1e-3, 4, 1);
  const std::string header("\x1f\x02\x40\x20\x80\x80\x04", 7);  // top plane 31, 2.1's coding, G 64, S 32, P 2^16
  const std::string file = test::with_section_payload(e.bytes, "PLNS", header + std::string(100, '\x01'));
  expect_format_error(file, "PLNS", "65,536 packets in 100 bytes", false);
  try {
    decode_isw(file, "count.isw");
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("packet count"), std::string::npos) << error.what();
  }
  const std::size_t planes_end = file.size() - 20;  // before END
  const IswDecoded cut = decode_isw(file.substr(0, planes_end - 50), "cut.isw");
  EXPECT_TRUE(cut.truncated);
  EXPECT_EQ(cut.stream.decoded, 0u);
}

TEST(IswFormat2, EncodingIsDeterministicAndRejectsBadOptions) {
  const Encoded e = encode_sample(test::genus_slab(2), 3, 1e-3);
  EXPECT_EQ(encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), e.options), e.bytes);
  IswEncodeOptions bad = e.options;
  bad.tangential_factor = 0.5;
  EXPECT_THROW(encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), bad), Error);
  for (const int minor : {-1, kIswMinorVersion + 1}) {
    bad = e.options;
    bad.minor_version = minor;
    EXPECT_THROW(encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), bad), Error) << minor;
  }
  bad = e.options;
  bad.major_version = 3;
  EXPECT_THROW(encode_isw(*e.surface.hierarchy, e.surface.coefficients, sample_metadata(), bad), Error);
  std::vector<Vec3> infinite = e.surface.coefficients;
  infinite.back().x = INFINITY;
  EXPECT_THROW(encode_isw(*e.surface.hierarchy, infinite, sample_metadata(), e.options), Error);
}

// The canonical base order renumbers the hierarchy: the transform commutes
// with it, so the analysis of S^L(base), renumbered, gives the base points
// back (renumbered) and zero details; the coded base then costs a fraction
// of version 1's.
// A frame base other than the base (IswEncodeOptions::frame_base, the normal
// fit's): the frames are those of isw_frame_normals() of that base, so a
// coefficient along its normal decodes with no tangential part, and the base
// decodes to its own points.
TEST(IswFormat2, AFrameBaseSetsTheFramesAndTheBaseRefinesIt) {
  PolygonMesh base = test::genus_slab(2);
  test::jitter(base, 0.1, 11);
  const SubdivisionHierarchy h(base, 2);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<Vec3> frame_base = base.positions;
  for (Vec3& p : frame_base) p += Vec3{u(rng), u(rng), u(rng)};
  IswEncodeOptions options;
  options.step = 1e-4;
  options.frame_step = 0.02;
  options.frame_base = &frame_base;
  const std::vector<Vec3> normals = isw_frame_normals(h, frame_base, options.frame_step);
  std::vector<Vec3> coefficients(h.fine_vertex_count());
  std::copy(base.positions.begin(), base.positions.end(), coefficients.begin());
  for (std::size_t i = h.vertex_count(0); i < coefficients.size(); ++i) coefficients[i] = normals[i] * u(rng);
  const IswDecoded d = decode_isw(encode_isw(h, coefficients, sample_metadata(), options), "frame base");
  for (std::size_t i = 0; i < h.vertex_count(0); ++i)
    EXPECT_LT(norm(d.coefficients[i] - base.positions[i]), bound(d, 0, 1, options.tangential_factor)) << i;
  const CoefficientClasses classes(h);
  for (std::size_t i = h.vertex_count(0); i < coefficients.size(); ++i) {
    const Vec3& n = normals[i];
    const Vec3 c = d.coefficients[i];
    EXPECT_LT(norm(c - n * dot(n, c)), 1e-12) << i;  // no tangential part
    EXPECT_LT(std::abs(dot(n, c - coefficients[i])), bound(d, classes.of(i), 1, 1)) << i;
  }
  std::vector<Vec3> wrong(3);
  options.frame_base = &wrong;
  EXPECT_THROW(encode_isw(h, coefficients, sample_metadata(), options), Error);
}

// 2.1 against 2.0 on coefficients 90% of which lie along their frame
// normals: the same values at every plane end (cut files), fewer estimated
// tangential bits and a smaller file; each file keeps its minor version
// through rewrite_isw(), and a cut 2.0 file still decodes as 2.0.
TEST(IswFormat2, Minor21DecodesAs20WithFewerTangentialBits) {
  PolygonMesh base = test::genus_slab(2);
  test::jitter(base, 0.1, 12);
  const SubdivisionHierarchy h(base, 3);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(-0.1, 0.1), share(0, 1);
  IswEncodeOptions options;
  options.step = 1e-4;
  options.frame_step = 0.02;
  const std::vector<Vec3> normals = isw_frame_normals(h, base.positions, options.frame_step);
  std::vector<Vec3> coefficients(h.fine_vertex_count());
  std::copy(base.positions.begin(), base.positions.end(), coefficients.begin());
  for (std::size_t i = h.vertex_count(0); i < coefficients.size(); ++i) {
    const double scale = std::ldexp(1.0, -2 * h.level_of_index(i));
    coefficients[i] = share(rng) < 0.9 ? normals[i] * (u(rng) * scale) : Vec3{u(rng), u(rng), u(rng)} * scale;
  }
  std::string files[2];
  IswPlaneBits bits[2];
  for (int minor : {0, 1}) {
    options.minor_version = minor;
    IswPlaneValues planes;
    files[minor] = encode_isw(h, coefficients, sample_metadata(), options, planes);
    bits[minor] = planes.plane_bits();
  }
  EXPECT_LT(bits[1].tangential(), bits[0].tangential());
  EXPECT_LT(files[1].size(), files[0].size());
  const IswDecoded d0 = decode_isw(files[0], "2.0"), d1 = decode_isw(files[1], "2.1");
  EXPECT_EQ(d0.minor_version, 0);
  EXPECT_EQ(d1.minor_version, 1);
  ASSERT_EQ(d0.stream.plane_ends.size(), d1.stream.plane_ends.size());
  EXPECT_EQ(d0.coefficients, d1.coefficients);
  for (std::size_t k = 0; k < d0.stream.plane_ends.size(); ++k) {
    const IswDecoded c0 = decode_isw(files[0].substr(0, d0.stream.offset + d0.stream.plane_ends[k]), "cut 2.0");
    const IswDecoded c1 = decode_isw(files[1].substr(0, d1.stream.offset + d1.stream.plane_ends[k]), "cut 2.1");
    EXPECT_EQ(c0.stream.planes_decoded, static_cast<int>(k + 1));
    EXPECT_EQ(c0.coefficients, c1.coefficients) << "plane " << k;
  }
  for (int minor : {0, 1}) {
    const IswDecoded& whole = minor == 0 ? d0 : d1;
    const std::uint64_t half = whole.stream.bytes / 2;
    const IswDecoded cut = decode_isw(rewrite_isw(files[minor], IswRewrite{half, {}, nullptr}), "rewritten");
    EXPECT_EQ(cut.minor_version, minor);
    const IswDecoded prefix = decode_isw(files[minor].substr(0, whole.stream.offset + half), "prefix");
    EXPECT_EQ(cut.coefficients, prefix.coefficients) << minor;
  }
}

TEST(IswFormat2, CanonicalSurfaceIsTheSameSurfaceRenumbered) {
  PolygonMesh base = test::genus_slab(2);
  test::jitter(base, 0.1, 4);
  // A non-canonical order: faces reversed, each rotated by one corner.
  PolygonMesh shuffled;
  shuffled.positions = base.positions;
  for (std::size_t f = base.face_count(); f-- > 0;) {
    std::vector<std::uint32_t> face(base.face_begin(f), base.face_begin(f) + base.face_size(f));
    std::rotate(face.begin(), face.begin() + 1, face.end());
    shuffled.add_face(face.data(), face.size());
  }
  const auto hierarchy = std::make_shared<const SubdivisionHierarchy>(shuffled, 3);
  const std::vector<Vec3> fine = subdivide(*hierarchy, shuffled.positions);
  const CanonicalSurface canonical = canonical_surface(hierarchy, fine);
  ASSERT_NE(canonical.hierarchy, hierarchy);
  std::vector<Vec3> analysed = canonical.fine;
  analyze(*canonical.hierarchy, analysed);
  const std::size_t base_count = shuffled.vertex_count();
  auto less = [](const Vec3& a, const Vec3& b) { return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z))); };
  std::vector<Vec3> got(analysed.begin(), analysed.begin() + static_cast<std::ptrdiff_t>(base_count));
  std::vector<Vec3> want = shuffled.positions;
  std::sort(want.begin(), want.end(), less);
  for (Vec3& p : got)  // round off the analysis' last bits before matching
    for (const Vec3& w : want)
      if (norm(p - w) < 1e-9) p = w;
  std::sort(got.begin(), got.end(), less);
  EXPECT_EQ(got, want);
  for (std::size_t i = base_count; i < analysed.size(); ++i) ASSERT_LT(norm(analysed[i]), 1e-9) << i;
  // Canonical already: the same hierarchy back.
  EXPECT_EQ(canonical_surface(canonical.hierarchy, canonical.fine).hierarchy, canonical.hierarchy);
  // Its file's base section is the traversal coder's, far below version 1's.
  std::vector<Vec3> coefficients = canonical.fine;
  analyze(*canonical.hierarchy, coefficients);
  IswEncodeOptions options;
  const IswDecoded compact = decode_isw(encode_isw(*canonical.hierarchy, coefficients, sample_metadata(), options), "c");
  std::vector<Vec3> original = fine;
  analyze(*hierarchy, original);
  const IswDecoded loose = decode_isw(encode_isw(*hierarchy, original, sample_metadata(), options), "l");
  EXPECT_EQ(compact.sections[1].tag, "BASE");
  EXPECT_LT(2 * compact.sections[1].bytes, loose.sections[1].bytes);
  EXPECT_EQ(compact.base.face_vertices, canonical.hierarchy->base().face_vertices);
}

}  // namespace
}  // namespace isowave
