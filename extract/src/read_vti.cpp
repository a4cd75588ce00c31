// VTK XML ImageData (.vti): ascii, inline base64 and appended (raw or base64)
// arrays, optionally vtkZLibDataCompressor-compressed, UInt32 or UInt64 block
// headers, either byte order. A small XML tokenizer reads the structure; the
// appended section is binary and ends the parse.
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "volume_io_internal.h"

namespace isowave::detail {
namespace {

constexpr std::size_t kMaxDepth = 64;

struct XmlElement {
  std::string name;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::vector<std::size_t> children;
  // The last run of character data directly inside the element.
  std::size_t text_begin = 0, text_end = 0;

  const std::string* attribute(std::string_view key) const {
    for (const auto& [k, v] : attributes) {
      if (k == key) return &v;
    }
    return nullptr;
  }
};

struct XmlDocument {
  std::vector<XmlElement> elements;  // elements[0] is the root
  std::optional<std::size_t> appended;  // index of <AppendedData>
  std::size_t appended_data = 0;        // offset of the byte after '_'
};

std::string decode_entities(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '&') {
      out.push_back(text[i]);
      continue;
    }
    // An entity is at most 10 characters: look no farther for its ';' (a
    // search to the end at every '&' made long attributes quadratic).
    const auto semi = text.substr(i, 11).find(';');
    if (semi == std::string_view::npos) {
      out.push_back('&');
      continue;
    }
    const std::string_view entity = text.substr(i + 1, semi - 1);
    if (entity == "lt") out.push_back('<');
    else if (entity == "gt") out.push_back('>');
    else if (entity == "amp") out.push_back('&');
    else if (entity == "quot") out.push_back('"');
    else if (entity == "apos") out.push_back('\'');
    else {
      out.append(text.substr(i, semi + 1));
    }
    i += semi;
  }
  return out;
}

class XmlParser {
 public:
  XmlParser(const std::string& path, const std::vector<char>& buffer) : path_(path), b_(buffer) {}

  XmlDocument parse() {
    XmlDocument doc;
    std::vector<std::size_t> stack;
    while (true) {
      const std::size_t text_start = p_;
      while (p_ < b_.size() && b_[p_] != '<') ++p_;
      if (!stack.empty()) {
        XmlElement& e = doc.elements[stack.back()];
        if (has_content(text_start, p_)) {
          e.text_begin = text_start;
          e.text_end = p_;
        }
      } else if (has_content(text_start, p_)) {
        fail("bad XML: text outside the root element");
      }
      if (p_ >= b_.size()) break;
      if (starts_with("<?")) {
        skip_past("?>");
      } else if (starts_with("<!--")) {
        skip_past("-->");
      } else if (starts_with("<![CDATA[")) {
        fail("bad XML: CDATA sections are not supported");
      } else if (starts_with("<!")) {
        skip_past(">");
      } else if (starts_with("</")) {
        p_ += 2;
        const std::string name = read_name();
        skip_space();
        expect('>');
        if (stack.empty() || doc.elements[stack.back()].name != name)
          fail("bad XML: unexpected closing tag </" + name + ">");
        stack.pop_back();
        if (stack.empty()) break;
      } else {
        ++p_;
        XmlElement element;
        element.name = read_name();
        bool self_closing = false;
        while (true) {
          skip_space();
          if (p_ >= b_.size()) fail("truncated XML (inside <" + element.name + ">)");
          if (b_[p_] == '>') {
            ++p_;
            break;
          }
          if (starts_with("/>")) {
            p_ += 2;
            self_closing = true;
            break;
          }
          std::string key = read_name();
          skip_space();
          expect('=');
          skip_space();
          if (p_ >= b_.size() || (b_[p_] != '"' && b_[p_] != '\'')) fail("bad XML: unquoted attribute value for " + key);
          const char quote = b_[p_++];
          const std::size_t start = p_;
          while (p_ < b_.size() && b_[p_] != quote) ++p_;
          if (p_ >= b_.size()) fail("truncated XML (inside an attribute of <" + element.name + ">)");
          element.attributes.emplace_back(std::move(key), decode_entities(std::string_view(b_.data() + start, p_ - start)));
          ++p_;
        }
        if (stack.empty() && !doc.elements.empty()) fail("bad XML: more than one root element");
        const std::size_t index = doc.elements.size();
        if (!stack.empty()) doc.elements[stack.back()].children.push_back(index);
        const bool appended = element.name == "AppendedData";
        doc.elements.push_back(std::move(element));
        if (appended) {
          // Binary data follows: find the '_' marker and stop.
          if (self_closing) fail("bad XML: empty <AppendedData/>");
          skip_space();
          if (p_ >= b_.size() || b_[p_] != '_') fail("bad appended data: missing the '_' marker");
          doc.appended = index;
          doc.appended_data = p_ + 1;
          return doc;
        }
        if (!self_closing) {
          stack.push_back(index);
          if (stack.size() > kMaxDepth) fail("bad XML: elements nested too deeply");
        }
      }
    }
    if (!stack.empty()) fail("truncated XML (<" + doc.elements[stack.back()].name + "> is not closed)");
    if (doc.elements.empty()) fail("not an XML file (no root element)");
    return doc;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { format_error(path_, what); }

  bool has_content(std::size_t begin, std::size_t end) const {
    for (std::size_t i = begin; i < end; ++i) {
      if (!std::isspace(static_cast<unsigned char>(b_[i]))) return true;
    }
    return false;
  }
  bool starts_with(const char* s) const {
    const std::size_t n = std::strlen(s);
    return b_.size() - p_ >= n && std::memcmp(b_.data() + p_, s, n) == 0;
  }
  void skip_past(const char* s) {
    const std::size_t n = std::strlen(s);
    while (p_ < b_.size() && !starts_with(s)) ++p_;
    if (p_ >= b_.size()) fail("truncated XML (unterminated markup)");
    p_ += n;
  }
  void skip_space() {
    while (p_ < b_.size() && std::isspace(static_cast<unsigned char>(b_[p_]))) ++p_;
  }
  void expect(char c) {
    if (p_ >= b_.size()) fail("truncated XML");
    if (b_[p_] != c) fail(std::string("bad XML: expected '") + c + "'");
    ++p_;
  }
  std::string read_name() {
    const std::size_t start = p_;
    while (p_ < b_.size() && (std::isalnum(static_cast<unsigned char>(b_[p_])) || b_[p_] == '_' || b_[p_] == ':' ||
                              b_[p_] == '-' || b_[p_] == '.'))
      ++p_;
    if (p_ == start) fail(p_ >= b_.size() ? "truncated XML" : "bad XML: expected a name");
    return std::string(b_.data() + start, p_ - start);
  }

  const std::string& path_;
  const std::vector<char>& b_;
  std::size_t p_ = 0;
};

// A stream of decoded bytes (raw or base64) with an upper bound on its length.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  // Returns fewer than `n` bytes only at the end of the data.
  virtual std::size_t read(std::uint8_t* out, std::size_t n) = 0;
  virtual std::uint64_t max_remaining() const = 0;
};

class RawSource final : public ByteSource {
 public:
  RawSource(const char* begin, const char* end) : p_(begin), end_(end) {}
  std::size_t read(std::uint8_t* out, std::size_t n) override {
    const std::size_t take = std::min<std::size_t>(n, static_cast<std::size_t>(end_ - p_));
    std::memcpy(out, p_, take);
    p_ += take;
    return take;
  }
  std::uint64_t max_remaining() const override { return static_cast<std::uint64_t>(end_ - p_); }

 private:
  const char* p_;
  const char* end_;
};

// Base64 that tolerates padding between groups (VTK encodes a compressed
// array's header and its data separately) and ends at '<' or the range end.
class Base64Source final : public ByteSource {
 public:
  Base64Source(const char* begin, const char* end, const std::string& path) : p_(begin), end_(end), path_(path) {}
  std::size_t read(std::uint8_t* out, std::size_t n) override {
    std::size_t got = 0;
    while (got < n) {
      if (pending_pos_ < pending_size_) {
        const std::size_t take = std::min(n - got, pending_size_ - pending_pos_);
        std::memcpy(out + got, pending_ + pending_pos_, take);
        pending_pos_ += take;
        got += take;
        continue;
      }
      if (!decode_group()) break;
    }
    return got;
  }
  std::uint64_t max_remaining() const override {
    return static_cast<std::uint64_t>(end_ - p_) / 4 * 3 + 3 + (pending_size_ - pending_pos_);
  }

 private:
  static int value_of(char c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  }
  bool decode_group() {
    int values[4] = {0, 0, 0, 0};
    int count = 0, padding = 0;
    while (count < 4) {
      while (p_ < end_ && std::isspace(static_cast<unsigned char>(*p_))) ++p_;
      if (p_ == end_ || *p_ == '<') break;
      const char c = *p_++;
      if (c == '=') {
        if (count < 2) format_error(path_, "corrupt base64 data (misplaced '=')");
        ++padding;
        values[count++] = 0;
        continue;
      }
      if (padding > 0) format_error(path_, "corrupt base64 data (data after '=' padding)");
      const int v = value_of(c);
      if (v < 0) format_error(path_, "corrupt base64 data (invalid character)");
      values[count++] = v;
    }
    if (count == 0) return false;
    if (count < 4) format_error(path_, "truncated base64 data");
    const std::uint32_t bits = (std::uint32_t(values[0]) << 18) | (std::uint32_t(values[1]) << 12) |
                               (std::uint32_t(values[2]) << 6) | std::uint32_t(values[3]);
    pending_[0] = static_cast<std::uint8_t>(bits >> 16);
    pending_[1] = static_cast<std::uint8_t>(bits >> 8);
    pending_[2] = static_cast<std::uint8_t>(bits);
    pending_size_ = static_cast<std::size_t>(3 - padding);
    pending_pos_ = 0;
    return true;
  }

  const char* p_;
  const char* end_;
  const std::string& path_;
  std::uint8_t pending_[3] = {};
  std::size_t pending_size_ = 0, pending_pos_ = 0;
};

struct Encoding {
  bool big_endian = false;
  bool header64 = false;
  bool compressed = false;
};

std::uint64_t read_header_word(ByteSource& source, const Encoding& enc, const std::string& path, const char* what) {
  std::uint8_t bytes[8] = {};
  const std::size_t size = enc.header64 ? 8 : 4;
  if (source.read(bytes, size) != size) format_error(path, std::string("truncated data (") + what + ")");
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < size; ++i) {
    const std::size_t shift = enc.big_endian ? (size - 1 - i) * 8 : i * 8;
    v |= std::uint64_t(bytes[i]) << shift;
  }
  return v;
}

// Reads one binary array (after its header) into `values` (count samples),
// allocated once the headers have been checked against the data available.
void read_binary_array(ByteSource& source, const Encoding& enc, std::uint64_t expected, ScalarType type,
                       std::vector<float>& values, std::size_t count, const std::string& path,
                       const std::string& what) {
  const auto allocate = [&values, count]() {
    values.resize(count);
    return values.data();
  };
  const std::uint64_t word = enc.header64 ? 8 : 4;
  if (!enc.compressed) {
    const std::uint64_t bytes = read_header_word(source, enc, path, "array header");
    if (bytes != expected)
      format_error(path, "size mismatch: " + what + " holds " + std::to_string(bytes) + " bytes but its extent needs " +
                             std::to_string(expected));
    if (bytes > source.max_remaining())
      format_error(path, "truncated data in " + what + " (" + std::to_string(expected) + " bytes declared)");
    SampleDecoder decoder(allocate(), count, type, enc.big_endian);
    std::vector<std::uint8_t> chunk(std::size_t{1} << 18);
    while (!decoder.full()) {
      const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(chunk.size(), decoder.bytes_remaining()));
      const std::size_t got = source.read(chunk.data(), want);
      if (got == 0) format_error(path, "truncated data in " + what);
      decoder.push(chunk.data(), got);
    }
    return;
  }

  const std::uint64_t blocks = read_header_word(source, enc, path, "compression header");
  const std::uint64_t block_size = read_header_word(source, enc, path, "compression header");
  const std::uint64_t last_size = read_header_word(source, enc, path, "compression header");
  if (blocks == 0) {
    if (expected != 0) format_error(path, "size mismatch: " + what + " has no compressed blocks");
    allocate();
    return;
  }
  if (block_size == 0 || last_size > block_size) format_error(path, "corrupt compression header in " + what);
  if (blocks > source.max_remaining() / word) format_error(path, "truncated compression header in " + what);
  std::uint64_t total = 0;
  if (__builtin_mul_overflow(blocks - 1, block_size, &total) ||
      __builtin_add_overflow(total, last_size ? last_size : block_size, &total) || total != expected)
    format_error(path, "size mismatch: the compressed blocks of " + what + " do not hold the " + std::to_string(expected) +
                           " bytes its extent needs");
  std::vector<std::uint64_t> sizes(static_cast<std::size_t>(blocks));
  std::uint64_t compressed_total = 0;
  for (auto& s : sizes) {
    s = read_header_word(source, enc, path, "compression header");
    if (s == 0 || __builtin_add_overflow(compressed_total, s, &compressed_total))
      format_error(path, "corrupt compression header in " + what);
  }
  if (compressed_total > source.max_remaining())
    format_error(path, "truncated data in " + what + " (" + std::to_string(compressed_total) + " compressed bytes declared)");
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    const std::uint64_t out = (b + 1 == sizes.size() && last_size) ? last_size : block_size;
    if (out > max_inflated_size(sizes[b]))
      format_error(path, "corrupt compression header in " + what + " (impossible compression ratio)");
  }

  // Memory as the blocks inflate: a block may claim up to 1032 times its size.
  reserve_samples(values, count, path);
  SampleDecoder decoder(values, count, type, enc.big_endian);
  std::vector<std::uint8_t> input, output(std::size_t{1} << 18);
  z_stream zs{};
  if (inflateInit(&zs) != Z_OK) throw Error(ErrorKind::Io, path + ": cannot initialise zlib");
  struct Guard {
    z_stream* zs;
    ~Guard() { inflateEnd(zs); }
  } guard{&zs};
  for (std::size_t b = 0; b < sizes.size(); ++b) {
    const std::uint64_t block_out = (b + 1 == sizes.size() && last_size) ? last_size : block_size;
    input.resize(static_cast<std::size_t>(sizes[b]));
    if (source.read(input.data(), input.size()) != input.size()) format_error(path, "truncated compressed data in " + what);
    if (inflateReset(&zs) != Z_OK) throw Error(ErrorKind::Io, path + ": zlib failure");
    zs.next_in = input.data();
    zs.avail_in = static_cast<uInt>(input.size());
    std::uint64_t produced_total = 0;
    while (true) {
      zs.next_out = output.data();
      zs.avail_out = static_cast<uInt>(output.size());
      const int status = inflate(&zs, Z_NO_FLUSH);
      const std::size_t produced = output.size() - zs.avail_out;
      produced_total += produced;
      if (produced_total > block_out)
        format_error(path, "corrupt zlib data in " + what + " (a block inflates beyond its declared size)");
      decoder.push(output.data(), produced);
      if (status == Z_STREAM_END) break;
      if (status == Z_BUF_ERROR || (status == Z_OK && zs.avail_in == 0 && produced == 0))
        format_error(path, "truncated zlib data in " + what);
      if (status != Z_OK)
        format_error(path, "corrupt zlib data in " + what + " (" + (zs.msg ? zs.msg : "error " + std::to_string(status)) + ")");
    }
    if (produced_total != block_out)
      format_error(path, "corrupt zlib data in " + what + " (a block inflates to " + std::to_string(produced_total) +
                             " bytes, " + std::to_string(block_out) + " declared)");
  }
  if (!decoder.full()) format_error(path, "truncated data in " + what);
}

std::optional<ScalarType> vti_type(const std::string& name, bool& known) {
  known = true;
  if (name == "Int8" || name == "Char") return ScalarType::Int8;
  if (name == "UInt8" || name == "UChar") return ScalarType::UInt8;
  if (name == "Int16") return ScalarType::Int16;
  if (name == "UInt16") return ScalarType::UInt16;
  if (name == "Int32") return ScalarType::Int32;
  if (name == "UInt32") return ScalarType::UInt32;
  if (name == "Float32") return ScalarType::Float32;
  if (name == "Float64") return ScalarType::Float64;
  known = name == "Int64" || name == "UInt64" || name == "String" || name == "Bit" || name == "IdType";
  return std::nullopt;
}

std::vector<double> numbers(const std::string& path, const std::string& what, const std::string& text, std::size_t n,
                            bool integral) {
  const auto tokens = split_whitespace(text);
  if (tokens.size() != n) format_error(path, "bad " + what + " '" + text + "' (expected " + std::to_string(n) + " numbers)");
  std::vector<double> values;
  for (const auto t : tokens) {
    double v = 0;
    std::int64_t i = 0;
    if (integral ? !parse_int64(t, i) : !parse_double(t, v)) format_error(path, "bad " + what + " '" + text + "'");
    if (integral) {
      if (i < -(std::int64_t{1} << 40) || i > (std::int64_t{1} << 40)) format_error(path, "bad " + what + " '" + text + "'");
      v = static_cast<double>(i);
    }
    if (!std::isfinite(v)) format_error(path, "bad " + what + " '" + text + "'");
    values.push_back(v);
  }
  return values;
}

const XmlElement* child_named(const XmlDocument& doc, const XmlElement& parent, const char* name) {
  for (std::size_t c : parent.children) {
    if (doc.elements[c].name == name) return &doc.elements[c];
  }
  return nullptr;
}

std::string name_of(const XmlElement* a) {
  const auto* n = a->attribute("Name");
  return n ? *n : std::string();
}

// The root's byte order, header size and compressor.
Encoding read_encoding(const std::string& path, const XmlElement& root) {
  Encoding enc;
  if (const auto* order = root.attribute("byte_order")) {
    if (*order == "BigEndian") enc.big_endian = true;
    else if (*order != "LittleEndian") format_error(path, "bad byte_order '" + *order + "'");
  }
  if (const auto* header = root.attribute("header_type")) {
    if (*header == "UInt64") enc.header64 = true;
    else if (*header != "UInt32") format_error(path, "bad header_type '" + *header + "' (UInt32 or UInt64)");
  }
  if (const auto* compressor = root.attribute("compressor")) {
    if (*compressor == "vtkZLibDataCompressor") enc.compressed = true;
    else if (!compressor->empty())
      format_error(path, "unsupported compressor '" + *compressor + "' (only vtkZLibDataCompressor)");
  }
  return enc;
}

// The one <Piece> of <ImageData>.
const XmlElement& single_piece(const std::string& path, const XmlDocument& doc, const XmlElement& image) {
  std::vector<const XmlElement*> pieces;
  for (std::size_t c : image.children) {
    if (doc.elements[c].name == "Piece") pieces.push_back(&doc.elements[c]);
  }
  if (pieces.empty()) format_error(path, "missing <Piece> element");
  if (pieces.size() > 1) format_error(path, "unsupported: " + std::to_string(pieces.size()) + " pieces (one is supported)");
  return *pieces[0];
}

// Dims, spacing and origin from the extent, Origin, Spacing and an
// axis-aligned Direction (a flipped axis becomes a negative spacing).
void read_grid_geometry(const std::string& path, const XmlElement& image, const XmlElement& piece, Volume& volume) {
  const std::string* extent_text = piece.attribute("Extent");
  if (!extent_text) extent_text = image.attribute("WholeExtent");
  if (!extent_text) format_error(path, "missing WholeExtent / Extent");
  const auto extent = numbers(path, "Extent", *extent_text, 6, true);
  for (int a = 0; a < 3; ++a) {
    if (extent[2 * a + 1] < extent[2 * a]) format_error(path, "bad Extent '" + *extent_text + "'");
    volume.dims[a] = static_cast<std::size_t>(extent[2 * a + 1] - extent[2 * a] + 1);
  }
  std::vector<double> origin{0, 0, 0}, spacing{1, 1, 1}, direction{1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (const auto* t = image.attribute("Origin")) origin = numbers(path, "Origin", *t, 3, false);
  if (const auto* t = image.attribute("Spacing")) spacing = numbers(path, "Spacing", *t, 3, false);
  if (const auto* t = image.attribute("Direction")) direction = numbers(path, "Direction", *t, 9, false);
  double axis_sign[3];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      const double d = direction[3 * r + c];
      if (r == c ? std::abs(std::abs(d) - 1) > 1e-9 : std::abs(d) > 1e-9)
        format_error(path, "unsupported Direction (only axis-aligned grids are supported)");
    }
    axis_sign[r] = direction[4 * r] < 0 ? -1 : 1;
  }
  const double sx = spacing[0] * axis_sign[0], sy = spacing[1] * axis_sign[1], sz = spacing[2] * axis_sign[2];
  volume.spacing = {sx, sy, sz};
  volume.origin = {origin[0] + sx * extent[0], origin[1] + sy * extent[2], origin[2] + sz * extent[4]};
  for (double s : {sx, sy, sz}) {
    if (s == 0) format_error(path, "bad Spacing (zero)");
  }
}

// The point-data array to read: options.field, else the Scalars attribute's,
// else the first.
const XmlElement& pick_array(const std::string& path, const XmlDocument& doc, const XmlElement& piece,
                             const VolumeReadOptions& options) {
  const auto& el = doc.elements;
  const XmlElement* point_data = child_named(doc, piece, "PointData");
  std::vector<const XmlElement*> arrays;
  if (point_data) {
    for (std::size_t c : point_data->children) {
      if (el[c].name == "DataArray") arrays.push_back(&el[c]);
    }
  }
  std::string wanted = options.field;
  if (wanted.empty() && point_data) {
    if (const auto* s = point_data->attribute("Scalars")) wanted = *s;
    if (!wanted.empty() &&
        std::none_of(arrays.begin(), arrays.end(), [&](const XmlElement* a) { return name_of(a) == wanted; }))
      wanted.clear();  // a dangling Scalars attribute: fall back to the first array
  }
  if (wanted.empty()) {
    if (arrays.empty()) format_error(path, "missing field: no point data arrays");
    return *arrays[0];
  }
  for (const auto* a : arrays) {
    if (name_of(a) == wanted) return *a;
  }
  std::string where;
  if (const XmlElement* cell = child_named(doc, piece, "CellData")) {
    for (std::size_t c : cell->children) {
      if (el[c].name == "DataArray" && name_of(&el[c]) == wanted) where = " (it is cell data)";
    }
  }
  std::string list;
  for (const auto* a : arrays) list += (list.empty() ? "" : ", ") + name_of(a);
  format_error(path, "missing field '" + wanted + "'" + where + " (point arrays: " + (list.empty() ? "none" : list) + ")");
}

// The array's samples, ascii, inline binary (base64) or appended (raw or
// base64), into volume.values; volume.dims must be set.
void read_array_samples(const std::string& path, const std::vector<char>& buffer, const XmlDocument& doc,
                        const Encoding& enc, const XmlElement& array, Volume& volume) {
  const std::string what = "array '" + name_of(&array) + "'";
  const std::string* type_name = array.attribute("type");
  if (!type_name) format_error(path, "bad " + what + ": missing type");
  bool known = false;
  const auto type = vti_type(*type_name, known);
  if (!type) format_error(path, std::string(known ? "unsupported" : "unknown") + " data type '" + *type_name + "' in " + what);
  volume.source_type = *type;
  if (const auto* nc = array.attribute("NumberOfComponents")) {
    std::int64_t n = 0;
    if (!parse_int64(*nc, n) || n < 1) format_error(path, "bad NumberOfComponents in " + what);
    if (n != 1) format_error(path, what + " has " + std::to_string(n) + " components (a scalar field needs 1)");
  }
  const std::size_t sample_size = scalar_type_size(*type);
  const std::size_t count = checked_sample_count(volume.dims, sample_size, path);
  const std::uint64_t expected = static_cast<std::uint64_t>(count) * sample_size;

  const std::string* format_attr = array.attribute("format");
  const std::string format = format_attr ? *format_attr : "ascii";
  const char* text_begin = buffer.data() + array.text_begin;
  const char* text_end = buffer.data() + array.text_end;
  if (format == "ascii") {
    if (count > static_cast<std::size_t>(text_end - text_begin) / 2 + 1)
      format_error(path, "truncated data in " + what + ": the text cannot hold " + std::to_string(count) + " values");
    volume.values.resize(count);
    parse_text_samples(text_begin, text_end, count, *type, false, true, volume.values.data(), path, what);
  } else if (format == "binary") {
    Base64Source source(text_begin, text_end, path);
    read_binary_array(source, enc, expected, *type, volume.values, count, path, what);
  } else if (format == "appended") {
    if (!doc.appended) format_error(path, "missing <AppendedData> for " + what);
    const std::string* offset_text = array.attribute("offset");
    std::int64_t offset = 0;
    if (!offset_text || !parse_int64(*offset_text, offset) || offset < 0)
      format_error(path, "bad or missing offset in " + what);
    const std::uint64_t start = doc.appended_data + static_cast<std::uint64_t>(offset);
    if (start > buffer.size()) format_error(path, "truncated appended data (" + what + " starts past the end of the file)");
    const std::string* encoding = doc.elements[*doc.appended].attribute("encoding");
    const std::string appended_encoding = encoding ? *encoding : "raw";
    if (appended_encoding == "raw") {
      RawSource source(buffer.data() + start, buffer.data() + buffer.size());
      read_binary_array(source, enc, expected, *type, volume.values, count, path, what);
    } else if (appended_encoding == "base64") {
      Base64Source source(buffer.data() + start, buffer.data() + buffer.size(), path);
      read_binary_array(source, enc, expected, *type, volume.values, count, path, what);
    } else {
      format_error(path, "unsupported AppendedData encoding '" + appended_encoding + "'");
    }
  } else {
    format_error(path, "unsupported format '" + format + "' in " + what);
  }
}

}  // namespace

Volume read_vti(const std::string& path, const VolumeReadOptions& options) {
  const std::vector<char> buffer = InputFile(path).read_all();
  const XmlDocument doc = XmlParser(path, buffer).parse();
  const XmlElement& root = doc.elements[0];
  if (root.name != "VTKFile") format_error(path, "not a VTK XML file (root element <" + root.name + ">)");
  const std::string* file_type = root.attribute("type");
  if (!file_type || *file_type != "ImageData")
    format_error(path, "unsupported VTK XML type '" + (file_type ? *file_type : std::string("?")) + "' (only ImageData)");
  const Encoding enc = read_encoding(path, root);
  const XmlElement* image = child_named(doc, root, "ImageData");
  if (!image) format_error(path, "missing <ImageData> element");
  const XmlElement& piece = single_piece(path, doc, *image);

  Volume volume;
  read_grid_geometry(path, *image, piece, volume);
  read_array_samples(path, buffer, doc, enc, pick_array(path, doc, piece, options), volume);
  make_spacing_positive(volume);
  check_geometry(volume, path);
  return volume;
}

}  // namespace isowave::detail
