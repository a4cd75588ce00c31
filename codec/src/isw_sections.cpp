#include "isw_sections.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iterator>

#include <zlib.h>

namespace isowave {

double IswMetadata::number(const std::string& key, double fallback) const {
  const auto it = values.find(key);
  if (it == values.end()) return fallback;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  return end && *end == '\0' && std::isfinite(v) ? v : fallback;
}

std::string IswMetadata::text(const std::string& key, const std::string& fallback) const {
  const auto it = values.find(key);
  return it == values.end() ? fallback : it->second;
}

namespace detail {
namespace {

constexpr const char* kHeaderOrder[] = {"META", "BASE", "QUAN", "BPTS"};

// The sections after the headers, in their order (docs/FORMAT.md): whether
// one may come more than once, and whether it may be left out.
struct StreamTag {
  std::string_view tag;
  bool repeats;
  bool optional;
};
constexpr StreamTag kStream1[] = {{"CHNK", true, true}, {"END ", false, false}};
constexpr StreamTag kStream2[] = {
    {"RDTB", false, true}, {"GIDX", false, true}, {"PCNT", false, true}, {"PLNS", false, false}, {"END ", false, false}};

struct StreamOrder {
  const StreamTag* tags;
  int count;
  // The position of `tag` in the order, or -1.
  int index(std::string_view tag) const {
    for (int k = 0; k < count; ++k)
      if (tags[k].tag == tag) return k;
    return -1;
  }
};

StreamOrder stream_order(int major) {
  return major == 1 ? StreamOrder{kStream1, static_cast<int>(std::size(kStream1))}
                    : StreamOrder{kStream2, static_cast<int>(std::size(kStream2))};
}

bool known_tag(int major, std::string_view tag) {
  return std::find(std::begin(kHeaderOrder), std::end(kHeaderOrder), tag) != std::end(kHeaderOrder) ||
         stream_order(major).index(tag) >= 0;
}

std::uint32_t crc_of(const char* tag, std::string_view payload) {
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(tag), 4);
  // zlib's crc32 takes a uInt length: feed large payloads in pieces.
  for (std::size_t offset = 0; offset < payload.size(); offset += 1u << 30) {
    const std::size_t n = std::min<std::size_t>(payload.size() - offset, 1u << 30);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(payload.data() + offset), static_cast<uInt>(n));
  }
  return static_cast<std::uint32_t>(crc);
}

// The header has its own CRC so that a damaged size field reads as corruption,
// while a file cut inside a payload reads as truncation.
std::uint32_t header_crc(const char* tag, std::uint64_t size) {
  std::string size_bytes;
  put_u64(size_bytes, size);
  return crc_of(tag, size_bytes);
}

// Whether the section at `position` with payload `size` fits in `bytes`
// (header, payload and CRC).
bool fits(const std::string& bytes, std::size_t position, std::uint64_t size) {
  return size <= bytes.size() - position - kSectionHeader && bytes.size() - position - kSectionHeader - size >= 4;
}

}  // namespace

bool read_varint(PayloadReader& reader, std::uint64_t& v) {
  v = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    if (reader.remaining() == 0) return false;
    const auto byte = reader.read<std::uint8_t>();
    // The tenth byte holds bit 63 only.
    if (shift == 63 && byte > 1) break;
    v |= std::uint64_t{byte & 0x7Fu} << shift;
    if (!(byte & 0x80)) return true;
  }
  reader.fail("holds an invalid number");
}

void put_file_header(std::string& out, int major, int minor) {
  out.append(kIswMagic, kIswMagic + 8);
  put_u16(out, static_cast<std::uint16_t>(major));
  put_u16(out, static_cast<std::uint16_t>(minor));
  put_u32(out, 0);
}

void put_section(std::string& out, const char* tag, std::string_view payload) {
  out.append(tag, 4);
  put_u64(out, payload.size());
  put_u32(out, header_crc(tag, payload.size()));
  out += payload;
  put_u32(out, crc_of(tag, payload));
}

void read_file_header(const std::string& bytes, const std::string& name, IswDecoded& result) {
  if (bytes.empty()) throw Error(ErrorKind::Format, name + ": empty file, not an isowave .isw file");
  if (std::memcmp(bytes.data(), kIswMagic, std::min<std::size_t>(8, bytes.size())) != 0)
    throw Error(ErrorKind::Format, name + ": not an isowave .isw file (bad magic)");
  if (bytes.size() < kFileHeaderBytes)
    throw Error(ErrorKind::Format, name + ": truncated inside the file header (" + std::to_string(bytes.size()) +
                                       " of " + std::to_string(kFileHeaderBytes) + " bytes)");
  std::uint16_t major = 0, minor = 0;
  std::uint32_t reserved = 0;
  std::memcpy(&major, bytes.data() + 8, 2);
  std::memcpy(&minor, bytes.data() + 10, 2);
  std::memcpy(&reserved, bytes.data() + 12, 4);
  if (major != 1 && (major != kIswMajorVersion || minor > kIswMinorVersion))
    throw Error(ErrorKind::Unsupported, name + ": .isw format version " + std::to_string(major) + "." +
                                            std::to_string(minor) + " is not supported (this build reads 1.x and " +
                                            std::to_string(kIswMajorVersion) + ".0-" +
                                            std::to_string(kIswMajorVersion) + "." +
                                            std::to_string(kIswMinorVersion) + ")");
  if (reserved != 0) throw Error(ErrorKind::Format, name + ": corrupt file header (reserved field is not zero)");
  result.major_version = major;
  result.minor_version = minor;
}

std::optional<Section> SectionWalker::next() {
  if (position_ >= bytes_.size()) return std::nullopt;
  const bool in_stream = headers_read_ >= std::size(kHeaderOrder);
  if (bytes_.size() - position_ < kSectionHeader) {
    if (in_stream) {
      truncated_ = true;
      return std::nullopt;
    }
    throw Error(ErrorKind::Format, name_ + ": truncated inside the header of section " + kHeaderOrder[headers_read_] +
                                       " (at byte " + std::to_string(position_) + ")");
  }
  Section section;
  section.tag = bytes_.substr(position_, 4);
  std::uint64_t size = 0;
  std::uint32_t stored_header_crc = 0;
  std::memcpy(&size, bytes_.data() + position_ + 4, 8);
  std::memcpy(&stored_header_crc, bytes_.data() + position_ + 12, 4);
  const std::string& tag = section.tag;
  section.where = where(tag);
  section.payload_size = size;
  if (header_crc(tag.c_str(), size) != stored_header_crc)
    throw Error(ErrorKind::Format, section.where + ": corrupt section header (CRC mismatch)");
  section.known = known_tag(major_, tag);
  if (section.known && !in_stream && tag != kHeaderOrder[headers_read_])
    throw Error(ErrorKind::Format, section.where + ": expected section " + kHeaderOrder[headers_read_]);
  if (section.known && in_stream) check_stream_order(tag, section.where);
  if (!fits(bytes_, position_, size)) {
    // Known tags are in order here: a cut stream section ends the stream,
    // and a cut plane stream still decodes as far as it goes.
    if (in_stream) {
      truncated_ = true;
      if (major_ == 2 && tag == "PLNS") {
        section.cut = true;
        section.payload = std::string_view(bytes_).substr(std::min(bytes_.size(), position_ + kSectionHeader));
        section.info = IswSectionInfo{tag, position_, bytes_.size() - position_, 0};
        position_ = bytes_.size();
        return section;
      }
      return std::nullopt;
    }
    throw Error(ErrorKind::Format, section.where + " is truncated");
  }
  section.payload = std::string_view(bytes_).substr(position_ + kSectionHeader, static_cast<std::size_t>(size));
  std::uint32_t stored_crc = 0;
  std::memcpy(&stored_crc, bytes_.data() + position_ + kSectionHeader + size, 4);
  if (crc_of(tag.c_str(), section.payload) != stored_crc)
    throw Error(ErrorKind::Format, section.where + " is corrupt (CRC mismatch)");
  section.info = IswSectionInfo{tag, position_, size + kSectionOverhead, 0};
  position_ += static_cast<std::size_t>(size) + kSectionOverhead;
  if (section.known && !in_stream) ++headers_read_;
  return section;
}

std::string SectionWalker::where(const std::string& tag) const {
  return name_ + ": section " + tag + " (at byte " + std::to_string(position_) + ")";
}

void SectionWalker::check_stream_order(const std::string& tag, const std::string& where) {
  const StreamOrder order = stream_order(major_);
  const int index = order.index(tag);
  if (index < 0) throw Error(ErrorKind::Format, where + ": section out of order");
  if (index == stream_stage_ && !order.tags[index].repeats)
    throw Error(ErrorKind::Format, where + " is repeated (a file holds one)");
  if (index < stream_stage_)
    throw Error(ErrorKind::Format, where + " comes after section " + std::string(order.tags[stream_stage_].tag) +
                                       " (out of order)");
  for (int k = stream_stage_ + 1; k < index; ++k)
    if (!order.tags[k].optional)
      throw Error(ErrorKind::Format, where + " comes before section " + std::string(order.tags[k].tag) +
                                         ", which is missing");
  stream_stage_ = index;
}

void SectionWalker::require_headers() const {
  if (headers_read_ < std::size(kHeaderOrder))
    throw Error(ErrorKind::Format, name_ + ": truncated before section " + kHeaderOrder[headers_read_] +
                                       " (at byte " + std::to_string(position_) + ")");
}

bool SectionWalker::list_rest(std::vector<IswSectionInfo>& sections) {
  while (position_ + kSectionHeader <= bytes_.size()) {
    std::uint64_t size = 0;
    std::memcpy(&size, bytes_.data() + position_ + 4, 8);
    IswSectionInfo next{bytes_.substr(position_, 4), position_, 0, 0};
    if (known_tag(major_, next.tag))
      check_stream_order(next.tag, where(next.tag));
    if (!fits(bytes_, position_, size)) {
      truncated_ = true;
      break;
    }
    next.bytes = size + kSectionOverhead;
    if (next.tag == "CHNK" && size >= 20) {  // chunk index, then the first and end ranks
      std::uint64_t begin = 0, end = 0;
      std::memcpy(&begin, bytes_.data() + position_ + kSectionHeader + 4, 8);
      std::memcpy(&end, bytes_.data() + position_ + kSectionHeader + 12, 8);
      next.coefficients = end >= begin ? end - begin : 0;
    }
    sections.push_back(next);
    position_ += static_cast<std::size_t>(next.bytes);
  }
  // As the full decode says it: a file without its END is truncated.
  if (sections.empty() || sections.back().tag != "END ") truncated_ = true;
  return truncated_;
}

}  // namespace detail
}  // namespace isowave
