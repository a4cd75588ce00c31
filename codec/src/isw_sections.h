#pragma once
// Private: the framing of an .isw file (docs/FORMAT.md, "Layout"): the file
// header, tagged sections with a CRC-32 over tag and size and another over
// tag and payload, and bounds-checked payload reading. Every byte is treated
// as hostile: a damaged size field reads as corruption (its header CRC), a
// file cut inside a payload as truncation; both are Error(Format) naming the
// section, except a cut inside the coefficient stream, which the reader
// reports as truncated() so that the chunks before it still decode.
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/core/error.h"

namespace isowave::detail {

constexpr char kIswMagic[8] = {'\x89', 'I', 'S', 'W', '\r', '\n', '\x1a', '\n'};
constexpr std::size_t kFileHeaderBytes = 16;             // magic, u16 major, u16 minor, u32 zero
constexpr std::size_t kSectionHeader = 4 + 8 + 4;        // tag, payload size, CRC-32 of tag and size
constexpr std::size_t kSectionOverhead = kSectionHeader + 4;  // and the payload's CRC-32

// Little-endian appends (the format's byte order; the hosts we build for are
// little-endian).
inline void put_u16(std::string& out, std::uint16_t v) { out.append(reinterpret_cast<const char*>(&v), 2); }
inline void put_u32(std::string& out, std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); }
inline void put_u64(std::string& out, std::uint64_t v) { out.append(reinterpret_cast<const char*>(&v), 8); }
inline void put_f64(std::string& out, double v) { out.append(reinterpret_cast<const char*>(&v), 8); }

// LEB128: 7 bits a byte, low bits first, the top bit set on all but the last.
inline void put_varint(std::string& out, std::uint64_t v) {
  for (; v >= 0x80; v >>= 7) out.push_back(static_cast<char>((v & 0x7F) | 0x80));
  out.push_back(static_cast<char>(v));
}

// The 16-byte file header of version `major`.`minor` (1.0, 2.0, 2.1 or 2.2).
void put_file_header(std::string& out, int major, int minor = 0);
// Appends one section: header, payload, CRC. `tag` is 4 characters.
void put_section(std::string& out, const char* tag, std::string_view payload);

// Checks the magic and the version of `bytes` and stores the version in
// `result`. Errors: Format (not an .isw file, a truncated or corrupt header),
// Unsupported (another major version, or a major 2 minor version above
// kIswMinorVersion: a minor version may change the plane coding). `name`
// heads the messages.
void read_file_header(const std::string& bytes, const std::string& name, IswDecoded& result);

// Bounds-checked little-endian reader over one section's payload; fail()
// throws Error(Format) headed by the section's name and offset.
class PayloadReader {
 public:
  PayloadReader(std::string_view data, std::string context) : data_(data), context_(std::move(context)) {}
  template <class T>
  T read() {
    if (data_.size() - position_ < sizeof(T)) fail("is truncated");
    T v;
    std::memcpy(&v, data_.data() + position_, sizeof(T));
    position_ += sizeof(T);
    return v;
  }
  std::string_view bytes(std::uint64_t n) {
    if (data_.size() - position_ < n) fail("is truncated");
    const std::string_view s = data_.substr(position_, static_cast<std::size_t>(n));
    position_ += static_cast<std::size_t>(n);
    return s;
  }
  std::size_t remaining() const { return data_.size() - position_; }
  [[noreturn]] void fail(const std::string& what) const { throw Error(ErrorKind::Format, context_ + " " + what); }

 private:
  std::string_view data_;
  std::size_t position_ = 0;
  std::string context_;
};

// A LEB128 value from `reader`: false when the bytes end first (a cut
// table); Error(Format) through `reader` for a value of 2^64 or more.
bool read_varint(PayloadReader& reader, std::uint64_t& v);

// One framed section, both CRCs checked.
struct Section {
  std::string tag;
  std::string_view payload;
  std::uint64_t payload_size = 0;  // as its header says (more than `payload` holds when cut)
  IswSectionInfo info;  // offset and whole size; coefficients left to the CHNK decoder
  std::string where;    // "NAME: section TAG (at byte N)", for messages
  bool known = false;   // a tag of this version (others come from later minor versions and are skipped)
  bool cut = false;     // version 2 PLNS only: the file ends inside it; `payload` is what is present, unchecked
  PayloadReader reader() const { return PayloadReader(payload, where); }
};

// Walks the sections of a file after its header, checking the order of the
// known ones: META, BASE, QUAN, BPTS, then any number of CHNK (version 1) or
// an optional RDTB and one PLNS (version 2), and END; a known section
// repeated (but CHNK), out of that order or following a missing PLNS is
// Error(Format) naming it. Unknown tags may appear anywhere. Cost: one CRC
// pass over the bytes.
class SectionWalker {
 public:
  SectionWalker(const std::string& bytes, const std::string& name, int major)
      : bytes_(bytes), name_(name), major_(major) {}
  // The next section, or nothing at the end of the bytes or when the file is
  // cut inside the coefficient stream (then truncated()). Throws Error(Format)
  // for a corrupt or misplaced section and for a cut before the stream.
  std::optional<Section> next();
  bool truncated() const { return truncated_; }
  std::size_t position() const { return position_; }
  // Throws Error(Format) unless META, BASE, QUAN and BPTS were all read.
  void require_headers() const;
  // Appends the remaining sections to `sections` without checking their
  // payloads (CHNK with their coefficient counts), only their order; returns
  // whether the file is truncated (a section cut short, or no END). For `info`.
  bool list_rest(std::vector<IswSectionInfo>& sections);

 private:
  // "NAME: section TAG (at byte N)" for the section at the position.
  std::string where(const std::string& tag) const;
  // Error(Format) headed by `where` unless a known stream section `tag` may
  // follow those before it; records it.
  void check_stream_order(const std::string& tag, const std::string& where);

  const std::string& bytes_;
  std::string name_;
  int major_;
  std::size_t position_ = kFileHeaderBytes;
  std::size_t headers_read_ = 0;  // of META, BASE, QUAN, BPTS
  int stream_stage_ = -1;         // the order's index of the last stream section read
  bool truncated_ = false;
};

}  // namespace isowave::detail
