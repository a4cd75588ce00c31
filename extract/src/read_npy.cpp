// NumPy .npy (format versions 1.0, 2.0 and 3.0): a 3-D array of a numeric
// dtype, C or Fortran order, either byte order. The header's dict is parsed
// strictly (exactly the keys descr, fortran_order and shape; Python literals
// only), since the file is hostile.
#include <array>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "isowave/core/error.h"
#include "volume_io_internal.h"

namespace isowave::detail {
namespace {

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicSize = 6;
// numpy itself refuses headers over 10,000 bytes unless told otherwise.
constexpr std::uint32_t kMaxHeaderBytes = 65536;
constexpr std::size_t kMaxRank = 32;  // numpy's own limit

struct NpyHeader {
  ScalarType type = ScalarType::Float32;
  bool big_endian = false;
  bool fortran_order = false;
  std::vector<std::uint64_t> shape;
  std::uint64_t data_offset = 0;
};

// A cursor over the header text; every method fails with a Format error
// naming the file and what was expected.
class DictParser {
 public:
  DictParser(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  void skip_space() {
    while (at_ < text_.size() && (text_[at_] == ' ' || text_[at_] == '\t' || text_[at_] == '\n' || text_[at_] == '\r'))
      ++at_;
  }
  bool accept(char c) {
    skip_space();
    if (at_ < text_.size() && text_[at_] == c) {
      ++at_;
      return true;
    }
    return false;
  }
  void expect(char c, const char* where) {
    if (!accept(c)) fail(std::string("expected '") + c + "' " + where);
  }
  bool at_end() {
    skip_space();
    return at_ == text_.size();
  }
  // A Python string literal in single or double quotes, without escapes.
  std::string string_literal(const char* what) {
    skip_space();
    if (at_ >= text_.size() || (text_[at_] != '\'' && text_[at_] != '"')) fail(std::string("expected a quoted ") + what);
    const char quote = text_[at_++];
    const std::size_t close = text_.find(quote, at_);
    if (close == std::string_view::npos) fail(std::string("unterminated ") + what);
    const std::string_view value = text_.substr(at_, close - at_);
    if (value.find('\\') != std::string_view::npos || value.size() > 64) fail(std::string("unsupported ") + what);
    at_ = close + 1;
    return std::string(value);
  }
  bool boolean() {
    skip_space();
    for (const auto& [word, value] : {std::pair{"True", true}, std::pair{"False", false}}) {
      const std::size_t n = std::strlen(word);
      if (text_.substr(at_, n) == word) {
        at_ += n;
        return value;
      }
    }
    fail("fortran_order must be True or False");
  }
  // A tuple of non-negative integers: (), (n,), (a, b, c) or (a, b, c,).
  std::vector<std::uint64_t> shape() {
    expect('(', "to open the shape");
    std::vector<std::uint64_t> dims;
    while (!accept(')')) {
      if (dims.size() == kMaxRank) fail("the shape has more than 32 dimensions");
      dims.push_back(integer());
      accept('L');  // Python 2 long literals
      if (!accept(',')) {
        expect(')', "to close the shape");
        if (dims.size() == 1) fail("a 1-element shape needs a trailing comma");
        break;
      }
    }
    return dims;
  }
  [[noreturn]] void fail(const std::string& what) const {
    format_error(path_, "bad .npy header: " + what + " (at byte " + std::to_string(at_) + " of the header)");
  }

 private:
  std::uint64_t integer() {
    skip_space();
    const std::size_t start = at_;
    std::uint64_t value = 0;
    while (at_ < text_.size() && text_[at_] >= '0' && text_[at_] <= '9') {
      if (__builtin_mul_overflow(value, 10, &value) || __builtin_add_overflow(value, std::uint64_t(text_[at_] - '0'), &value))
        fail("a dimension is too large");
      ++at_;
    }
    if (at_ == start) fail("expected a non-negative integer in the shape");
    return value;
  }

  std::string_view text_;
  const std::string& path_;
  std::size_t at_ = 0;
};

// '<f4', '>i2', '|u1', ... -> the sample type and byte order.
void parse_descr(const std::string& descr, NpyHeader& header, const DictParser& parser) {
  const auto unsupported = [&](const std::string& why) {
    parser.fail("unsupported dtype '" + descr + "' (" + why +
                "; supported: int8, uint8, int16, uint16, int32, uint32, int64, uint64, float16, float32, float64)");
  };
  if (descr.size() < 3) unsupported("not a simple dtype");
  const char order = descr[0];
  if (order != '<' && order != '>' && order != '|' && order != '=') unsupported("unknown byte order");
  const std::string code = descr.substr(1);
  struct Code {
    const char* name;
    ScalarType type;
  };
  static constexpr Code kCodes[] = {{"i1", ScalarType::Int8},    {"u1", ScalarType::UInt8},   {"i2", ScalarType::Int16},
                                    {"u2", ScalarType::UInt16},  {"i4", ScalarType::Int32},   {"u4", ScalarType::UInt32},
                                    {"i8", ScalarType::Int64},   {"u8", ScalarType::UInt64},  {"f2", ScalarType::Float16},
                                    {"f4", ScalarType::Float32}, {"f8", ScalarType::Float64}};
  for (const Code& c : kCodes) {
    if (code != c.name) continue;
    const bool multibyte = scalar_type_size(c.type) > 1;
    if (order == '|' && multibyte) unsupported("'|' is for single-byte types");
    header.type = c.type;
    header.big_endian = order == '>';  // '=' (the writer's native order) is taken as little-endian
    return;
  }
  if (code == "b1" || code == "?") unsupported("booleans are not a scalar field");
  if (!code.empty() && code[0] == 'c') unsupported("complex values");
  unsupported("not a numeric type");
}

// The dict: {'descr': ..., 'fortran_order': ..., 'shape': (...), } in any key
// order, each key exactly once, nothing else.
void parse_dict(std::string_view text, NpyHeader& header, const std::string& path) {
  DictParser p(text, path);
  p.expect('{', "at the start of the header");
  bool seen_descr = false, seen_order = false, seen_shape = false;
  while (!p.accept('}')) {
    const std::string key = p.string_literal("key");
    p.expect(':', "after a key");
    bool* seen = nullptr;
    if (key == "descr") {
      seen = &seen_descr;
      if (p.accept('[')) p.fail("structured dtypes are not supported");
      parse_descr(p.string_literal("dtype"), header, p);
    } else if (key == "fortran_order") {
      seen = &seen_order;
      header.fortran_order = p.boolean();
    } else if (key == "shape") {
      seen = &seen_shape;
      header.shape = p.shape();
    } else {
      p.fail("unknown key '" + key + "'");
    }
    if (*seen) p.fail("key '" + key + "' appears twice");
    *seen = true;
    if (!p.accept(',')) {
      p.expect('}', "to close the header");
      break;
    }
  }
  if (!p.at_end()) p.fail("text after the closing '}'");
  if (!seen_descr || !seen_order || !seen_shape) p.fail("the keys descr, fortran_order and shape are all required");
}

NpyHeader read_header(InputFile& file) {
  const std::string& path = file.path();
  unsigned char prefix[kMagicSize + 2] = {};
  if (file.read_some(prefix, sizeof prefix) != sizeof prefix || std::memcmp(prefix, kMagic, kMagicSize) != 0)
    format_error(path, "not a NumPy .npy file (no \\x93NUMPY magic)");
  const int major = prefix[kMagicSize], minor = prefix[kMagicSize + 1];
  if (major < 1 || major > 3 || minor != 0)
    format_error(path, "unsupported .npy version " + std::to_string(major) + "." + std::to_string(minor) +
                           " (1.0, 2.0 and 3.0 are supported)");
  const std::size_t length_bytes = major == 1 ? 2 : 4;
  unsigned char length_field[4] = {};
  file.read_exact(length_field, length_bytes, "header length");
  std::uint32_t length = 0;
  for (std::size_t i = length_bytes; i-- > 0;) length = length << 8 | length_field[i];
  if (length > kMaxHeaderBytes)
    format_error(path, "bad .npy header: " + std::to_string(length) + " bytes declared (at most " +
                           std::to_string(kMaxHeaderBytes) + ")");
  const std::uint64_t data_offset = sizeof prefix + length_bytes + length;
  if (data_offset > file.size()) format_error(path, "truncated header (" + std::to_string(length) + " bytes declared)");

  std::string text(length, '\0');
  file.read_exact(text.data(), text.size(), "header");
  // Versions 1 and 2 are latin-1, version 3 UTF-8; a valid dict is ASCII either way.
  for (const char c : text)
    if (static_cast<unsigned char>(c) >= 0x80 || c == '\0') format_error(path, "bad .npy header: non-ASCII byte");
  NpyHeader header;
  parse_dict(text, header, path);
  header.data_offset = data_offset;
  return header;
}

std::string shape_text(const std::vector<std::uint64_t>& shape) {
  std::string text = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) text += (i ? ", " : "") + std::to_string(shape[i]);
  return text + (shape.size() == 1 ? ",)" : ")");
}

}  // namespace

Volume read_npy(const std::string& path, const VolumeReadOptions& options) {
  InputFile file(path);
  const NpyHeader header = read_header(file);
  if (header.shape.size() != 3)
    format_error(path, "the array has shape " + shape_text(header.shape) + ": only 3-D arrays are volumes");
  for (const std::uint64_t d : header.shape)
    if (d > std::numeric_limits<std::size_t>::max()) format_error(path, "shape " + shape_text(header.shape) + " is too large");

  // The fastest-varying axis is x: the last in C order, the first in Fortran order.
  Volume volume;
  const auto& s = header.shape;
  volume.dims = header.fortran_order ? std::array<std::size_t, 3>{s[0], s[1], s[2]}
                                     : std::array<std::size_t, 3>{s[2], s[1], s[0]};
  volume.source_type = header.type;
  const std::size_t sample_size = scalar_type_size(header.type);
  const std::size_t count = checked_sample_count(volume.dims, sample_size, path);
  const std::uint64_t expected = static_cast<std::uint64_t>(count) * sample_size;
  const std::uint64_t available = file.size() - header.data_offset;
  if (available != expected)
    format_error(path, std::string(available < expected ? "truncated data" : "size mismatch") + ": " +
                           std::to_string(available) + " data bytes for shape " + shape_text(header.shape) + " " +
                           to_string(header.type) + " (" + std::to_string(expected) + " bytes)");
  volume.values.resize(count);
  read_binary_samples(file, volume.values.data(), count, header.type, header.big_endian, "array data");
  (void)options;
  return volume;
}

}  // namespace isowave::detail
