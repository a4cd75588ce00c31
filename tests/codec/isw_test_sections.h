#pragma once
// Taking .isw files apart and putting them together again in tests, written
// from docs/FORMAT.md ("Layout") rather than with the codec's own framing: a
// 16-byte file header, then sections of a 4-character tag, u64 payload size,
// CRC-32 of tag and size bytes, the payload, CRC-32 of tag and payload.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <zlib.h>

namespace isowave::test {

// CRC-32 (zlib) of a 4-character tag followed by `data`.
inline std::uint32_t section_crc(const std::string& tag, const std::string& data) {
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(tag.data()), 4);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(data.data()), static_cast<uInt>(data.size()));
  return static_cast<std::uint32_t>(crc);
}

// One whole section holding `payload`, sizes and CRCs consistent.
inline std::string make_section(const std::string& tag, const std::string& payload) {
  std::string size_bytes(8, '\0');
  const std::uint64_t size = payload.size();
  std::memcpy(size_bytes.data(), &size, 8);
  const std::uint32_t header_crc = section_crc(tag, size_bytes), payload_crc = section_crc(tag, payload);
  return tag + size_bytes + std::string(reinterpret_cast<const char*>(&header_crc), 4) + payload +
         std::string(reinterpret_cast<const char*>(&payload_crc), 4);
}

// The file header, then each whole section in file order (a section cut
// short ends the list).
inline std::vector<std::string> split_sections(const std::string& file) {
  constexpr std::size_t kFileHeader = 16, kSectionHeader = 16;
  std::vector<std::string> parts{file.substr(0, kFileHeader)};
  for (std::size_t position = kFileHeader; position + kSectionHeader <= file.size();) {
    std::uint64_t size = 0;
    std::memcpy(&size, file.data() + position + 4, 8);
    if (size + 4 > file.size() - position - kSectionHeader) break;
    const std::size_t end = position + kSectionHeader + static_cast<std::size_t>(size) + 4;
    parts.push_back(file.substr(position, end - position));
    position = end;
  }
  return parts;
}

inline std::string section_tag(const std::string& section) { return section.substr(0, 4); }
inline std::string section_payload(const std::string& section) { return section.substr(16, section.size() - 20); }

inline std::string join(const std::vector<std::string>& parts) {
  std::string out;
  for (const std::string& part : parts) out += part;
  return out;
}

// `file` with the payload of every section `tag` replaced (sizes and CRCs made consistent).
inline std::string with_section_payload(const std::string& file, const std::string& tag, const std::string& payload) {
  std::vector<std::string> parts = split_sections(file);
  for (std::size_t k = 1; k < parts.size(); ++k)
    if (section_tag(parts[k]) == tag) parts[k] = make_section(tag, payload);
  return join(parts);
}

// The payload of the first section `tag` of `file`, or "".
inline std::string payload_of(const std::string& file, const std::string& tag) {
  for (const std::string& part : split_sections(file))
    if (part.size() >= 20 && section_tag(part) == tag) return section_payload(part);
  return "";
}

}  // namespace isowave::test
