// Random access in version 2.2 files (issue #48, item 5; docs/FORMAT.md,
// "Version 2.2"): a region decode that reads the file in part equals the
// complete decode inside the region, reads exactly the headers and the
// packets of the groups it decodes (found by damaging each group's packets
// in turn), and checks what it reads against GIDX's CRCs; damaged,
// truncated and inconsistent indexes fail cleanly; the groups follow space.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <numeric>

#include "codec_test_data.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/region.h"
#include "isowave/core/error.h"
#include "isowave/transform/wavelet_transform.h"
#include "isw_test_sections.h"

namespace isowave {
namespace {

// A jittered 48 x 48 grid (unit edges) at 3 levels: about 150,000 tree
// nodes, so that 4,096-node groups give a few dozen of them.
struct Sample {
  test::CodedSurface surface;
  std::string bytes;
  std::string path;
};

const Sample& sample() {
  static const Sample s = [] {
    Sample out{test::make_coded_surface(test::quad_grid(48, 48), 3, 0.2, 11), {}, {}};
    IswEncodeOptions options;
    options.step = 1e-3;
    options.group_nodes = 4096;
    out.bytes = encode_isw(*out.surface.hierarchy, out.surface.coefficients, test::sample_metadata(), options);
    out.path = ::testing::TempDir() + "random_access.isw";
    write_isw(out.path, out.bytes, true);
    return out;
  }();
  return s;
}

std::string write_temp(const std::string& name, const std::string& bytes) {
  const std::string path = ::testing::TempDir() + name;
  write_isw(path, bytes, true);
  return path;
}

RegionOfInterest corner_box() { return parse_region("3,3,-10,12,12,10", false, "--roi"); }

IswDecoded read_region(const std::string& path, const RegionOfInterest& region) {
  IswDecodeOptions options;
  options.region = region;
  return read_isw(path, options);
}

// The region mesh of a region decode (a patch) against the one of the
// complete decode: the same faces and vertices, every vertex inside the
// region at the same point (up to rounding: the entries kept are found with
// weights on each hierarchy's own indices), every other one within the base's frame
// precision (a base control point of a group not decoded is BPTS's);
// returns the vertices inside.
std::size_t expect_same_region_mesh(const IswDecoded& full, const IswDecoded& part, const RegionOfInterest& region) {
  EXPECT_FALSE(full.patch);
  EXPECT_TRUE(part.patch);
  EXPECT_FALSE(part.hierarchy);
  EXPECT_TRUE(part.coefficients.empty());
  const PolygonMesh whole = region_mesh(full, region, 0), mine = region_mesh(part, region, 0);
  EXPECT_EQ(mine.face_offsets, whole.face_offsets);
  EXPECT_EQ(mine.face_vertices, whole.face_vertices);
  if (mine.positions.size() != whole.positions.size()) {
    ADD_FAILURE() << mine.positions.size() << " vertices, " << whole.positions.size() << " in the complete decode's";
    return 0;
  }
  std::size_t inside = 0;
  for (std::size_t v = 0; v < whole.positions.size(); ++v) {
    if (region.contains(whole.positions[v])) {
      ++inside;
      EXPECT_LE(norm(mine.positions[v] - whole.positions[v]), 1e-12 * norm(region.high - region.low)) << v;
    } else {
      EXPECT_LE(norm(mine.positions[v] - whole.positions[v]), full.stream.frame_step) << v;
    }
  }
  return inside;
}

// The packet table as docs/FORMAT.md describes it: per group, the offsets
// (in the file) and sizes of its packets.
struct Packet {
  std::size_t offset, size;
};
std::vector<std::vector<Packet>> packets_by_group(const std::string& file) {
  std::size_t position = 16;
  for (const std::string& part : test::split_sections(file)) {
    if (position > 16 && test::section_tag(part) == "PLNS") break;
    position = part.size() == 16 ? 16 : position + part.size();
  }
  // `position` is PLNS's header; its payload follows.
  std::size_t at = position + 16 + 2;
  const auto varint = [&] {
    std::uint64_t v = 0;
    for (int shift = 0;; shift += 7) {
      const auto byte = static_cast<unsigned char>(file[at++]);
      v |= std::uint64_t{byte & 0x7Fu} << shift;
      if (!(byte & 0x80)) return v;
    }
  };
  const std::size_t groups = varint();
  varint();  // segments
  const std::size_t count = varint();
  std::vector<std::uint64_t> sizes(count);
  for (std::uint64_t& size : sizes) size = varint();
  std::vector<std::vector<Packet>> result(groups);
  for (std::size_t j = 0; j < count; at += sizes[j], ++j) result[j % groups].push_back({at, sizes[j]});
  return result;
}

TEST(RandomAccess, ARegionReadsItsGroupsOnlyAndEqualsTheCompleteDecodeInside) {
  const Sample& s = sample();
  const IswDecoded full = read_isw(s.path);
  EXPECT_EQ(full.minor_version, 2);
  EXPECT_EQ(full.file_bytes_read, s.bytes.size());
  const IswDecoded part = read_region(s.path, corner_box());
  EXPECT_FALSE(part.truncated) << part.truncation_note;
  ASSERT_GE(part.stream.groups, 20u);
  EXPECT_GT(part.stream.groups_decoded, 0u);
  EXPECT_LT(part.stream.groups_decoded, part.stream.groups / 3);
  // The headers through the packet table, and the packets decoded: nothing else.
  EXPECT_EQ(part.file_bytes_read, part.stream.offset + part.stream.decoded);
  EXPECT_LT(part.file_bytes_read, s.bytes.size() / 2);
  EXPECT_GT(expect_same_region_mesh(full, part, corner_box()), 1000u);
  // The same decode from the bytes in memory (no partial reads).
  IswDecodeOptions options;
  options.region = corner_box();
  const IswDecoded memory = decode_isw(s.bytes, "memory.isw", options);
  EXPECT_EQ(memory.patch->coefficients, part.patch->coefficients);
  EXPECT_EQ(memory.stream.decoded, part.stream.decoded);
}

// A region no base face meets: no group read, the base mesh, nothing inside.
TEST(RandomAccess, ARegionAwayFromTheSurfaceGivesTheBaseMesh) {
  const Sample& s = sample();
  const RegionOfInterest away = parse_region("100,100,100,101,101,101", false, "--roi");
  const IswDecoded part = read_region(s.path, away);
  ASSERT_TRUE(part.patch);
  EXPECT_FALSE(part.patch->patch);
  EXPECT_EQ(part.stream.groups_decoded, 0u);
  EXPECT_EQ(part.file_bytes_read, part.stream.offset);
  RegionReconstruction counts;
  counts.inside_points = 1;
  const PolygonMesh mesh = region_mesh(part, away, 0, &counts);
  EXPECT_EQ(counts.inside_points, 0u);
  EXPECT_EQ(mesh.face_vertices, part.base.face_vertices);
  EXPECT_EQ(mesh.positions, part.base.positions);
}

// Damaging one group's packets at a time: a region decode fails (naming
// GIDX's CRC) exactly for the groups it reads, and those groups' packets
// are the stream bytes it reports; for the others it decodes as before.
TEST(RandomAccess, TheBytesReadAreThePacketsOfTheGroupsTheIndexNames) {
  const Sample& s = sample();
  const IswDecoded intact = read_region(s.path, corner_box());
  const std::vector<std::vector<Packet>> groups = packets_by_group(s.bytes);
  ASSERT_EQ(groups.size(), intact.stream.groups);
  std::size_t failed = 0;
  std::uint64_t failed_bytes = 0;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const auto largest = std::max_element(groups[g].begin(), groups[g].end(),
                                          [](const Packet& a, const Packet& b) { return a.size < b.size; });
    ASSERT_GT(largest->size, 0u) << g;
    std::string damaged = s.bytes;
    damaged[largest->offset + largest->size / 2] ^= 0x5A;
    const std::string path = write_temp("damaged.isw", damaged);
    try {
      const IswDecoded d = read_region(path, corner_box());
      EXPECT_EQ(d.patch->coefficients, intact.patch->coefficients) << "group " << g;
    } catch (const Error& error) {
      EXPECT_EQ(error.kind(), ErrorKind::Format);
      EXPECT_NE(std::string(error.what()).find("GIDX's CRC"), std::string::npos) << error.what();
      ++failed;
      for (const Packet& p : groups[g]) failed_bytes += p.size;
    }
  }
  EXPECT_EQ(failed, intact.stream.groups_decoded);
  EXPECT_EQ(failed_bytes, intact.stream.decoded);
}

TEST(RandomAccess, DamagedTruncatedOrInconsistentIndexesFailCleanly) {
  const Sample& s = sample();
  const std::string index = test::payload_of(s.bytes, "GIDX");
  ASSERT_FALSE(index.empty());
  const auto expect_error = [&](const std::string& bytes, const std::string& what, const std::string& says) {
    SCOPED_TRACE(what);
    for (const bool region : {false, true}) {
      try {
        if (region) read_region(write_temp("bad_index.isw", bytes), corner_box());
        else decode_isw(bytes, "bad_index.isw");
        ADD_FAILURE() << "decoded";
      } catch (const Error& error) {
        EXPECT_EQ(error.kind(), ErrorKind::Format) << error.what();
        EXPECT_NE(std::string(error.what()).find(says), std::string::npos) << error.what();
      }
    }
  };
  // A byte of GIDX changed: its CRC.
  std::string flipped = s.bytes;
  flipped[s.bytes.find("GIDX") + 16 + index.size() / 2] ^= 1;
  expect_error(flipped, "a flipped byte", "GIDX");
  // Cut inside GIDX: a file cut after BPTS, which decodes to the base mesh.
  const std::string cut = s.bytes.substr(0, s.bytes.find("GIDX") + 16 + index.size() / 2);
  for (const IswDecoded& d : {decode_isw(cut, "cut.isw"), read_region(write_temp("cut.isw", cut), corner_box())}) {
    EXPECT_TRUE(d.truncated);
    EXPECT_EQ(d.stream.decoded, 0u);
  }
  // Consistent CRCs, impossible contents.
  const auto with_index = [&](const std::string& payload) { return test::with_section_payload(s.bytes, "GIDX", payload); };
  expect_error(with_index(std::string(1, '\0') + index.substr(1)), "no groups", "group count");
  expect_error(with_index(index + "x"), "a byte after the groups", "GIDX");
  std::string runs = index;
  runs[1] = static_cast<char>(runs[1] == 1 ? 2 : 1);  // the first run (one byte) changed: the sum differs
  expect_error(with_index(runs), "runs not covering the faces", "GIDX");
  // A negative reach: the groups' count is the first byte (below 128), then one byte per run.
  std::string reach = index;
  const std::size_t groups = static_cast<unsigned char>(index[0]);
  ASSERT_LT(groups, 128u);
  std::size_t at = 1;
  for (std::size_t g = 0; g < groups; ++g)
    while (static_cast<unsigned char>(reach[at++]) & 0x80) {
    }
  reach[at + 3] = static_cast<char>(0xBF);  // the first reach's sign and exponent: -1.5
  expect_error(with_index(reach), "a negative reach", "reach");
  // A packet table that GIDX's CRC does not describe (the table's first byte,
  // the top plane, lowered: its CRC differs); only readers that check it.
  std::string table = test::payload_of(s.bytes, "PLNS");
  table[0] = static_cast<char>(table[0] - 1);
  const std::string retabled = test::with_section_payload(s.bytes, "PLNS", table);
  EXPECT_THROW(read_region(write_temp("retabled.isw", retabled), corner_box()), Error);
  // Tables a reader in part must not loop on: a size that never ends, and
  // more sizes than bytes (the same errors as a whole read).
  const std::string plane_header = table.substr(0, 2) + std::string(1, static_cast<char>(groups)) + "\x04";
  for (const std::string& bad : {plane_header + "\x10" + std::string(100000, '\x80'),
                                 plane_header + "\xff\xff\x03" + std::string(50, '\x01')}) {
    const std::string file = test::with_section_payload(s.bytes, "PLNS", bad);
    EXPECT_THROW(decode_isw(file, "bad_table.isw"), Error);
    try {
      read_region(write_temp("bad_table.isw", file), corner_box());
      ADD_FAILURE() << "decoded";
    } catch (const Error& error) {
      EXPECT_EQ(error.kind(), ErrorKind::Format) << error.what();
    }
  }
}

// A file cut inside its plane stream, or rewritten to a prefix of it, reads
// in part as it decodes whole: what the region's groups hold of the prefix.
TEST(RandomAccess, CutAndRewrittenFilesReadInPart) {
  const Sample& s = sample();
  const IswDecoded full = read_isw(s.path);
  const std::uint64_t half = full.stream.bytes / 2;
  IswDecodeOptions options;
  options.region = corner_box();
  const std::string rewritten = rewrite_isw(s.bytes, IswRewrite{half, {}, nullptr});
  const IswDecoded from_file = read_region(write_temp("rewritten.isw", rewritten), corner_box());
  EXPECT_FALSE(from_file.truncated);
  EXPECT_EQ(from_file.patch->coefficients, decode_isw(rewritten, "rewritten.isw", options).patch->coefficients);
  const std::string cut = s.bytes.substr(0, static_cast<std::size_t>(full.stream.offset + half));
  const IswDecoded cut_part = read_region(write_temp("cut.isw", cut), corner_box());
  EXPECT_TRUE(cut_part.truncated);
  EXPECT_EQ(cut_part.patch->coefficients, decode_isw(cut, "cut.isw", options).patch->coefficients);
  EXPECT_LE(cut_part.stream.decoded, half);
}

// A coefficient limit, a maximum error or a stream limit reads the headers and
// the stream's prefix it decodes, no more, and decodes as from memory.
TEST(RandomAccess, LimitsReadOnlyThePrefixTheyDecode) {
  const Sample& s = sample();
  std::vector<IswDecodeOptions> limits(3);
  limits[0].max_percent = 2;
  limits[1].max_coefficients = 0;
  limits[2].max_stream_bytes = 5000;
  for (const IswDecodeOptions& options : limits) {
    const IswDecoded part = read_isw(s.path, options);
    EXPECT_EQ(part.file_bytes_read, part.stream.offset + part.stream.decoded);
    EXPECT_LT(part.file_bytes_read, s.bytes.size() / 2);
    EXPECT_FALSE(part.truncated);
    const IswDecoded memory = decode_isw(s.bytes, "memory.isw", options);
    EXPECT_EQ(part.coefficients, memory.coefficients);
    EXPECT_EQ(part.ranked, memory.ranked);
  }
}

// Files before 2.2 have no index: a region decode reads and decodes every group.
TEST(RandomAccess, EarlierVersionsDecodeEveryGroup) {
  const Sample& s = sample();
  IswEncodeOptions options;
  options.step = 1e-3;
  options.minor_version = 1;
  const std::string old = encode_isw(*s.surface.hierarchy, s.surface.coefficients, test::sample_metadata(), options);
  const IswDecoded d = read_region(write_temp("old.isw", old), corner_box());
  EXPECT_EQ(d.stream.groups_decoded, d.stream.groups);
  EXPECT_EQ(d.coefficients, decode_isw(old, "old.isw").coefficients);
}

// Groups follow space: every group's faces lie in a box much smaller than
// the surface's, and the encoding is deterministic.
TEST(RandomAccess, GroupsAreCompactInSpaceAndTheEncodingDeterministic) {
  const Sample& s = sample();
  IswEncodeOptions options;
  options.step = 1e-3;
  options.group_nodes = 4096;
  EXPECT_EQ(encode_isw(*s.surface.hierarchy, s.surface.coefficients, test::sample_metadata(), options), s.bytes);
  // A unit box in a corner (the grid spans 48 x 48): the groups whose faces
  // may meet it hold few of the nodes.
  const IswDecoded d = read_region(s.path, parse_region("0,0,-10,1,1,10", false, "--roi"));
  EXPECT_LE(d.stream.groups_decoded, 4u);
}

}  // namespace
}  // namespace isowave
