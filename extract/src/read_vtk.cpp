// Legacy VTK (.vtk) STRUCTURED_POINTS, ASCII or BINARY (big-endian). Arrays
// other than the requested scalars (VECTORS, NORMALS, FIELD, cell data, ...)
// are skipped by their declared sizes.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "volume_io_internal.h"

namespace isowave::detail {
namespace {

struct VtkType {
  std::optional<ScalarType> scalar;  // readable as volume samples
  std::size_t size = 0;              // bytes per value in BINARY files (0: bit array)
  bool skippable = true;             // string arrays cannot be skipped reliably
};

std::optional<VtkType> vtk_type(std::string_view name) {
  const std::string n = to_lower(name);
  if (n == "unsigned_char") return VtkType{ScalarType::UInt8, 1};
  if (n == "char" || n == "signed_char") return VtkType{ScalarType::Int8, 1};
  if (n == "unsigned_short") return VtkType{ScalarType::UInt16, 2};
  if (n == "short") return VtkType{ScalarType::Int16, 2};
  if (n == "unsigned_int") return VtkType{ScalarType::UInt32, 4};
  if (n == "int") return VtkType{ScalarType::Int32, 4};
  if (n == "float") return VtkType{ScalarType::Float32, 4};
  if (n == "double") return VtkType{ScalarType::Float64, 8};
  if (n == "unsigned_long" || n == "long" || n == "vtktypeint64" || n == "vtktypeuint64" || n == "vtkidtype" ||
      n == "unsigned_long_long" || n == "long_long")
    return VtkType{std::nullopt, 8};
  if (n == "bit") return VtkType{std::nullopt, 0};
  if (n == "string" || n == "utf8_string" || n == "variant") return VtkType{std::nullopt, 0, false};
  return std::nullopt;
}

// VTK writes names with special characters as %XX.
std::string decode_name(std::string_view name) {
  std::string out;
  for (std::size_t i = 0; i < name.size(); ++i) {
    if (name[i] == '%' && i + 2 < name.size() && std::isxdigit(static_cast<unsigned char>(name[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(name[i + 2]))) {
      out.push_back(static_cast<char>(std::stoi(std::string(name.substr(i + 1, 2)), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(name[i]);
    }
  }
  return out;
}

class VtkParser {
 public:
  VtkParser(const std::string& path, const VolumeReadOptions& options)
      : path_(path), options_(options), buffer_(InputFile(path).read_all()) {}

  Volume read();

 private:
  // The next line (after its newline), or nullopt at the end of the file.
  std::optional<std::string_view> raw_line() {
    if (pos_ >= buffer_.size()) return std::nullopt;
    const char* begin = buffer_.data() + pos_;
    const void* nl = std::memchr(begin, '\n', buffer_.size() - pos_);
    const std::size_t length = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : buffer_.size() - pos_;
    pos_ += length + (nl ? 1 : 0);
    std::string_view line(begin, length);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line;
  }

  // The tokens of the next line that holds any, or empty at the end of the file.
  std::vector<std::string_view> next_line() {
    while (auto line = raw_line()) {
      auto tokens = split_whitespace(*line);
      if (!tokens.empty()) return tokens;
    }
    return {};
  }

  // True (and consumed) when the next line starts with `keyword`.
  bool peek_keyword(std::string_view keyword) {
    std::size_t p = pos_;
    if (!binary_) {
      while (p < buffer_.size() && std::isspace(static_cast<unsigned char>(buffer_[p]))) ++p;
    }
    if (buffer_.size() - p < keyword.size()) return false;
    if (!iequals(std::string_view(buffer_.data() + p, keyword.size()), keyword)) return false;
    if (p + keyword.size() < buffer_.size() && !std::isspace(static_cast<unsigned char>(buffer_[p + keyword.size()])))
      return false;
    pos_ = p;
    raw_line();
    return true;
  }

  [[noreturn]] void fail(const std::string& what) const { format_error(path_, what); }

  std::size_t count_token(std::string_view token, const char* what) const {
    std::int64_t v = 0;
    if (!parse_int64(token, v) || v < 0)
      fail("bad header: invalid " + std::string(what) + " '" + std::string(token) + "'");
    return static_cast<std::size_t>(v);
  }

  std::size_t multiply(std::size_t a, std::size_t b) const {
    std::size_t r = 0;
    if (__builtin_mul_overflow(a, b, &r)) fail("bad header: array size overflows");
    return r;
  }

  VtkType type_of(std::string_view name) const {
    const auto type = vtk_type(name);
    if (!type) fail("unknown data type '" + std::string(name) + "'");
    return *type;
  }

  // Skips `values` values of `type` (ASCII tokens or BINARY bytes).
  void skip_values(std::size_t values, const VtkType& type, const std::string& what) {
    if (!type.skippable) fail("cannot skip string array " + what + " (string arrays are not supported)");
    if (binary_) {
      const std::size_t bytes = type.size == 0 ? (values + 7) / 8 : multiply(values, type.size);
      if (bytes > buffer_.size() - pos_) fail("truncated data in " + what);
      pos_ += bytes;
      return;
    }
    for (std::size_t i = 0; i < values; ++i) {
      while (pos_ < buffer_.size() && std::isspace(static_cast<unsigned char>(buffer_[pos_]))) ++pos_;
      if (pos_ == buffer_.size()) fail("truncated data in " + what);
      while (pos_ < buffer_.size() && !std::isspace(static_cast<unsigned char>(buffer_[pos_]))) ++pos_;
    }
  }

  // Skips an optional METADATA block (ends at a blank line).
  void skip_metadata() {
    while (peek_keyword("METADATA")) {
      while (auto line = raw_line()) {
        if (trim(*line).empty()) break;
      }
    }
  }

  using Tokens = std::vector<std::string_view>;
  // Steps of read(), in file order.
  void read_header();
  Tokens read_geometry();  // returns the POINT_DATA / CELL_DATA line
  void read_attributes(Tokens tokens);
  [[noreturn]] void fail_missing_field() const;
  // Skips a FIELD block whose header line is `t` (FIELD name numArrays); true
  // when an array of it was the wanted field and was read.
  bool skip_field_block(const Tokens& t, std::size_t elements, bool point_data, bool attribute);
  void read_samples(const VtkType& type, const std::string& what);
  // Called for each point-data candidate; true when it was read.
  bool consider(const std::string& name, const char* kind, std::size_t components, std::size_t tuples,
                const VtkType& type, bool point_data, bool is_scalars);

  std::string path_;
  const VolumeReadOptions& options_;
  std::vector<char> buffer_;
  std::size_t pos_ = 0;
  bool binary_ = false;
  Volume volume_;
  std::size_t points_ = 0;
  bool found_ = false;
  std::vector<std::string> seen_;
};

void VtkParser::read_samples(const VtkType& type, const std::string& what) {
  volume_.source_type = *type.scalar;
  const std::size_t count = points_;
  if (binary_) {
    const std::size_t bytes = multiply(count, type.size);
    if (bytes > buffer_.size() - pos_)
      fail("truncated data in " + what + ": " + std::to_string(buffer_.size() - pos_) + " bytes left for " +
           std::to_string(count) + " " + to_string(*type.scalar) + " values (" + std::to_string(bytes) + " bytes)");
    volume_.values.resize(count);
    decode_samples(reinterpret_cast<const std::uint8_t*>(buffer_.data() + pos_), count, *type.scalar, true,
                   volume_.values.data());
    pos_ += bytes;
  } else {
    if (count > (buffer_.size() - pos_) / 2 + 1)
      fail("truncated data in " + what + ": the rest of the file cannot hold " + std::to_string(count) + " values");
    volume_.values.resize(count);
    parse_text_samples(buffer_.data() + pos_, buffer_.data() + buffer_.size(), count, *type.scalar, false, false,
                       volume_.values.data(), path_, what);
  }
}

bool VtkParser::consider(const std::string& name, const char* kind, std::size_t components, std::size_t tuples,
                         const VtkType& type, bool point_data, bool is_scalars) {
  seen_.push_back(name + " (" + kind + (point_data ? " point data" : " cell data") + ")");
  if (found_ || !point_data) return false;
  const bool wanted = options_.field.empty() ? is_scalars : name == options_.field;
  if (!wanted) return false;
  const std::string what = std::string(kind) + " array '" + name + "'";
  if (std::strcmp(kind, "SCALARS") != 0 && std::strcmp(kind, "FIELD") != 0)
    fail(what + " is not a scalar array");
  if (components != 1) fail(what + " has " + std::to_string(components) + " components (a scalar field needs 1)");
  if (tuples != points_) fail(what + " has " + std::to_string(tuples) + " values for " + std::to_string(points_) + " points");
  if (!type.scalar) fail(what + " has an unsupported data type");
  read_samples(type, what);
  found_ = true;
  return true;
}

void VtkParser::read_header() {
  auto header = raw_line();
  if (!header || header->rfind("# vtk DataFile Version", 0) != 0)
    fail("not a legacy VTK file (missing '# vtk DataFile Version' header)");
  if (!raw_line()) fail("truncated header (no title line)");
  const auto format = next_line();
  if (format.empty()) fail("truncated header (no ASCII/BINARY line)");
  if (iequals(format[0], "BINARY")) binary_ = true;
  else if (!iequals(format[0], "ASCII")) fail("bad header: expected ASCII or BINARY, got '" + std::string(format[0]) + "'");

  const auto tokens = next_line();
  if (tokens.size() < 2 || !iequals(tokens[0], "DATASET")) fail("bad header: expected 'DATASET STRUCTURED_POINTS'");
  if (!iequals(tokens[1], "STRUCTURED_POINTS"))
    fail("unsupported dataset type '" + std::string(tokens[1]) + "' (only STRUCTURED_POINTS is supported)");
}

VtkParser::Tokens VtkParser::read_geometry() {
  std::optional<std::array<std::size_t, 3>> dims;
  Vec3 spacing{1, 1, 1}, origin{0, 0, 0};
  const auto read_vec = [this](const Tokens& t, const char* what) {
    if (t.size() < 4) fail(std::string("bad header: ") + what + " needs 3 numbers");
    double v[3];
    for (int i = 0; i < 3; ++i) {
      if (!parse_double(t[i + 1], v[i]) || !std::isfinite(v[i]))
        fail(std::string("bad header: invalid number '") + std::string(t[i + 1]) + "' in " + what);
    }
    return Vec3{v[0], v[1], v[2]};
  };

  Tokens tokens;
  while (true) {
    tokens = next_line();
    if (tokens.empty()) fail("truncated header (no POINT_DATA section)");
    const std::string key = to_lower(tokens[0]);
    if (key == "dimensions") {
      if (tokens.size() < 4) fail("bad header: DIMENSIONS needs 3 numbers");
      std::array<std::size_t, 3> d{};
      for (int i = 0; i < 3; ++i) {
        d[i] = count_token(tokens[i + 1], "dimension");
        if (d[i] == 0) fail("bad header: DIMENSIONS must be positive");
      }
      dims = d;
    } else if (key == "spacing" || key == "aspect_ratio") {
      spacing = read_vec(tokens, "SPACING");
    } else if (key == "origin") {
      origin = read_vec(tokens, "ORIGIN");
    } else if (key == "field") {
      skip_field_block(tokens, 0, false, false);
    } else if (key == "point_data" || key == "cell_data") {
      break;
    } else if (key == "metadata") {
      while (auto line = raw_line()) {
        if (trim(*line).empty()) break;
      }
    } else {
      fail("bad header: unexpected keyword '" + std::string(tokens[0]) + "' in the STRUCTURED_POINTS geometry");
    }
  }
  if (!dims) fail("bad header: missing DIMENSIONS");
  volume_.dims = *dims;
  volume_.spacing = spacing;
  volume_.origin = origin;
  points_ = checked_sample_count(volume_.dims, 1, path_);
  return tokens;
}

bool VtkParser::skip_field_block(const Tokens& t, std::size_t elements, bool point_data, bool attribute) {
  if (t.size() < 3) fail("bad header: FIELD needs a name and an array count");
  const std::size_t arrays = count_token(t[2], "FIELD array count");
  for (std::size_t a = 0; a < arrays; ++a) {
    skip_metadata();
    const auto line = next_line();
    if (line.empty()) fail("truncated FIELD data (array " + std::to_string(a) + " of " + std::to_string(arrays) + ")");
    if (iequals(line[0], "NULL_ARRAY")) continue;
    if (line.size() < 4) fail("bad header: FIELD array line needs name, components, tuples and type");
    const std::string name = decode_name(line[0]);
    const std::size_t components = count_token(line[1], "component count");
    const std::size_t tuples = count_token(line[2], "tuple count");
    const VtkType type = type_of(line[3]);
    if (attribute && tuples == elements &&
        consider(name, "FIELD", components, tuples, type, point_data, false))
      return true;
    skip_values(multiply(components, tuples), type, "FIELD array '" + name + "'");
  }
  return false;
}

void VtkParser::read_attributes(Tokens tokens) {
  bool point_data = false;
  std::size_t elements = 0;
  while (!tokens.empty()) {
    const std::string key = to_lower(tokens[0]);
    const auto need = [&](std::size_t n) {
      if (tokens.size() < n) fail("bad header: incomplete " + std::string(tokens[0]) + " line");
    };
    if (key == "point_data" || key == "cell_data") {
      need(2);
      point_data = key == "point_data";
      elements = count_token(tokens[1], "POINT_DATA/CELL_DATA count");
      if (point_data && elements != points_)
        fail("POINT_DATA count " + std::to_string(elements) + " does not match DIMENSIONS (" + std::to_string(points_) +
             " points)");
    } else if (key == "scalars") {
      need(3);
      const std::string name = decode_name(tokens[1]);
      const VtkType type = type_of(tokens[2]);
      std::size_t components = 1;
      if (tokens.size() >= 4) {
        components = count_token(tokens[3], "SCALARS component count");
        if (components < 1 || components > 4) fail("bad header: SCALARS component count must be 1 to 4");
      }
      peek_keyword("LOOKUP_TABLE");
      if (consider(name, "SCALARS", components, elements, type, point_data, true)) break;
      skip_values(multiply(elements, components), type, "SCALARS array '" + name + "'");
    } else if (key == "color_scalars") {
      need(3);
      const std::size_t n = count_token(tokens[2], "COLOR_SCALARS component count");
      consider(decode_name(tokens[1]), "COLOR_SCALARS", n, elements, VtkType{std::nullopt, 1}, point_data, false);
      skip_values(multiply(elements, n), binary_ ? VtkType{std::nullopt, 1} : VtkType{std::nullopt, 4},
                  "COLOR_SCALARS array");
    } else if (key == "lookup_table") {
      need(3);
      const std::size_t n = count_token(tokens[2], "LOOKUP_TABLE size");
      skip_values(multiply(n, 4), VtkType{std::nullopt, 1}, "LOOKUP_TABLE");
    } else if (key == "vectors" || key == "normals" || key == "tensors" || key == "tensors6" ||
               key == "global_ids" || key == "pedigree_ids") {
      need(3);
      const std::size_t n = key == "tensors" ? 9 : key == "tensors6" ? 6 : (key == "global_ids" || key == "pedigree_ids") ? 1 : 3;
      const VtkType type = type_of(tokens[2]);
      consider(decode_name(tokens[1]), key == "vectors" ? "VECTORS" : key == "normals" ? "NORMALS" : "TENSORS/IDS", n,
               elements, type, point_data, false);
      skip_values(multiply(elements, n), type, std::string(tokens[0]) + " array");
    } else if (key == "texture_coordinates") {
      need(4);
      const std::size_t n = count_token(tokens[2], "TEXTURE_COORDINATES dimension");
      const VtkType type = type_of(tokens[3]);
      consider(decode_name(tokens[1]), "TEXTURE_COORDINATES", n, elements, type, point_data, false);
      skip_values(multiply(elements, n), type, "TEXTURE_COORDINATES array");
    } else if (key == "field") {
      if (skip_field_block(tokens, elements, point_data, true)) break;
    } else if (key == "metadata") {
      while (auto line = raw_line()) {
        if (trim(*line).empty()) break;
      }
    } else {
      fail("bad header: unexpected keyword '" + std::string(tokens[0]) + "' in the attribute data");
    }
    tokens = next_line();
  }

}

void VtkParser::fail_missing_field() const {
  std::string list;
  for (const auto& s : seen_) list += (list.empty() ? "" : ", ") + s;
  if (list.empty()) list = "none";
  if (options_.field.empty()) fail("missing field: no SCALARS point data (arrays found: " + list + ")");
  fail("missing field '" + options_.field + "' (arrays found: " + list + ")");
}

Volume VtkParser::read() {
  read_header();
  read_attributes(read_geometry());
  if (!found_) fail_missing_field();
  make_spacing_positive(volume_);
  check_geometry(volume_, path_);
  return std::move(volume_);
}

}  // namespace

Volume read_vtk_legacy(const std::string& path, const VolumeReadOptions& options) {
  VtkParser parser(path, options);
  return parser.read();
}

}  // namespace isowave::detail
