#include "isowave/core/mesh_io.h"

#include <algorithm>
#include <cmath>
#include <cctype>
#include <charconv>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <sys/stat.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/parallel_reduce.h>

#include "isowave/core/atomic_file.h"
#include "isowave/core/error.h"

namespace isowave {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw Error(ErrorKind::Format, path + ": " + what);
}

std::string lower_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// Cursor over text: whitespace-separated tokens, line-aware.
class TextCursor {
 public:
  TextCursor(const char* begin, const char* end) : p_(begin), end_(end) {}
  bool at_end() const { return p_ >= end_; }
  const char* position() const { return p_; }
  void skip_spaces() {  // within a line
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r')) ++p_;
  }
  void skip_whitespace() {
    while (p_ < end_ && std::isspace(static_cast<unsigned char>(*p_))) ++p_;
  }
  bool at_line_end() {
    skip_spaces();
    return p_ >= end_ || *p_ == '\n';
  }
  void next_line() {
    while (p_ < end_ && *p_ != '\n') ++p_;
    if (p_ < end_) ++p_;
  }
  std::string_view token() {
    skip_whitespace();
    const char* start = p_;
    while (p_ < end_ && !std::isspace(static_cast<unsigned char>(*p_))) ++p_;
    return {start, static_cast<std::size_t>(p_ - start)};
  }
  std::string_view token_in_line() {
    skip_spaces();
    const char* start = p_;
    while (p_ < end_ && !std::isspace(static_cast<unsigned char>(*p_))) ++p_;
    return {start, static_cast<std::size_t>(p_ - start)};
  }

 private:
  const char* p_;
  const char* end_;
};

bool parse_double(std::string_view s, double& value) {
  if (s.empty()) return false;
  const char* first = s.data();
  if (*first == '+') ++first;
  const auto result = std::from_chars(first, s.data() + s.size(), value);
  return result.ec == std::errc() && result.ptr == s.data() + s.size();
}

template <class Int>
bool parse_integer(std::string_view s, Int& value) {
  if (s.empty()) return false;
  const char* first = s.data();
  if (*first == '+') ++first;
  const auto result = std::from_chars(first, s.data() + s.size(), value);
  return result.ec == std::errc() && result.ptr == s.data() + s.size();
}

// ---------------------------------------------------------------- PLY

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool ply_type_from_name(std::string_view name, PlyType& type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::Int8},     {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const auto& entry : kNames)
    if (name == entry.first) {
      type = entry.second;
      return true;
    }
  return false;
}

std::size_t ply_type_size(PlyType type) {
  switch (type) {
    case PlyType::Int8: case PlyType::UInt8: return 1;
    case PlyType::Int16: case PlyType::UInt16: return 2;
    case PlyType::Int32: case PlyType::UInt32: case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
  }
  return 1;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyEncoding { Ascii, BinaryLittle, BinaryBig };

// Reads scalar values from the body, binary or ASCII.
class PlyBody {
 public:
  PlyBody(const std::string& path, const char* begin, const char* end, PlyEncoding encoding)
      : path_(path), p_(begin), end_(end), text_(begin, end), encoding_(encoding) {}

  std::size_t remaining() const { return static_cast<std::size_t>(end_ - (encoding_ == PlyEncoding::Ascii ? text_.position() : p_)); }

  double read(PlyType type, const char* what) {
    if (encoding_ == PlyEncoding::Ascii) {
      const std::string_view token = text_.token();
      double value = 0;
      if (token.empty()) fail(path_, std::string("unexpected end of file while reading ") + what);
      if (!parse_double(token, value)) fail(path_, std::string("malformed number '") + std::string(token) + "' in " + what);
      return value;
    }
    const std::size_t size = ply_type_size(type);
    if (static_cast<std::size_t>(end_ - p_) < size) fail(path_, std::string("file is truncated while reading ") + what);
    unsigned char bytes[8];
    std::memcpy(bytes, p_, size);
    p_ += size;
    if (encoding_ == PlyEncoding::BinaryBig) std::reverse(bytes, bytes + size);
    switch (type) {
      case PlyType::Int8: { std::int8_t v; std::memcpy(&v, bytes, 1); return v; }
      case PlyType::UInt8: return bytes[0];
      case PlyType::Int16: { std::int16_t v; std::memcpy(&v, bytes, 2); return v; }
      case PlyType::UInt16: { std::uint16_t v; std::memcpy(&v, bytes, 2); return v; }
      case PlyType::Int32: { std::int32_t v; std::memcpy(&v, bytes, 4); return v; }
      case PlyType::UInt32: { std::uint32_t v; std::memcpy(&v, bytes, 4); return v; }
      case PlyType::Float32: { float v; std::memcpy(&v, bytes, 4); return v; }
      case PlyType::Float64: { double v; std::memcpy(&v, bytes, 8); return v; }
    }
    return 0;
  }

  bool is_ascii() const { return encoding_ == PlyEncoding::Ascii; }

 private:
  const std::string& path_;
  const char* p_;
  const char* end_;
  TextCursor text_;
  PlyEncoding encoding_;
};

std::size_t minimum_element_bytes(const PlyElement& element, bool ascii) {
  std::size_t bytes = 0;
  for (const PlyProperty& property : element.properties)
    bytes += ascii ? 2 : (property.is_list ? ply_type_size(property.count_type) : ply_type_size(property.type));
  return std::max<std::size_t>(bytes, 1);
}

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::Ascii;
  std::vector<PlyElement> elements;
  std::size_t body_start = 0;  // byte offset of the first element's data
};

// Header: lines up to "end_header".
PlyHeader read_ply_header(const std::string& path, const std::string& data) {
  const std::size_t header_end = data.find("end_header");
  if (data.compare(0, 3, "ply") != 0) fail(path, "not a PLY file (missing 'ply' magic)");
  if (header_end == std::string::npos) fail(path, "PLY header has no end_header line");
  PlyHeader result;
  result.body_start = data.find('\n', header_end);
  result.body_start = result.body_start == std::string::npos ? data.size() : result.body_start + 1;
  TextCursor header(data.data(), data.data() + header_end);
  header.next_line();
  bool have_format = false;
  while (!header.at_end()) {
    const std::string_view keyword = header.token_in_line();
    if (keyword == "format") {
      const std::string_view name = header.token_in_line();
      if (name == "ascii") result.encoding = PlyEncoding::Ascii;
      else if (name == "binary_little_endian") result.encoding = PlyEncoding::BinaryLittle;
      else if (name == "binary_big_endian") result.encoding = PlyEncoding::BinaryBig;
      else fail(path, "unknown PLY format '" + std::string(name) + "'");
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      element.name = std::string(header.token_in_line());
      if (!parse_integer(header.token_in_line(), element.count)) fail(path, "malformed element count for '" + element.name + "'");
      result.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (result.elements.empty()) fail(path, "PLY property before any element");
      PlyProperty property;
      std::string_view type_name = header.token_in_line();
      if (type_name == "list") {
        property.is_list = true;
        if (!ply_type_from_name(header.token_in_line(), property.count_type)) fail(path, "unknown PLY list count type");
        type_name = header.token_in_line();
      }
      if (!ply_type_from_name(type_name, property.type)) fail(path, "unknown PLY property type '" + std::string(type_name) + "'");
      property.name = std::string(header.token_in_line());
      result.elements.back().properties.push_back(property);
    } else if (!keyword.empty() && keyword != "comment" && keyword != "obj_info") {
      fail(path, "unknown PLY header line '" + std::string(keyword) + "'");
    }
    header.next_line();
  }
  if (!have_format) fail(path, "PLY header has no format line");
  return result;
}

// Positions (and the optional `sharp` flags) of the vertex element.
void read_ply_vertices(const std::string& path, const PlyElement& element, PlyBody& body, PolygonMesh& mesh) {
  int x = -1, y = -1, z = -1, sharp = -1;
  for (int i = 0; i < static_cast<int>(element.properties.size()); ++i) {
    const PlyProperty& property = element.properties[i];
    if (property.is_list) continue;
    if (property.name == "x") x = i;
    else if (property.name == "y") y = i;
    else if (property.name == "z") z = i;
    else if (property.name == "sharp") sharp = i;
  }
  if (x < 0 || y < 0 || z < 0) fail(path, "vertex element lacks x, y or z");
  mesh.positions.resize(element.count);
  if (sharp >= 0) mesh.sharp.assign(element.count, 0);
  for (std::uint64_t v = 0; v < element.count; ++v) {
    double xyz[3] = {0, 0, 0};
    for (int i = 0; i < static_cast<int>(element.properties.size()); ++i) {
      const PlyProperty& property = element.properties[i];
      if (property.is_list) {
        const double n = body.read(property.count_type, "a vertex list");
        if (!(n >= 0 && n <= 1e6) || n != std::floor(n)) fail(path, "malformed list length in vertex " + std::to_string(v));
        for (int k = 0; k < static_cast<int>(n); ++k) body.read(property.type, "a vertex list");
        continue;
      }
      const double value = body.read(property.type, "vertex data");
      if (i == x) xyz[0] = value;
      else if (i == y) xyz[1] = value;
      else if (i == z) xyz[2] = value;
      else if (i == sharp) mesh.sharp[v] = value != 0;
    }
    mesh.positions[v] = {xyz[0], xyz[1], xyz[2]};
  }
}

// Faces from the vertex_indices (or vertex_index) list of the face element.
void read_ply_faces(const std::string& path, const PlyElement& element, PlyBody& body, PolygonMesh& mesh) {
  int list = -1;
  for (int i = 0; i < static_cast<int>(element.properties.size()); ++i)
    if (element.properties[i].is_list &&
        (element.properties[i].name == "vertex_indices" || element.properties[i].name == "vertex_index"))
      list = i;
  if (list < 0) fail(path, "face element lacks a vertex_indices list");
  mesh.face_offsets.reserve(element.count + 1);
  mesh.face_vertices.reserve(element.count * 3);
  std::vector<std::uint32_t> corners;
  for (std::uint64_t f = 0; f < element.count; ++f) {
    for (int i = 0; i < static_cast<int>(element.properties.size()); ++i) {
      const PlyProperty& property = element.properties[i];
      if (!property.is_list) {
        body.read(property.type, "face data");
        continue;
      }
      const double n = body.read(property.count_type, "a face's vertex count");
      if (!(n >= 0 && n <= body.remaining() + 1.0) || n != std::floor(n))  // range first: no cast of NaN or 1e30
        fail(path, "malformed vertex count in face " + std::to_string(f));
      corners.clear();
      for (std::int64_t k = 0; k < static_cast<std::int64_t>(n); ++k) {
        const double index = body.read(property.type, "face indices");
        if (i != list) continue;
        if (!(index >= 0 && index < 4294967295.0) || index != std::floor(index))
          fail(path, "invalid vertex index in face " + std::to_string(f));
        corners.push_back(static_cast<std::uint32_t>(index));
      }
      if (i == list) mesh.add_face(corners.data(), corners.size());
    }
  }
}

void skip_ply_element(const std::string& path, const PlyElement& element, PlyBody& body) {
  for (std::uint64_t e = 0; e < element.count; ++e)
    for (const PlyProperty& property : element.properties) {
      if (!property.is_list) {
        body.read(property.type, element.name.c_str());
        continue;
      }
      const double n = body.read(property.count_type, element.name.c_str());
      if (!(n >= 0 && n <= body.remaining() + 1.0) || n != std::floor(n)) fail(path, "malformed list length in element '" + element.name + "'");
      for (std::int64_t k = 0; k < static_cast<std::int64_t>(n); ++k) body.read(property.type, element.name.c_str());
    }
}

PolygonMesh read_ply(const std::string& path, const std::string& data) {
  const PlyHeader header = read_ply_header(path, data);
  PlyBody body(path, data.data() + header.body_start, data.data() + data.size(), header.encoding);
  PolygonMesh mesh;
  bool have_vertices = false;
  bool have_faces = false;
  for (const PlyElement& element : header.elements) {
    // Every element needs at least a few bytes per entry: reject counts the
    // file cannot hold before allocating anything for them.
    if (element.count > body.remaining() / minimum_element_bytes(element, body.is_ascii()))
      fail(path, "element '" + element.name + "' claims " + std::to_string(element.count) +
                     " entries, more than the file can hold (truncated?)");
    if (element.name == "vertex") {
      read_ply_vertices(path, element, body, mesh);
      have_vertices = true;
    } else if (element.name == "face") {
      read_ply_faces(path, element, body, mesh);
      have_faces = true;
    } else {
      skip_ply_element(path, element, body);
    }
  }
  if (!have_vertices) fail(path, "PLY file has no vertex element");
  if (!have_faces) fail(path, "PLY file has no face element");
  return mesh;
}

// ---------------------------------------------------------------- OBJ

PolygonMesh read_obj(const std::string& path, const std::string& data) {
  PolygonMesh mesh;
  TextCursor cursor(data.data(), data.data() + data.size());
  std::vector<std::int64_t> raw;
  std::vector<std::pair<std::size_t, std::int64_t>> faces;  // (corner count, first raw index)
  std::vector<std::uint32_t> corners;
  std::size_t line = 1;
  for (; !cursor.at_end(); cursor.next_line(), ++line) {
    const std::string_view keyword = cursor.token_in_line();
    if (keyword == "v") {
      double xyz[3];
      for (double& c : xyz)
        if (!parse_double(cursor.token_in_line(), c)) fail(path, "line " + std::to_string(line) + ": malformed vertex");
      mesh.positions.push_back({xyz[0], xyz[1], xyz[2]});
    } else if (keyword == "f") {
      corners.clear();
      while (!cursor.at_line_end()) {
        std::string_view token = cursor.token_in_line();
        token = token.substr(0, token.find('/'));
        std::int64_t index = 0;
        if (!parse_integer(token, index) || index == 0)
          fail(path, "line " + std::to_string(line) + ": malformed face index");
        // Negative indices count back from the vertices read so far.
        const std::int64_t resolved = index > 0 ? index - 1 : static_cast<std::int64_t>(mesh.positions.size()) + index;
        // Positive indices may point past the vertices read so far; validate_indices() checks them at the end.
        if (resolved < 0 || resolved >= std::numeric_limits<std::uint32_t>::max())
          fail(path, "line " + std::to_string(line) + ": face index " + std::to_string(index) + " is out of range");
        corners.push_back(static_cast<std::uint32_t>(resolved));
      }
      if (corners.size() < 3) fail(path, "line " + std::to_string(line) + ": face with fewer than 3 vertices");
      mesh.add_face(corners.data(), corners.size());
    }
  }
  return mesh;
}

// ---------------------------------------------------------------- OFF

PolygonMesh read_off(const std::string& path, const std::string& data) {
  // Strip comments first so that tokens can be read freely.
  std::string text = data;
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] == '#')
      while (i < text.size() && text[i] != '\n') text[i++] = ' ';
  TextCursor cursor(text.data(), text.data() + text.size());
  std::string_view magic = cursor.token();
  const bool has_colors = magic == "COFF";
  const bool has_normals = magic == "NOFF";
  if (magic != "OFF" && !has_colors && !has_normals) fail(path, "not an OFF file (missing 'OFF' magic)");
  std::uint64_t vertex_count = 0, face_count = 0, edge_count = 0;
  if (!parse_integer(cursor.token(), vertex_count) || !parse_integer(cursor.token(), face_count) ||
      !parse_integer(cursor.token(), edge_count))
    fail(path, "malformed OFF counts line");
  // At least "x y z\n" per vertex and "3 a b c\n" per face.
  if (vertex_count > text.size() / 6 || face_count > text.size() / 8)
    fail(path, "OFF counts exceed what the file can hold (truncated?)");
  PolygonMesh mesh;
  mesh.positions.resize(vertex_count);
  const int extra = has_colors ? 4 : (has_normals ? 3 : 0);
  for (std::uint64_t v = 0; v < vertex_count; ++v) {
    double xyz[3];
    for (double& c : xyz) {
      const std::string_view token = cursor.token();
      if (token.empty()) fail(path, "file is truncated in vertex " + std::to_string(v));
      if (!parse_double(token, c)) fail(path, "malformed coordinate in vertex " + std::to_string(v));
    }
    for (int k = 0; k < extra; ++k) cursor.token();
    mesh.positions[v] = {xyz[0], xyz[1], xyz[2]};
  }
  std::vector<std::uint32_t> corners;
  for (std::uint64_t f = 0; f < face_count; ++f) {
    std::uint64_t n = 0;
    const std::string_view count_token = cursor.token();
    if (count_token.empty()) fail(path, "file is truncated in face " + std::to_string(f));
    if (!parse_integer(count_token, n) || n > text.size()) fail(path, "malformed vertex count in face " + std::to_string(f));
    corners.clear();
    for (std::uint64_t k = 0; k < n; ++k) {
      std::uint64_t index = 0;
      const std::string_view token = cursor.token_in_line();
      if (token.empty()) fail(path, "face " + std::to_string(f) + " has fewer indices than its count says");
      if (!parse_integer(token, index)) fail(path, "malformed index in face " + std::to_string(f));
      if (index >= vertex_count)
        fail(path, "face " + std::to_string(f) + " references vertex " + std::to_string(index) + " of " +
                       std::to_string(vertex_count));
      corners.push_back(static_cast<std::uint32_t>(index));
    }
    cursor.next_line();  // optional face colour
    mesh.add_face(corners.data(), corners.size());
  }
  return mesh;
}

// ---------------------------------------------------------------- writers

void append_number(std::string& out, double value, bool double_precision) {
  char buffer[32];
  const int n = std::snprintf(buffer, sizeof buffer, double_precision ? "%.17g" : "%.9g", value);
  out.append(buffer, static_cast<std::size_t>(n));
}

// The binary body in blocks of a few megabytes, vertices then faces: each
// value one memcpy into a reusable buffer (not a string append), blocks
// serialized on all threads and written in order by one, so the conversion
// overlaps the copying into the file.
void write_binary_ply_body(AtomicFileWriter& file, const PolygonMesh& mesh, const MeshWriteOptions& options,
                           bool with_sharp) {
  for (std::size_t f = 0; f < mesh.face_count(); ++f)
    if (mesh.face_size(f) > 255)
      throw Error(ErrorKind::Unsupported, file.path() + ": PLY faces are limited to 255 vertices");
  constexpr std::size_t kVerticesPerBlock = 1 << 18, kFacesPerBlock = 1 << 17;
  const std::size_t scalar_bytes = options.double_precision ? 8 : 4;
  const std::size_t vertex_bytes = 3 * scalar_bytes + (with_sharp ? 1 : 0);
  const std::size_t vertex_blocks = (mesh.vertex_count() + kVerticesPerBlock - 1) / kVerticesPerBlock;
  const std::size_t face_blocks = (mesh.face_count() + kFacesPerBlock - 1) / kFacesPerBlock;

  struct Block {
    std::size_t index = 0;
    std::vector<char> bytes;
  };
  const auto serialize = [&](Block& block) {
    if (block.index < vertex_blocks) {
      const std::size_t first = block.index * kVerticesPerBlock;
      const std::size_t last = std::min(mesh.vertex_count(), first + kVerticesPerBlock);
      block.bytes.resize((last - first) * vertex_bytes);
      char* p = block.bytes.data();
      for (std::size_t v = first; v < last; ++v, p += vertex_bytes) {
        const Vec3& position = mesh.positions[v];
        if (options.double_precision) {
          const double values[3] = {position.x, position.y, position.z};
          std::memcpy(p, values, sizeof values);
        } else {
          const float values[3] = {static_cast<float>(position.x), static_cast<float>(position.y),
                                   static_cast<float>(position.z)};
          std::memcpy(p, values, sizeof values);
        }
        if (with_sharp) p[3 * scalar_bytes] = static_cast<char>(mesh.is_sharp(v) ? 1 : 0);
      }
    } else {
      const std::size_t first = (block.index - vertex_blocks) * kFacesPerBlock;
      const std::size_t last = std::min(mesh.face_count(), first + kFacesPerBlock);
      block.bytes.resize((last - first) + 4 * std::size_t{mesh.face_offsets[last] - mesh.face_offsets[first]});
      char* p = block.bytes.data();
      for (std::size_t f = first; f < last; ++f) {
        const std::uint32_t n = mesh.face_size(f);
        *p++ = static_cast<char>(n);
        std::memcpy(p, mesh.face_begin(f), 4 * std::size_t{n});  // indices < 2^31: the bytes of int32
        p += 4 * std::size_t{n};
      }
    }
  };

  // At most pool.size() blocks are in flight and they leave in order, so
  // block i may reuse the buffer of block i - pool.size().
  std::vector<Block> pool(4);
  std::size_t next = 0;
  tbb::parallel_pipeline(
      pool.size(),
      tbb::make_filter<void, Block*>(tbb::filter_mode::serial_in_order,
                                     [&](tbb::flow_control& control) -> Block* {
                                       if (next == vertex_blocks + face_blocks) {
                                         control.stop();
                                         return nullptr;
                                       }
                                       Block* block = &pool[next % pool.size()];
                                       block->index = next++;
                                       return block;
                                     }) &
          tbb::make_filter<Block*, Block*>(tbb::filter_mode::parallel,
                                           [&](Block* block) {
                                             serialize(*block);
                                             return block;
                                           }) &
          tbb::make_filter<Block*, void>(tbb::filter_mode::serial_in_order, [&](Block* block) {
            file.write(block->bytes.data(), block->bytes.size());
          }));
}

void write_ply(AtomicFileWriter& file, const PolygonMesh& mesh, const MeshWriteOptions& options) {
  // The face lists hold "int" (int32) indices.
  if (mesh.vertex_count() > std::size_t(std::numeric_limits<std::int32_t>::max()))
    throw Error(ErrorKind::Unsupported, file.path() + ": PLY vertex indices are limited to 2^31 - 1 vertices");
  const bool with_sharp = mesh.sharp_count() > 0;
  const char* scalar = options.double_precision ? "double" : "float";
  std::string header = "ply\nformat ";
  header += options.ascii ? "ascii 1.0\n" : "binary_little_endian 1.0\n";
  header += "comment written by isowave\n";
  header += "element vertex " + std::to_string(mesh.vertex_count()) + "\n";
  for (const char* axis : {"x", "y", "z"}) header += std::string("property ") + scalar + " " + axis + "\n";
  if (with_sharp) header += "property uchar sharp\n";
  header += "element face " + std::to_string(mesh.face_count()) + "\n";
  header += "property list uchar int vertex_indices\nend_header\n";
  file.write(header);
  if (!options.ascii) {
    write_binary_ply_body(file, mesh, options, with_sharp);
    return;
  }

  std::string out;
  out.reserve(1 << 20);
  const auto flush_if_large = [&] {
    if (out.size() > (1 << 20)) {
      file.write(out);
      out.clear();
    }
  };
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    const Vec3& p = mesh.positions[v];
    for (int k = 0; k < 3; ++k) {
      append_number(out, p[k], options.double_precision);
      out += k < 2 ? ' ' : (with_sharp ? ' ' : '\n');
    }
    if (with_sharp) out += mesh.is_sharp(v) ? "1\n" : "0\n";
    flush_if_large();
  }
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t n = mesh.face_size(f);
    if (n > 255) throw Error(ErrorKind::Unsupported, file.path() + ": PLY faces are limited to 255 vertices");
    out += std::to_string(n);
    for (std::uint32_t k = 0; k < n; ++k) out += ' ' + std::to_string(mesh.face_begin(f)[k]);
    out += '\n';
    flush_if_large();
  }
  file.write(out);
}

void write_text_mesh(AtomicFileWriter& file, const PolygonMesh& mesh, const MeshWriteOptions& options, MeshFormat format) {
  std::string out;
  out.reserve(1 << 20);
  if (format == MeshFormat::Off)
    out += "OFF\n" + std::to_string(mesh.vertex_count()) + " " + std::to_string(mesh.face_count()) + " 0\n";
  else
    out += "# written by isowave\n";
  for (const Vec3& p : mesh.positions) {
    out += format == MeshFormat::Obj ? "v " : "";
    for (int k = 0; k < 3; ++k) {
      append_number(out, p[k], options.double_precision);
      out += k < 2 ? ' ' : '\n';
    }
    if (out.size() > (1 << 20)) {
      file.write(out);
      out.clear();
    }
  }
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    if (format == MeshFormat::Obj) {
      out += 'f';
      for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) out += ' ' + std::to_string(mesh.face_begin(f)[k] + 1);
    } else {
      out += std::to_string(mesh.face_size(f));
      for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) out += ' ' + std::to_string(mesh.face_begin(f)[k]);
    }
    out += '\n';
    if (out.size() > (1 << 20)) {
      file.write(out);
      out.clear();
    }
  }
  file.write(out);
}

}  // namespace

MeshFormat mesh_format_from_path(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == "ply") return MeshFormat::Ply;
  if (ext == "obj") return MeshFormat::Obj;
  if (ext == "off") return MeshFormat::Off;
  throw Error(ErrorKind::InvalidArgument, path + ": unknown mesh format (use .ply, .obj or .off)");
}

PolygonMesh read_mesh(const std::string& path) {
  const MeshFormat format = mesh_format_from_path(path);
  const std::string data = read_file_bytes(path);
  PolygonMesh mesh;
  switch (format) {
    case MeshFormat::Ply: mesh = read_ply(path, data); break;
    case MeshFormat::Obj: mesh = read_obj(path, data); break;
    case MeshFormat::Off: mesh = read_off(path, data); break;
  }
  validate_indices(mesh, path);
  return mesh;
}

bool float_loses_geometry(const PolygonMesh& mesh) {
  if (mesh.positions.empty()) return false;
  struct Range {
    double low[3], high[3], largest = 0, smallest = std::numeric_limits<double>::infinity();
  };
  Range start;
  for (int k = 0; k < 3; ++k) start.low[k] = start.high[k] = mesh.positions[0][k];
  // In parallel: it runs before every mesh write, over every vertex.
  const Range range = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.positions.size(), 1 << 16), start,
      [&](const tbb::blocked_range<std::size_t>& r, Range a) {
        for (std::size_t i = r.begin(); i < r.end(); ++i)
          for (int k = 0; k < 3; ++k) {
            const double c = mesh.positions[i][k];
            a.low[k] = std::min(a.low[k], c);
            a.high[k] = std::max(a.high[k], c);
            a.largest = std::max(a.largest, std::abs(c));
            if (c != 0) a.smallest = std::min(a.smallest, std::abs(c));
          }
        return a;
      },
      [](Range a, const Range& b) {
        for (int k = 0; k < 3; ++k) {
          a.low[k] = std::min(a.low[k], b.low[k]);
          a.high[k] = std::max(a.high[k], b.high[k]);
        }
        a.largest = std::max(a.largest, b.largest);
        a.smallest = std::min(a.smallest, b.smallest);
        return a;
      });
  const double extent =
      std::max({range.high[0] - range.low[0], range.high[1] - range.low[1], range.high[2] - range.low[2]});
  // Beyond float's range, near its smallest normal numbers, or rounding the
  // largest coordinate (by about largest * 2^-24) by more than a millionth
  // of the mesh's size: a far origin.
  return range.largest > 0.5 * std::numeric_limits<float>::max() ||
         range.smallest < 1e4 * std::numeric_limits<float>::min() || range.largest * 0x1p-24 > 1e-6 * extent;
}

void write_mesh(const std::string& path, const PolygonMesh& mesh, const MeshWriteOptions& options) {
  const MeshFormat format = mesh_format_from_path(path);
  validate_indices(mesh, path);
  MeshWriteOptions chosen = options;
  chosen.double_precision = options.double_precision || float_loses_geometry(mesh);
  AtomicFileWriter file(path);
  if (format == MeshFormat::Ply) write_ply(file, mesh, chosen);
  else write_text_mesh(file, mesh, chosen, format);
  file.commit();
}

std::string read_file_bytes(const std::string& path) {
  struct stat info {};
  if (stat(path.c_str(), &info) != 0) throw Error(ErrorKind::Io, path + ": cannot open: " + std::strerror(errno));
  if (S_ISDIR(info.st_mode)) throw Error(ErrorKind::Io, path + ": cannot read: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::Io, path + ": cannot open: " + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw Error(ErrorKind::Io, path + ": cannot read: not a regular file");
  in.seekg(0);
  std::string data(static_cast<std::size_t>(size), '\0');
  if (size > 0 && !in.read(data.data(), size)) throw Error(ErrorKind::Io, path + ": read failed: " + std::strerror(errno));
  return data;
}

}  // namespace isowave
