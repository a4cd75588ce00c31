// The .isw decoder on hostile bytes (codec/src/isw_decoder.cpp). Every
// section carries CRC-32s (docs/FORMAT.md), which almost every mutation would
// break: the harness rewrites them first so that mutations reach the decoders
// (GIDX's CRCs of the packet table and of the groups' packets stay: a region
// decode of a mutated stream finds them, as it should). Layout: a 16-byte
// file header, then sections of tag (4), payload size (u64), CRC-32 of tag
// and size (u32), payload, CRC-32 of tag and payload (u32).
#include <cstring>
#include <string>

#include <zlib.h>

#include "fuzz_support.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/region.h"
#include "isowave/codec/region_of_interest.h"
#include "isowave/codec/view.h"

namespace {

std::uint32_t crc(const char* tag, const char* bytes, std::size_t n) {
  uLong c = crc32(0L, Z_NULL, 0);
  c = crc32(c, reinterpret_cast<const Bytef*>(tag), 4);
  return static_cast<std::uint32_t>(crc32(c, reinterpret_cast<const Bytef*>(bytes), static_cast<uInt>(n)));
}

// Little-endian, as the format stores them.
void put_u32(std::string& bytes, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<char>((v >> (8 * i)) & 0xff);
}

void fix_crcs(std::string& bytes) {
  constexpr std::size_t kFileHeader = 16, kSectionHeader = 16;
  for (std::size_t at = kFileHeader; at <= bytes.size() && bytes.size() - at >= kSectionHeader;) {
    const char* tag = bytes.data() + at;
    std::uint64_t size = 0;
    for (int i = 0; i < 8; ++i) size |= std::uint64_t(static_cast<unsigned char>(bytes[at + 4 + i])) << (8 * i);
    put_u32(bytes, at + 12, crc(tag, bytes.data() + at + 4, 8));
    const std::size_t payload = at + kSectionHeader;
    if (size > bytes.size() - payload || bytes.size() - payload - size < 4) return;  // cut: the decoder says so
    put_u32(bytes, payload + size, crc(tag, bytes.data() + payload, static_cast<std::size_t>(size)));
    at = payload + static_cast<std::size_t>(size) + 4;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  fix_crcs(bytes);
  isowave::fuzz::expect_clean([&] { isowave::decode_isw(bytes, "fuzz.isw"); });
  // A region decode (2.2): the groups it selects, GIDX's CRCs checked, the
  // patch it builds and the mesh over it.
  isowave::IswDecodeOptions region;
  region.region = isowave::make_region({-1, -1, -1, 1, 1, 1}, false, "region");
  isowave::fuzz::expect_clean([&] {
    const isowave::IswDecoded decoded = isowave::decode_isw(bytes, "fuzz.isw", region);
    isowave::region_mesh(decoded, *region.region, 0);
  });
  // A view decode over a patch (2.2): the frustum's groups and the mesh.
  isowave::IswDecodeOptions view;
  view.frustum = isowave::Camera{{0, 0, -3}, {0, 0, 0}, {0, 1, 0}, 60, 64, 48};
  view.view_scope = isowave::IswDecodeOptions::ViewScope::Patch;
  isowave::fuzz::expect_clean([&] {
    const isowave::IswDecoded decoded = isowave::decode_isw(bytes, "fuzz.isw", view);
    isowave::view_mesh(decoded, *view.frustum, 1.0);
  });
  // A coefficient limit (2.2): the prefix PCNT's counts choose.
  isowave::IswDecodeOptions percent;
  percent.max_percent = 5;
  isowave::fuzz::expect_clean([&] { isowave::decode_isw(bytes, "fuzz.isw", percent); });
  return 0;
}
