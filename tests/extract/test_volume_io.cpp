// Volume readers: the shared real volumes, exact round trips through files
// written here in every supported variant of every format, malformed inputs
// (each must be an Error naming the file), and truncation / byte-flip sweeps
// that must end in a volume or an Error, never a crash.
#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/extract/volume_io.h"
#include "support/test_meshes.h"

// OpenVDB 10's RootNode::readTopology leaks the child node it is reading when
// the stream throws (a corrupted VDB in the sweeps); the leak is OpenVDB's and
// bounded by one node per failed read. Tell LeakSanitizer (sanitizer builds).
extern "C" const char* __lsan_default_suppressions() {
  return "leak:openvdb::v10_0::tree::RootNode*::readTopology\n";
}

namespace isowave {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

constexpr ScalarType kAllTypes[] = {ScalarType::UInt8,  ScalarType::Int8,  ScalarType::UInt16,  ScalarType::Int16,
                                    ScalarType::UInt32, ScalarType::Int32, ScalarType::Float32, ScalarType::Float64};
constexpr std::array<std::size_t, 3> kDims{5, 4, 3};

bool host_is_little_endian() {
  const std::uint16_t one = 1;
  std::uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    // Prefer a RAM directory: the sweeps write thousands of small files.
    std::error_code ec;
    const fs::path shm = "/dev/shm";
    const fs::path base = fs::is_directory(shm, ec) && ::access(shm.c_str(), W_OK) == 0 ? shm : fs::temp_directory_path();
    path_ = base /
            ("isowave_volume_io_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

void write_file(const std::string& path, const void* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  ASSERT_TRUE(out.good()) << path;
}
void write_file(const std::string& path, const Bytes& data) { write_file(path, data.data(), data.size()); }
void write_file(const std::string& path, const std::string& data) { write_file(path, data.data(), data.size()); }

Bytes read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void append(Bytes& out, const std::string& text) { out.insert(out.end(), text.begin(), text.end()); }
void append(Bytes& out, const Bytes& bytes) { out.insert(out.end(), bytes.begin(), bytes.end()); }

// ---------------------------------------------------------------------------
// Generated samples: little-endian bytes, exact decimal text, and the floats a
// reader must produce (static_cast<float> of the stored value).

struct Samples {
  ScalarType type = ScalarType::Float32;
  Bytes little;
  std::vector<std::string> text;
  std::vector<float> expected;

  Bytes bytes(bool big_endian) const {
    if (!big_endian) return little;
    Bytes out = little;
    const std::size_t size = scalar_type_size(type);
    for (std::size_t i = 0; i < out.size(); i += size) std::reverse(out.begin() + i, out.begin() + i + size);
    return out;
  }
  std::string joined_text(const char* separator = " ") const {
    std::string out;
    for (std::size_t i = 0; i < text.size(); ++i) out += (i ? separator : "") + text[i];
    return out;
  }
};

template <typename T>
void push_value(Samples& s, T value) {
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (!host_is_little_endian()) std::reverse(bytes, bytes + sizeof(T));
  s.little.insert(s.little.end(), bytes, bytes + sizeof(T));
  char buffer[64];
  if constexpr (std::is_same_v<T, float>) {
    std::snprintf(buffer, sizeof buffer, "%.9g", static_cast<double>(value));
  } else if constexpr (std::is_same_v<T, double>) {
    std::snprintf(buffer, sizeof buffer, "%.17g", value);
  } else if constexpr (std::is_signed_v<T>) {
    std::snprintf(buffer, sizeof buffer, "%lld", static_cast<long long>(value));
  } else {
    std::snprintf(buffer, sizeof buffer, "%llu", static_cast<unsigned long long>(value));
  }
  s.text.emplace_back(buffer);
  s.expected.push_back(static_cast<float>(value));
}

template <typename T>
void fill_integers(Samples& s, std::size_t count, std::mt19937& rng) {
  const T lo = std::numeric_limits<T>::min(), hi = std::numeric_limits<T>::max();
  std::uniform_int_distribution<long long> dist(static_cast<long long>(lo), static_cast<long long>(hi));
  for (std::size_t i = 0; i < count; ++i) {
    T v = i == 0 ? lo : i == 1 ? hi : i == 2 ? T(0) : static_cast<T>(dist(rng));
    push_value<T>(s, v);
  }
}

// Distinct values over each type's whole range, including its extremes;
// `nonfinite` puts NaN, +Inf and -Inf into the float types.
Samples make_samples(ScalarType type, std::size_t count, std::uint32_t seed, bool nonfinite = false) {
  Samples s;
  s.type = type;
  std::mt19937 rng(seed);
  switch (type) {
    case ScalarType::UInt8: fill_integers<std::uint8_t>(s, count, rng); break;
    case ScalarType::Int8: fill_integers<std::int8_t>(s, count, rng); break;
    case ScalarType::UInt16: fill_integers<std::uint16_t>(s, count, rng); break;
    case ScalarType::Int16: fill_integers<std::int16_t>(s, count, rng); break;
    case ScalarType::UInt32: fill_integers<std::uint32_t>(s, count, rng); break;
    case ScalarType::Int32: fill_integers<std::int32_t>(s, count, rng); break;
    case ScalarType::Float32: {
      std::normal_distribution<float> dist(0.0f, 1000.0f);
      for (std::size_t i = 0; i < count; ++i) {
        float v = dist(rng);
        if (i == 1) v = std::numeric_limits<float>::max();
        if (i == 2) v = -std::numeric_limits<float>::denorm_min();
        if (i == 3) v = 0.1f;
        if (nonfinite && i == 4) v = std::numeric_limits<float>::quiet_NaN();
        if (nonfinite && i == 5) v = std::numeric_limits<float>::infinity();
        if (nonfinite && i == 6) v = -std::numeric_limits<float>::infinity();
        push_value<float>(s, v);
      }
      break;
    }
    case ScalarType::Float64: {
      std::normal_distribution<double> dist(0.0, 1e5);
      for (std::size_t i = 0; i < count; ++i) {
        double v = dist(rng);
        if (i == 1) v = 0.1;
        if (i == 2) v = -1e-300;
        if (i == 3) v = 3.4e38;
        if (nonfinite && i == 4) v = std::numeric_limits<double>::quiet_NaN();
        if (nonfinite && i == 5) v = 1e300;  // finite, but beyond float: Inf
        if (nonfinite && i == 6) v = -std::numeric_limits<double>::infinity();
        push_value<double>(s, v);
      }
      break;
    }
  }
  return s;
}

std::size_t count_nonfinite(const std::vector<float>& values) {
  return static_cast<std::size_t>(std::count_if(values.begin(), values.end(), [](float v) { return !std::isfinite(v); }));
}

void expect_values(const Volume& volume, const std::vector<float>& expected, const std::string& label) {
  ASSERT_EQ(volume.values.size(), expected.size()) << label;
  std::size_t mismatches = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const float a = volume.values[i], b = expected[i];
    const bool same = std::isnan(b) ? std::isnan(a) : a == b;
    if (!same && ++mismatches <= 3) ADD_FAILURE() << label << ": sample " << i << " is " << a << ", expected " << b;
  }
  EXPECT_EQ(mismatches, 0u) << label;
  EXPECT_EQ(volume.nonfinite_count, count_nonfinite(expected)) << label;
}

void expect_geometry(const Volume& volume, std::array<std::size_t, 3> dims, Vec3 spacing, Vec3 origin,
                     const std::string& label) {
  EXPECT_EQ(volume.dims, dims) << label;
  EXPECT_DOUBLE_EQ(volume.spacing.x, spacing.x) << label;
  EXPECT_DOUBLE_EQ(volume.spacing.y, spacing.y) << label;
  EXPECT_DOUBLE_EQ(volume.spacing.z, spacing.z) << label;
  EXPECT_DOUBLE_EQ(volume.origin.x, origin.x) << label;
  EXPECT_DOUBLE_EQ(volume.origin.y, origin.y) << label;
  EXPECT_DOUBLE_EQ(volume.origin.z, origin.z) << label;
}

// Expects read_volume to throw isowave::Error whose message names `path`
// (and contains `keyword` if given).
void expect_error(const std::string& path, const VolumeReadOptions& options, const std::string& keyword,
                  const std::string& label, const std::string& named = "") {
  try {
    const Volume v = read_volume(path, options);
    ADD_FAILURE() << label << ": expected an error, got a " << v.dims[0] << "x" << v.dims[1] << "x" << v.dims[2]
                  << " volume";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(named.empty() ? path : named), std::string::npos) << label << ": " << message;
    if (!keyword.empty()) {
      EXPECT_NE(message.find(keyword), std::string::npos) << label << ": " << message;
    }
    EXPECT_TRUE(e.kind() == ErrorKind::Format || e.kind() == ErrorKind::Io) << label << ": " << message;
  } catch (const std::exception& e) {
    ADD_FAILURE() << label << ": expected isowave::Error, got " << e.what();
  }
}

// ---------------------------------------------------------------------------
// Compression and encodings used by the writers.

Bytes gzip(const Bytes& data) {
  z_stream zs{};
  EXPECT_EQ(deflateInit2(&zs, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
  Bytes out(deflateBound(&zs, data.size()) + 32);
  zs.next_in = const_cast<Bytef*>(data.data());
  zs.avail_in = static_cast<uInt>(data.size());
  zs.next_out = out.data();
  zs.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
  out.resize(zs.total_out);
  deflateEnd(&zs);
  return out;
}

Bytes zlib_compress(const Bytes& data) {
  uLongf size = compressBound(data.size());
  Bytes out(size);
  EXPECT_EQ(compress2(out.data(), &size, data.data(), data.size(), 6), Z_OK);
  out.resize(size);
  return out;
}

std::string base64(const Bytes& data) {
  static const char* kChars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < data.size(); i += 3) {
    const std::uint32_t b0 = data[i], b1 = i + 1 < data.size() ? data[i + 1] : 0, b2 = i + 2 < data.size() ? data[i + 2] : 0;
    const std::uint32_t bits = b0 << 16 | b1 << 8 | b2;
    out += kChars[bits >> 18 & 63];
    out += kChars[bits >> 12 & 63];
    out += i + 1 < data.size() ? kChars[bits >> 6 & 63] : '=';
    out += i + 2 < data.size() ? kChars[bits & 63] : '=';
  }
  return out;
}

void put_word(Bytes& out, std::uint64_t v, bool header64, bool big_endian) {
  const int size = header64 ? 8 : 4;
  for (int i = 0; i < size; ++i) {
    const int shift = big_endian ? (size - 1 - i) * 8 : i * 8;
    out.push_back(static_cast<std::uint8_t>(v >> shift));
  }
}

// ---------------------------------------------------------------------------
// Writers

const char* nrrd_type_name(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: return "unsigned char";
    case ScalarType::Int8: return "signed char";
    case ScalarType::UInt16: return "ushort";
    case ScalarType::Int16: return "short";
    case ScalarType::UInt32: return "uint32";
    case ScalarType::Int32: return "int";
    case ScalarType::Float32: return "float";
    case ScalarType::Float64: return "double";
  }
  return "?";
}

struct NrrdOptions {
  std::string encoding = "raw";  // raw, gzip, ascii
  bool big_endian = false;
  bool detached = false;
  bool detached_blank_line = false;  // a blank line ending the detached header
  int geometry = 0;                  // 0 none, 1 spacings, 2 space directions + origin
  bool flip_x = false;               // negative x space direction
  int version = 4;
  int line_skip = 0;
  long byte_skip = 0;  // -1: data at the end of the file
};

// Writes PATH (.nrrd or .nhdr, plus its data file) and returns the expected
// spacing and origin.
std::pair<Vec3, Vec3> write_nrrd(const std::string& path, const Samples& s, const NrrdOptions& o) {
  std::string header = "NRRD000" + std::to_string(o.version) + "\n# generated by test_volume_io\n";
  header += std::string("type: ") + nrrd_type_name(s.type) + "\ndimension: 3\n";
  header += "sizes: " + std::to_string(kDims[0]) + " " + std::to_string(kDims[1]) + " " + std::to_string(kDims[2]) + "\n";
  if (o.encoding != "ascii") header += std::string("endian: ") + (o.big_endian ? "big" : "little") + "\n";
  header += "encoding: " + o.encoding + "\n";
  header += "key:=value with: colon\n";
  Vec3 spacing{1, 1, 1}, origin{0, 0, 0};
  if (o.geometry == 1) {
    header += "spacings: 0.5 2 1.25\nkinds: domain domain domain\n";
    spacing = {0.5, 2, 1.25};
  } else if (o.geometry == 2) {
    header += "space: right-anterior-superior\n";
    header += std::string("space directions: (") + (o.flip_x ? "-0.5" : "0.5") + ",0,0) (0,2,0) (0,0,1.25)\n";
    header += "space origin: (1,-2,3.5)\n";
    spacing = {0.5, 2, 1.25};
    origin = {o.flip_x ? 1 - 0.5 * double(kDims[0] - 1) : 1.0, -2, 3.5};
  }
  if (o.line_skip) header += "line skip: " + std::to_string(o.line_skip) + "\n";
  if (o.byte_skip) header += "byte skip: " + std::to_string(o.byte_skip) + "\n";

  Bytes payload;
  if (o.encoding == "ascii") {
    append(payload, s.joined_text("\n") + "\n");
  } else {
    payload = s.bytes(o.big_endian);
  }
  Bytes prefix;
  for (int i = 0; i < o.line_skip; ++i) append(prefix, "skipped line " + std::to_string(i) + "\n");
  Bytes junk(o.byte_skip > 0 ? static_cast<std::size_t>(o.byte_skip) : 0, 0xAB);
  if (o.byte_skip == -1) junk.assign(17, 0xCD);
  Bytes data;
  if (o.encoding == "gzip") {
    Bytes raw = junk;
    append(raw, payload);
    data = prefix;
    append(data, gzip(raw));
  } else {
    data = prefix;
    append(data, junk);
    append(data, payload);
  }

  Bytes file;
  if (o.detached) {
    const std::string data_name = fs::path(path).filename().string() + (o.encoding == "gzip" ? ".raw.gz" : ".raw");
    header += "data file: " + data_name + "\n";
    if (o.detached_blank_line) header += "\n";
    write_file((fs::path(path).parent_path() / data_name).string(), data);
    append(file, header);
  } else {
    append(file, header + "\n");
    append(file, data);
  }
  write_file(path, file);
  return {spacing, origin};
}

const char* vtk_type_name(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: return "unsigned_char";
    case ScalarType::Int8: return "char";
    case ScalarType::UInt16: return "unsigned_short";
    case ScalarType::Int16: return "short";
    case ScalarType::UInt32: return "unsigned_int";
    case ScalarType::Int32: return "int";
    case ScalarType::Float32: return "float";
    case ScalarType::Float64: return "double";
  }
  return "?";
}

struct VtkOptions {
  bool binary = true;
  bool aspect_ratio = false;  // ASPECT_RATIO instead of SPACING
  bool extras = true;         // VECTORS, FIELD and a second SCALARS around the target
  bool cell_data = false;     // CELL_DATA section before POINT_DATA
  bool lookup_table = true;   // LOOKUP_TABLE line after SCALARS
};

void vtk_array(Bytes& out, const Samples& s, bool binary) {
  if (binary) {
    append(out, s.bytes(true));
    append(out, "\n");
  } else {
    for (std::size_t i = 0; i < s.text.size(); ++i) append(out, s.text[i] + ((i + 1) % 7 == 0 ? "\n" : " "));
    append(out, "\n");
  }
}

void write_vtk(const std::string& path, const Samples& target, const VtkOptions& o) {
  const std::size_t points = kDims[0] * kDims[1] * kDims[2];
  Bytes out;
  append(out, "# vtk DataFile Version 3.0\ngenerated by test_volume_io\n");
  append(out, o.binary ? "BINARY\n" : "ASCII\n");
  append(out, "DATASET STRUCTURED_POINTS\nDIMENSIONS 5 4 3\n");
  append(out, o.aspect_ratio ? "ASPECT_RATIO 0.5 2 1.25\n" : "SPACING 0.5 2 1.25\n");
  append(out, "ORIGIN 1 -2 3.5\n");
  if (o.cell_data) {
    append(out, "CELL_DATA 24\nSCALARS cells float 1\nLOOKUP_TABLE default\n");
    vtk_array(out, make_samples(ScalarType::Float32, 24, 99), o.binary);
  }
  append(out, "POINT_DATA " + std::to_string(points) + "\n");
  if (o.extras) {
    append(out, "VECTORS velocity float\n");
    vtk_array(out, make_samples(ScalarType::Float32, points * 3, 7), o.binary);
    append(out, "FIELD FieldData 2\nids 2 " + std::to_string(points) + " int\n");
    vtk_array(out, make_samples(ScalarType::Int32, points * 2, 8), o.binary);
    append(out, "pressure 1 " + std::to_string(points) + " double\n");
    vtk_array(out, make_samples(ScalarType::Float64, points, 9), o.binary);
  }
  append(out, std::string("SCALARS density ") + vtk_type_name(target.type) + (o.extras ? " 1" : "") + "\n");
  if (o.lookup_table) append(out, "LOOKUP_TABLE default\n");
  vtk_array(out, target, o.binary);
  if (o.extras) {
    append(out, "SCALARS second float\nLOOKUP_TABLE default\n");
    vtk_array(out, make_samples(ScalarType::Float32, points, 10), o.binary);
    append(out, "NORMALS normals float\n");
    vtk_array(out, make_samples(ScalarType::Float32, points * 3, 11), o.binary);
  }
  write_file(path, out);
}

const char* vti_type_name(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: return "UInt8";
    case ScalarType::Int8: return "Int8";
    case ScalarType::UInt16: return "UInt16";
    case ScalarType::Int16: return "Int16";
    case ScalarType::UInt32: return "UInt32";
    case ScalarType::Int32: return "Int32";
    case ScalarType::Float32: return "Float32";
    case ScalarType::Float64: return "Float64";
  }
  return "?";
}

struct VtiOptions {
  std::string format = "binary";  // ascii, binary, appended-raw, appended-base64
  bool zlib = false;
  bool header64 = false;
  bool big_endian = false;
  std::size_t block_size = 64;  // uncompressed bytes per zlib block
  bool extras = true;           // a 3-component array before, cell data after
};

// One binary array: (header, data) as VTK lays them out.
std::pair<Bytes, Bytes> vti_binary(const Bytes& raw, const VtiOptions& o) {
  Bytes header, data;
  if (!o.zlib) {
    put_word(header, raw.size(), o.header64, o.big_endian);
    data = raw;
    return {header, data};
  }
  std::vector<Bytes> blocks;
  for (std::size_t i = 0; i < raw.size(); i += o.block_size)
    blocks.push_back(zlib_compress(Bytes(raw.begin() + i, raw.begin() + std::min(raw.size(), i + o.block_size))));
  put_word(header, blocks.size(), o.header64, o.big_endian);
  put_word(header, o.block_size, o.header64, o.big_endian);
  put_word(header, raw.size() % o.block_size, o.header64, o.big_endian);
  for (const auto& b : blocks) {
    put_word(header, b.size(), o.header64, o.big_endian);
    append(data, b);
  }
  return {header, data};
}

// Expected origin: Origin + Spacing * extent start.
constexpr int kExtentStart[3] = {-2, 3, 0};

void write_vti(const std::string& path, const Samples& target, const VtiOptions& o, std::string target_name = "density") {
  const std::size_t points = kDims[0] * kDims[1] * kDims[2];
  std::string extent;
  for (int a = 0; a < 3; ++a)
    extent += (a ? " " : "") + std::to_string(kExtentStart[a]) + " " + std::to_string(kExtentStart[a] + int(kDims[a]) - 1);
  std::string xml = "<?xml version=\"1.0\"?>\n<!-- generated by test_volume_io -->\n";
  xml += std::string("<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"") +
         (o.big_endian ? "BigEndian" : "LittleEndian") + "\" header_type=\"" + (o.header64 ? "UInt64" : "UInt32") + "\"" +
         (o.zlib ? " compressor=\"vtkZLibDataCompressor\"" : "") + ">\n";
  xml += "  <ImageData WholeExtent=\"" + extent + "\" Origin=\"1 -2 3.5\" Spacing=\"0.5 2 1.25\" Direction=\"1 0 0 0 1 0 0 0 1\">\n";
  xml += "  <Piece Extent=\"" + extent + "\">\n    <PointData Scalars=\"" + target_name + "\">\n";

  Bytes appended;
  const auto array = [&](const Samples& s, const std::string& name, int components) {
    std::string element = std::string("      <DataArray type=\"") + vti_type_name(s.type) + "\" Name=\"" + name + "\"" +
                          (components > 1 ? " NumberOfComponents=\"" + std::to_string(components) + "\"" : "");
    if (o.format == "ascii") {
      return element + " format=\"ascii\">\n        " + s.joined_text() + "\n      </DataArray>\n";
    }
    const auto [header, data] = vti_binary(s.bytes(o.big_endian), o);
    if (o.format == "binary") {
      Bytes together = header;
      append(together, data);
      const std::string text = o.zlib ? base64(header) + base64(data) : base64(together);
      return element + " format=\"binary\">\n        " + text + "\n      </DataArray>\n";
    }
    const std::size_t offset = appended.size();
    if (o.format == "appended-raw") {
      append(appended, header);
      append(appended, data);
    } else {
      Bytes together = header;
      append(together, data);
      append(appended, o.zlib ? base64(header) + base64(data) : base64(together));
    }
    return element + " format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
  };
  if (o.extras) xml += array(make_samples(ScalarType::Float32, points * 3, 21), "velocity", 3);
  xml += array(target, target_name, 1);
  if (o.extras) xml += array(make_samples(ScalarType::Int16, points, 22), "other", 1);
  xml += "    </PointData>\n    <CellData>\n";
  if (o.extras) xml += array(make_samples(ScalarType::Float32, 24, 23), "cellvalues", 1);
  xml += "    </CellData>\n  </Piece>\n  </ImageData>\n";
  Bytes file;
  append(file, xml);
  if (o.format.rfind("appended", 0) == 0) {
    append(file, std::string("  <AppendedData encoding=\"") + (o.format == "appended-raw" ? "raw" : "base64") + "\">\n   _");
    append(file, appended);
    append(file, "\n  </AppendedData>\n");
  }
  append(file, "</VTKFile>\n");
  write_file(path, file);
}

// ---------------------------------------------------------------------------
// Shared real data

struct SharedVolume {
  const char* file;
  std::array<std::size_t, 3> dims;
  ScalarType type;
  double iso;
  bool raw;
};

// From the table in ../shared/data/README.md.
const SharedVolume kShared[] = {
    {"miranda_256x256x256.nrrd", {256, 256, 256}, ScalarType::Float32, 1.5, false},
    {"hcci_oh_187x187x187.nrrd", {187, 187, 187}, ScalarType::Float32, 0.0003, false},
    {"csafe_heptane_151x151x151.nrrd", {151, 151, 151}, ScalarType::Float32, 50, false},
    {"engine_256x256x128.nrrd", {256, 256, 128}, ScalarType::Float32, 100, false},
    {"aneurism_256x256x256.nrrd", {256, 256, 256}, ScalarType::Float32, 100, false},
    {"embryo_256x256x256.nrrd", {256, 256, 256}, ScalarType::UInt8, 50, false},
    {"mri_head_256x256x256.nrrd", {256, 256, 256}, ScalarType::UInt8, 30, false},
    {"stent_128x128x256.nrrd", {128, 128, 256}, ScalarType::Int16, 300, false},
    {"neghip_66x66x66_uint8.raw", {66, 66, 66}, ScalarType::UInt8, 64, true},
    {"skull_64x64x64_float32.raw", {64, 64, 64}, ScalarType::Float32, 2.9, true},
    {"ironProt.vtk", {68, 68, 68}, ScalarType::UInt8, 128, false},
    {"carotid.vtk", {76, 49, 45}, ScalarType::Float32, 200, false},
    {"hydrogen.vti", {64, 64, 64}, ScalarType::Float32, 0.05, false},
    {"viscousfingers_050.vti", {64, 64, 64}, ScalarType::Float32, 30, false},
    {"viscousfingers_099.vti", {64, 64, 64}, ScalarType::Float32, 30, false},
    {"isabel_30.vti", {125, 125, 25}, ScalarType::Float64, 30, false},
};

void PrintTo(const SharedVolume& volume, std::ostream* os) { *os << volume.file; }

class SharedVolumes : public ::testing::TestWithParam<SharedVolume> {};

TEST_P(SharedVolumes, LoadsWithTheDocumentedDimsTypeAndRange) {
  const SharedVolume& info = GetParam();
  ISOWAVE_REQUIRE_SHARED_FILE(path, std::string("volumes/") + info.file);
  VolumeReadOptions options;
  if (info.raw) {
    options.dims = info.dims;
    options.type = info.type;
  }
  const Volume volume = read_volume(path, options);
  EXPECT_EQ(volume.dims, info.dims);
  EXPECT_EQ(volume.source_type, info.type);
  ASSERT_EQ(volume.values.size(), info.dims[0] * info.dims[1] * info.dims[2]);
  EXPECT_EQ(volume.nonfinite_count, count_nonfinite(volume.values));

  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (float v : volume.values) {
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  // The suggested isovalue must cut the field.
  EXPECT_LT(lo, info.iso) << info.file;
  EXPECT_GT(hi, info.iso) << info.file;
  // Integer samples are integers within their type's range.
  if (info.type == ScalarType::UInt8 || info.type == ScalarType::Int16) {
    const double tmin = info.type == ScalarType::UInt8 ? 0 : -32768, tmax = info.type == ScalarType::UInt8 ? 255 : 32767;
    EXPECT_GE(lo, tmin);
    EXPECT_LE(hi, tmax);
    EXPECT_TRUE(std::all_of(volume.values.begin(), volume.values.end(), [](float v) { return v == std::floor(v); }));
  }
  EXPECT_GT(volume.spacing.x, 0);
  EXPECT_GT(volume.spacing.y, 0);
  EXPECT_GT(volume.spacing.z, 0);
  const std::string name = info.file;
  if (name == "isabel_30.vti") {
    // README: spacing about 4.008, 4.008, 4.041.
    EXPECT_NEAR(volume.spacing.x, 4.008, 0.001);
    EXPECT_NEAR(volume.spacing.y, 4.008, 0.001);
    EXPECT_NEAR(volume.spacing.z, 4.041, 0.001);
  } else {
    // README: unit spacing unless stated.
    EXPECT_DOUBLE_EQ(volume.spacing.x, 1);
    EXPECT_DOUBLE_EQ(volume.spacing.y, 1);
    EXPECT_DOUBLE_EQ(volume.spacing.z, 1);
  }
  if (name == "carotid.vtk") {
    // The file's header says ORIGIN 100 80 1.
    EXPECT_DOUBLE_EQ(volume.origin.x, 100);
    EXPECT_DOUBLE_EQ(volume.origin.y, 80);
    EXPECT_DOUBLE_EQ(volume.origin.z, 1);
  }
}

INSTANTIATE_TEST_SUITE_P(VolumeIo, SharedVolumes, ::testing::ValuesIn(kShared),
                         [](const ::testing::TestParamInfo<SharedVolume>& param) {
                           std::string name = param.param.file;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

// The same data through two readers must agree exactly: the raw neghip file
// rewritten as NRRD gzip by the test, and carotid's float samples re-read as raw.
TEST(VolumeIo, SharedRawAgreesWithNrrdCopy) {
  ISOWAVE_REQUIRE_SHARED_FILE(path, "volumes/neghip_66x66x66_uint8.raw");
  VolumeReadOptions options;
  options.dims = {{66, 66, 66}};
  options.type = ScalarType::UInt8;
  const Volume raw = read_volume(path, options);
  TempDir dir;
  const std::string copy = dir.file("neghip.nrrd");
  std::string header = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 66 66 66\nencoding: gzip\n\n";
  Bytes file;
  append(file, header);
  append(file, gzip(read_file(path)));
  write_file(copy, file);
  const Volume nrrd = read_volume(copy);
  EXPECT_EQ(nrrd.dims, raw.dims);
  EXPECT_EQ(nrrd.values, raw.values);
}

// A gzip NRRD whose header claims 1.7 GB of float samples while its 1 MB of
// data inflates to 1 MB: the reader says so without first allocating (and
// zero-filling) what the header claims. In a child process, whose peak
// resident memory wait4() reports.
TEST(VolumeIo, LyingCompressedSizeIsRejectedWithoutAllocatingIt) {
  TempDir dir;
  Bytes noise(1u << 20);
  std::mt19937 rng(3);
  for (auto& byte : noise) byte = static_cast<std::uint8_t>(rng());
  Bytes file;
  append(file, std::string("NRRD0004\ntype: uint8\ndimension: 3\nsizes: 1200 1200 300\nencoding: gzip\n\n"));
  append(file, gzip(noise));
  const std::string path = dir.file("lying.nrrd");
  write_file(path, file);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      read_volume(path);
    } catch (const Error& error) {
      std::_Exit(std::string(error.what()).find("truncated data") != std::string::npos ? 0 : 2);
    } catch (...) {
      std::_Exit(3);
    }
    std::_Exit(4);
  }
  int status = 0;
  rusage usage{};
  ASSERT_EQ(wait4(child, &status, 0, &usage), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "not the truncation error";
  EXPECT_LT(usage.ru_maxrss, 600 * 1024) << "peak KB; the header claims 1.7 GB of floats";
}

// ---------------------------------------------------------------------------
// Round trips

TEST(VolumeIo, RawAllTypesBothEndians) {
  TempDir dir;
  for (ScalarType type : kAllTypes) {
    for (bool big : {false, true}) {
      const Samples s = make_samples(type, 60, 1 + static_cast<int>(type), true);
      const std::string path = dir.file(std::string("v_") + to_string(type) + (big ? "_be" : "_le") + ".RAW");
      write_file(path, s.bytes(big));
      VolumeReadOptions options;
      options.dims = kDims;
      options.type = type;
      options.big_endian = big;
      options.spacing = Vec3{0.5, 2, 1.25};
      options.origin = Vec3{1, -2, 3.5};
      const Volume v = read_volume(path, options);
      const std::string label = path;
      expect_geometry(v, kDims, {0.5, 2, 1.25}, {1, -2, 3.5}, label);
      EXPECT_EQ(v.source_type, type) << label;
      expect_values(v, s.expected, label);
    }
  }
}

// Given --dims and --type, a file of any name is raw samples (.bin, .dat and
// .f32 are common); without them such a name is still refused as unknown.
TEST(VolumeIo, RawDimsAndTypeReadAFileOfAnyName) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Float32, 60, 3, true);
  for (const char* name : {"v.bin", "v.dat", "v.f32", "v"}) {
    const std::string path = dir.file(name);
    write_file(path, s.bytes(false));
    VolumeReadOptions options;
    options.dims = kDims;
    options.type = ScalarType::Float32;
    const Volume v = read_volume(path, options);
    expect_geometry(v, kDims, {1, 1, 1}, {0, 0, 0}, path);
    expect_values(v, s.expected, path);
    try {
      read_volume(path);
      ADD_FAILURE() << path << ": expected an error without --dims and --type";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument) << e.what();
      EXPECT_NE(std::string(e.what()).find("--dims and --type"), std::string::npos) << e.what();
    }
  }
}

TEST(VolumeIo, RawNeedsDimsAndType) {
  TempDir dir;
  const std::string path = dir.file("x.raw");
  write_file(path, Bytes(60, 1));
  try {
    read_volume(path);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
}

TEST(VolumeIo, NrrdVariants) {
  TempDir dir;
  int n = 0;
  for (ScalarType type : kAllTypes) {
    for (const char* encoding : {"raw", "gzip", "ascii"}) {
      for (bool detached : {false, true}) {
        for (int geometry : {0, 1, 2}) {
          NrrdOptions o;
          o.encoding = encoding;
          o.detached = detached;
          o.geometry = geometry;
          o.big_endian = (n % 2) == 1;
          o.version = 1 + n % 5;
          o.detached_blank_line = (n % 3) == 0;
          o.line_skip = (n % 4 == 0) ? 2 : 0;
          o.byte_skip = (std::string(encoding) != "ascii" && n % 3 == 1) ? 5 : 0;
          if (std::string(encoding) == "raw" && n % 7 == 2) o.byte_skip = -1;
          const Samples s = make_samples(type, 60, 100 + n, true);
          const std::string path = dir.file("v" + std::to_string(n++) + (detached ? ".nhdr" : ".nrrd"));
          const auto [spacing, origin] = write_nrrd(path, s, o);
          const std::string label = path + " " + to_string(type) + " " + encoding + (detached ? " detached" : "") +
                                    " geometry " + std::to_string(geometry);
          try {
            const Volume v = read_volume(path);
            expect_geometry(v, kDims, spacing, origin, label);
            EXPECT_EQ(v.source_type, type) << label;
            expect_values(v, s.expected, label);
          } catch (const Error& e) {
            ADD_FAILURE() << label << ": " << e.what();
          }
        }
      }
    }
  }
}

TEST(VolumeIo, NrrdNegativeSpaceDirectionFlipsTheAxis) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Int16, 60, 5);
  NrrdOptions o;
  o.geometry = 2;
  o.flip_x = true;
  o.encoding = "gzip";
  const std::string path = dir.file("flip.nrrd");
  const auto [spacing, origin] = write_nrrd(path, s, o);
  const Volume v = read_volume(path);
  expect_geometry(v, kDims, spacing, origin, path);
  // Sample i along x now holds the file's sample (nx - 1 - i): same world position.
  for (std::size_t k = 0; k < kDims[2]; ++k)
    for (std::size_t j = 0; j < kDims[1]; ++j)
      for (std::size_t i = 0; i < kDims[0]; ++i)
        EXPECT_EQ(v.at(i, j, k), s.expected[(kDims[0] - 1 - i) + kDims[0] * (j + kDims[1] * k)]);
}

TEST(VolumeIo, VtkLegacyVariants) {
  TempDir dir;
  int n = 0;
  for (ScalarType type : kAllTypes) {
    for (bool binary : {true, false}) {
      for (bool extras : {true, false}) {
        VtkOptions o;
        o.binary = binary;
        o.extras = extras;
        o.aspect_ratio = n % 2 == 0;
        o.cell_data = n % 3 == 0;
        o.lookup_table = extras || n % 4 != 1;
        const Samples s = make_samples(type, 60, 200 + n, true);
        const std::string path = dir.file("v" + std::to_string(n++) + ".vtk");
        write_vtk(path, s, o);
        const std::string label = path + " " + to_string(type) + (binary ? " binary" : " ascii") + (extras ? " extras" : "");
        try {
          const Volume v = read_volume(path);
          expect_geometry(v, kDims, {0.5, 2, 1.25}, {1, -2, 3.5}, label);
          EXPECT_EQ(v.source_type, type) << label;
          expect_values(v, s.expected, label);
          if (extras) {
            // --field picks the later SCALARS array and a FIELD array.
            VolumeReadOptions options;
            options.field = "second";
            const Volume second = read_volume(path, options);
            expect_values(second, make_samples(ScalarType::Float32, 60, 10).expected, label + " field=second");
            options.field = "pressure";
            const Volume pressure = read_volume(path, options);
            EXPECT_EQ(pressure.source_type, ScalarType::Float64);
            expect_values(pressure, make_samples(ScalarType::Float64, 60, 9).expected, label + " field=pressure");
          }
        } catch (const Error& e) {
          ADD_FAILURE() << label << ": " << e.what();
        }
      }
    }
  }
}

TEST(VolumeIo, VtiVariants) {
  TempDir dir;
  int n = 0;
  for (const char* format : {"ascii", "binary", "appended-raw", "appended-base64"}) {
    for (bool zlib : {false, true}) {
      for (bool header64 : {false, true}) {
        for (ScalarType type : kAllTypes) {
          VtiOptions o;
          o.format = format;
          o.zlib = zlib;
          o.header64 = header64;
          o.big_endian = n % 3 == 2;
          o.extras = n % 2 == 0;
          // Block sizes that divide the data (last block full), that do not, and
          // that split samples across blocks.
          o.block_size = n % 4 == 0 ? scalar_type_size(type) * 15 : n % 4 == 2 ? 7 : 64;
          const Samples s = make_samples(type, 60, 300 + n, true);
          const std::string path = dir.file("v" + std::to_string(n++) + ".vti");
          write_vti(path, s, o);
          const std::string label = path + " " + format + (zlib ? " zlib" : "") + (header64 ? " UInt64" : " UInt32") +
                                    (o.big_endian ? " big" : "") + " " + to_string(type);
          try {
            const Volume v = read_volume(path);
            const Vec3 origin{1 + 0.5 * kExtentStart[0], -2 + 2.0 * kExtentStart[1], 3.5 + 1.25 * kExtentStart[2]};
            expect_geometry(v, kDims, {0.5, 2, 1.25}, origin, label);
            EXPECT_EQ(v.source_type, type) << label;
            expect_values(v, s.expected, label);
            if (o.extras) {
              VolumeReadOptions options;
              options.field = "other";
              expect_values(read_volume(path, options), make_samples(ScalarType::Int16, 60, 22).expected,
                            label + " field=other");
            }
          } catch (const Error& e) {
            ADD_FAILURE() << label << ": " << e.what();
          }
        }
      }
    }
  }
}

// VDB

void init_vdb() {
  static bool done = false;
  if (!done) openvdb::initialize();
  done = true;
}

openvdb::math::Transform::Ptr scale_translate() {
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  m.setToScale(openvdb::Vec3d(0.5, 0.25, 2));
  m.setTranslation(openvdb::Vec3d(1, 2, 3));
  return openvdb::math::Transform::createLinearTransform(m);
}

// A float grid with voxels in [2,6]x[-3,1]x[10,13] (one of them inactive), an
// active 8^3 tile, plus a vec3 grid written first and a double grid.
struct VdbFixture {
  std::vector<float> expected_float;  // dense over the active bbox
  std::vector<float> expected_double;
  std::array<std::size_t, 3> dims_float{}, dims_double{};
  Vec3 origin_float, origin_double;
};

VdbFixture write_vdb(const std::string& path) {
  init_vdb();
  VdbFixture f;
  auto vectors = openvdb::Vec3SGrid::create();
  vectors->setName("velocity");
  vectors->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));

  auto grid = openvdb::FloatGrid::create(-7.5f);
  grid->setName("density");
  grid->setTransform(scale_translate());
  auto acc = grid->getAccessor();
  std::mt19937 rng(5);
  std::normal_distribution<float> dist(0, 10);
  for (int z = 10; z <= 13; ++z)
    for (int y = -3; y <= 1; ++y)
      for (int x = 2; x <= 6; ++x) acc.setValue(openvdb::Coord(x, y, z), dist(rng));
  acc.setValueOff(openvdb::Coord(4, -1, 11), 99.0f);  // inactive: reads as the background
  grid->tree().addTile(1, openvdb::Coord(8, 0, 8), 42.0f, true);  // 8^3 active tile at [8,15]x[0,7]x[8,15]

  // Expected dense over [2,15]x[-3,7]x[8,15].
  const openvdb::Coord lo(2, -3, 8), hi(15, 7, 15);
  f.dims_float = {14, 11, 8};
  const openvdb::Vec3d o = scale_translate()->indexToWorld(lo);
  f.origin_float = {o.x(), o.y(), o.z()};
  auto probe = grid->getConstAccessor();
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const openvdb::Coord c(x, y, z);
        f.expected_float.push_back(probe.isValueOn(c) ? probe.getValue(c) : -7.5f);
      }

  auto dgrid = openvdb::DoubleGrid::create(0.25);
  dgrid->setName("pressure");
  dgrid->setTransform(openvdb::math::Transform::createLinearTransform(2.0));
  auto dacc = dgrid->getAccessor();
  f.dims_double = {3, 2, 2};
  f.origin_double = {-2, 0, 2};
  for (int z = 1; z <= 2; ++z)
    for (int y = 0; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x) {
        const double v = 0.1 * x + 1e-3 * y + 10 * z;
        dacc.setValue(openvdb::Coord(x, y, z), v);
        f.expected_double.push_back(static_cast<float>(v));
      }
  openvdb::GridPtrVec grids{vectors, grid, dgrid};
  openvdb::io::File(path).write(grids);
  return f;
}

TEST(VolumeIo, VdbFloatAndDoubleGrids) {
  TempDir dir;
  const std::string path = dir.file("grids.vdb");
  const VdbFixture f = write_vdb(path);

  const Volume v = read_volume(path);  // default: the first float/double grid
  expect_geometry(v, f.dims_float, {0.5, 0.25, 2}, f.origin_float, "density");
  EXPECT_EQ(v.source_type, ScalarType::Float32);
  expect_values(v, f.expected_float, "density");
  // The inactive voxel (4,-1,11) holds 99 in the tree but reads as the background.
  EXPECT_EQ(v.at(4 - 2, -1 + 3, 11 - 8), -7.5f);
  EXPECT_EQ(v.at(8 - 2, 0 + 3, 8 - 8), 42.0f);

  VolumeReadOptions options;
  options.grid = "pressure";
  const Volume d = read_volume(path, options);
  expect_geometry(d, f.dims_double, {2, 2, 2}, f.origin_double, "pressure");
  EXPECT_EQ(d.source_type, ScalarType::Float64);
  expect_values(d, f.expected_double, "pressure");

  options.grid = "velocity";
  expect_error(path, options, "velocity", "vec3 grid");
  options.grid = "nope";
  expect_error(path, options, "missing grid 'nope'", "missing grid");
}

// Every compression setting, half floats, the inactive-value encodings and an
// instanced grid, against OpenVDB's own reader of the same file.
template <typename GridT>
typename GridT::Ptr varied_grid(bool half) {
  using V = typename GridT::ValueType;
  auto grid = GridT::create(V(2));
  grid->setSaveFloatAsHalf(half);
  grid->setTransform(scale_translate());
  auto acc = grid->getAccessor();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> dist(-5, 5);
  // Leaf A: inactive values background and -background (mask, no stored inactive values).
  for (int i = 0; i < 40; ++i) acc.setValue(openvdb::Coord(i % 8, (i / 8) % 8, 0), V(dist(rng)));
  acc.setValueOff(openvdb::Coord(1, 7, 3), V(-2));
  // Leaf B: two other inactive values (mask and two inactive values).
  for (int i = 0; i < 30; ++i) acc.setValue(openvdb::Coord(8 + i % 8, i / 8, 1), V(dist(rng)));
  acc.setValueOff(openvdb::Coord(9, 5, 5), V(0.75));
  acc.setValueOff(openvdb::Coord(10, 5, 5), V(-1.5));
  // Leaf C: many distinct inactive values (no mask compression possible).
  for (int i = 0; i < 20; ++i) acc.setValue(openvdb::Coord(16 + i % 8, i / 8, 2), V(dist(rng)));
  for (int i = 0; i < 6; ++i) acc.setValueOff(openvdb::Coord(16 + i, 7, 7), V(10 + i));
  // Leaf D: one inactive value (no mask, one inactive value).
  for (int i = 0; i < 10; ++i) acc.setValue(openvdb::Coord(-8 + i % 8, -8 + i / 8, -8), V(dist(rng)));
  acc.setValueOff(openvdb::Coord(-7, -2, -5), V(3.25));
  // An active tile at the first internal level and one at the second.
  grid->tree().addTile(1, openvdb::Coord(24, 0, 0), V(7), true);
  grid->tree().addTile(2, openvdb::Coord(128, 0, 0), V(-3), true);
  return grid;
}

template <typename GridT>
std::vector<float> reference_dense(const std::string& path, const std::string& name, const Volume& shape) {
  openvdb::io::File file(path);
  file.open(false);
  auto grid = openvdb::gridPtrCast<GridT>(file.readGrid(name));
  file.close();
  const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
  EXPECT_EQ(shape.dims, (std::array<std::size_t, 3>{std::size_t(box.dim().x()), std::size_t(box.dim().y()),
                                                    std::size_t(box.dim().z())}));
  std::vector<float> out;
  auto acc = grid->getConstAccessor();
  for (int z = box.min().z(); z <= box.max().z(); ++z)
    for (int y = box.min().y(); y <= box.max().y(); ++y)
      for (int x = box.min().x(); x <= box.max().x(); ++x) {
        const openvdb::Coord c(x, y, z);
        out.push_back(static_cast<float>(acc.isValueOn(c) ? acc.getValue(c) : grid->background()));
      }
  return out;
}

TEST(VolumeIo, VdbCompressionVariants) {
  init_vdb();
  TempDir dir;
  const std::uint32_t settings[] = {
      openvdb::io::COMPRESS_NONE, openvdb::io::COMPRESS_ZIP, openvdb::io::COMPRESS_ACTIVE_MASK,
      openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK, openvdb::io::COMPRESS_BLOSC,
      openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK};
  int n = 0;
  for (std::uint32_t compression : settings) {
    for (bool half : {false, true}) {
      const std::string path = dir.file("c" + std::to_string(n++) + ".vdb");
      auto f = varied_grid<openvdb::FloatGrid>(half);
      f->setName("f");
      auto d = varied_grid<openvdb::DoubleGrid>(half);
      d->setName("d");
      auto instance = f->copyGrid();  // shares f's tree: written as an instance
      instance->setName("instance");
      openvdb::io::File file(path);
      file.setCompression(compression);
      file.write(openvdb::GridPtrVec{f, d, openvdb::ConstPtrCast<openvdb::GridBase>(instance)});
      const std::string label = path + " compression " + std::to_string(compression) + (half ? " half" : "");
      for (const char* name : {"f", "d", "instance"}) {
        VolumeReadOptions options;
        options.grid = name;
        try {
          const Volume v = read_volume(path, options);
          const std::vector<float> expected = std::string(name) == "d"
                                                  ? reference_dense<openvdb::DoubleGrid>(path, name, v)
                                                  : reference_dense<openvdb::FloatGrid>(path, name, v);
          expect_values(v, expected, label + " grid " + name);
          EXPECT_EQ(v.source_type, std::string(name) == "d" ? ScalarType::Float64 : ScalarType::Float32);
        } catch (const Error& e) {
          ADD_FAILURE() << label << " grid " << name << ": " << e.what();
        }
      }
    }
  }
}

TEST(VolumeIo, VdbRejectsRotatedTransform) {
  init_vdb();
  TempDir dir;
  const std::string path = dir.file("rotated.vdb");
  auto grid = openvdb::FloatGrid::create(0.0f);
  grid->setName("density");
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  m.setToRotation(openvdb::math::Z_AXIS, 0.3);
  grid->setTransform(openvdb::math::Transform::createLinearTransform(m));
  grid->tree().setValue(openvdb::Coord(1, 2, 3), 1.0f);
  openvdb::io::File(path).write(openvdb::GridPtrVec{grid});
  expect_error(path, {}, "rotated", "rotated transform");
}

TEST(VolumeIo, BuiltinPrefixDispatches) {
  try {
    const Volume v = read_volume("builtin:sphere:16");
    EXPECT_EQ(v.dims, (std::array<std::size_t, 3>{16, 16, 16}));
    EXPECT_EQ(v.values.size(), 16u * 16 * 16);
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Unsupported) throw;
    GTEST_SKIP() << "builtin fields not implemented yet: " << e.what();
  }
  EXPECT_THROW(read_volume("builtin:sphere:abc"), Error);
  EXPECT_THROW(read_volume("builtin:"), Error);
}

TEST(VolumeIo, UnknownExtensionAndMissingFile) {
  TempDir dir;
  EXPECT_THROW(read_volume(dir.file("x.xyz")), Error);
  expect_error(dir.file("missing.nrrd"), {}, "cannot open", "missing file");
  fs::create_directories(dir.file("folder.nrrd"));
  expect_error(dir.file("folder.nrrd"), {}, "not a regular file", "directory");
}

TEST(VolumeIo, ParseScalarType) {
  EXPECT_EQ(parse_scalar_type("uint8"), ScalarType::UInt8);
  EXPECT_EQ(parse_scalar_type("int16"), ScalarType::Int16);
  EXPECT_EQ(parse_scalar_type("Float32"), ScalarType::Float32);
  EXPECT_EQ(parse_scalar_type("float64"), ScalarType::Float64);
  for (ScalarType t : kAllTypes) EXPECT_EQ(parse_scalar_type(to_string(t)), t);
  try {
    parse_scalar_type("complex64");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
  }
}

// ---------------------------------------------------------------------------
// Malformed inputs

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::string as_string(const Bytes& b) { return std::string(b.begin(), b.end()); }

TEST(VolumeIo, RawMalformed) {
  TempDir dir;
  VolumeReadOptions options;
  options.dims = kDims;
  options.type = ScalarType::Float32;
  const std::string path = dir.file("bad.raw");
  write_file(path, Bytes(239, 0));
  expect_error(path, options, "size mismatch", "truncated raw");
  write_file(path, Bytes(241, 0));
  expect_error(path, options, "size mismatch", "oversized raw");
  options.dims = {{100000, 100000, 100000}};
  expect_error(path, options, "", "absurd raw dims");
}

TEST(VolumeIo, NrrdMalformed) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Float32, 60, 3);
  const std::string good_path = dir.file("good.nrrd");
  NrrdOptions o;
  write_nrrd(good_path, s, o);
  const std::string good = as_string(read_file(good_path));
  o.encoding = "gzip";
  write_nrrd(good_path, s, o);
  const std::string good_gz = as_string(read_file(good_path));
  const std::string path = dir.file("bad.nrrd");
  const auto check = [&](const std::string& content, const std::string& keyword, const std::string& label) {
    write_file(path, content);
    expect_error(path, {}, keyword, label);
  };
  check(good.substr(0, good.size() - 1), "truncated", "truncated raw data");
  check(good + "x", "size mismatch", "extra raw data");
  check(good_gz.substr(0, good_gz.size() - 9), "truncated", "truncated gzip");
  {
    std::string corrupt = good_gz;
    const std::size_t data = corrupt.find("\n\n") + 2;
    for (std::size_t i = data + 12; i < data + 40 && i < corrupt.size(); ++i) corrupt[i] = static_cast<char>(corrupt[i] ^ 0x5a);
    check(corrupt, "gzip", "corrupt gzip");
  }
  {
    // gzip holding more bytes than the header declares
    std::string header = good_gz.substr(0, good_gz.find("\n\n") + 2);
    header = replace(header, "sizes: 5 4 3", "sizes: 5 4 2");
    check(header + good_gz.substr(good_gz.find("\n\n") + 2), "size mismatch", "gzip too long");
  }
  check(replace(good, "type: float", "type: quaternion"), "unknown sample type", "unknown type");
  check(replace(good, "type: float", "type: int64"), "unsupported sample type", "int64 type");
  check(replace(good, "sizes: 5 4 3\n", ""), "missing required field 'sizes'", "missing sizes");
  check(replace(good, "encoding: raw", "encoding: bzip2"), "unsupported encoding", "bzip2");
  check(replace(good, "endian: little\n", ""), "endian", "missing endian");
  check(replace(good, "NRRD0004", "NRRD0009"), "NRRD", "bad version");
  check(replace(good, "NRRD0004", "PNG"), "not a NRRD file", "bad magic");
  check(replace(good, "dimension: 3", "dimension 3"), "bad header line", "no colon");
  check(replace(good, "dimension: 3", "dimension: 2"), "dimension", "2-D");
  check(replace(replace(good, "dimension: 3", "dimension: 4"), "sizes: 5 4 3", "sizes: 3 5 4 1"), "dimension", "4-D");
  check(replace(good, "sizes: 5 4 3", "sizes: 5 4 -3"), "sizes", "negative size");
  check(replace(good, "sizes: 5 4 3", "sizes: 5 4"), "sizes", "two sizes");
  check(replace(good, "encoding: raw", "encoding: raw\nkinds: 3-vector domain domain"), "kind", "vector kind");
  check(replace(good, "encoding: raw", "encoding: raw\nspace directions: (0.5,0.5,0) (0,2,0) (0,0,1)"), "axis-aligned",
        "rotated directions");
  check(replace(good, "encoding: raw", "encoding: raw\nspacings: 1 nope 1"), "invalid number", "bad spacing");
  check(replace(good, "encoding: raw", "encoding: raw\nencoding: raw"), "twice", "duplicate field");
  check(replace(good, "sizes: 5 4 3", "sizes: 100000 100000 100000"), "truncated", "absurd dims raw");
  check(replace(good_gz, "sizes: 5 4 3", "sizes: 100000 100000 100000"), "truncated", "absurd dims gzip");
  check(replace(good, "sizes: 5 4 3", "sizes: 4000000000 4000000000 4000000000"), "", "overflowing dims");
  check(good.substr(0, good.find("\n\n")), "no data", "no blank line, no data file");
  // Detached: the data file is missing, or too short (the error names both files).
  const std::string header = dir.file("bad.nhdr");
  write_file(header, replace(good.substr(0, good.find("\n\n") + 1), "encoding: raw\n", "encoding: raw\ndata file: nothere.raw\n"));
  expect_error(header, {}, "cannot open", "missing data file", "nothere.raw");
  write_file(dir.file("short.raw"), Bytes(100, 0));
  write_file(header, replace(good.substr(0, good.find("\n\n") + 1), "encoding: raw\n", "encoding: raw\ndata file: short.raw\n"));
  expect_error(header, {}, "truncated", "short data file");
  expect_error(header, {}, "short.raw", "short data file names the data file");
}

TEST(VolumeIo, VtkMalformed) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Float32, 60, 3);
  const std::string good_path = dir.file("good.vtk");
  VtkOptions o;
  write_vtk(good_path, s, o);
  const std::string good = as_string(read_file(good_path));
  o.binary = false;
  write_vtk(good_path, s, o);
  const std::string good_ascii = as_string(read_file(good_path));
  const std::string path = dir.file("bad.vtk");
  const auto check = [&](const std::string& content, const std::string& keyword, const std::string& label,
                         const VolumeReadOptions& options = {}) {
    write_file(path, content);
    expect_error(path, options, keyword, label);
  };
  // Cut inside the density array.
  const std::size_t density = good.find("SCALARS density");
  check(good.substr(0, density + 100), "truncated", "truncated binary");
  check(good_ascii.substr(0, good_ascii.find("SCALARS density") + 100), "truncated", "truncated ascii");
  check(replace(good, "SCALARS density float", "SCALARS density float16"), "unknown data type", "unknown type");
  check(replace(good, "VECTORS velocity float", "VECTORS velocity quad"), "unknown data type", "unknown type in skipped");
  VolumeReadOptions field;
  field.field = "nope";
  check(good, "missing field 'nope'", "missing field", field);
  field.field = "velocity";
  check(good, "not a scalar array", "vectors as field", field);
  check(replace(good, "# vtk DataFile", "# vtx DataFile"), "not a legacy VTK file", "bad magic");
  check(replace(good, "BINARY", "BINARI"), "ASCII or BINARY", "bad format line");
  check(replace(good, "STRUCTURED_POINTS", "POLYDATA"), "unsupported dataset type", "polydata");
  check(replace(good, "POINT_DATA 60", "POINT_DATA 61"), "POINT_DATA", "count mismatch");
  check(replace(good, "DIMENSIONS 5 4 3", "DIMENSIONS 5 4"), "DIMENSIONS", "two dims");
  check(replace(replace(good, "DIMENSIONS 5 4 3", "DIMENSIONS 100000 100000 100000"), "POINT_DATA 60",
                "POINT_DATA 1000000000000000"),
        "truncated", "absurd dims");
  check(replace(good, "SCALARS density float 1", "SCALARS density float 3"), "3 components", "3 components");
  check(replace(good, "SPACING 0.5 2 1.25", "SPACING 0.5 abc 1.25"), "invalid number", "bad spacing");
  check(replace(good, "SPACING 0.5 2 1.25", "SPACING 0.5 0 1.25"), "spacing", "zero spacing");
  check(replace(good, "ORIGIN 1 -2 3.5", "BOGUS 1 2 3"), "unexpected keyword", "unknown keyword");
  check(replace(good, "FIELD FieldData 2", "FIELD FieldData 3"), "", "field count too big");
  check(good.substr(0, good.find("POINT_DATA")), "POINT_DATA", "no point data");
}

TEST(VolumeIo, VtiMalformed) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Float32, 60, 3);
  const std::string path = dir.file("bad.vti");
  const auto make = [&](const VtiOptions& o) {
    write_vti(path, s, o);
    return as_string(read_file(path));
  };
  const auto check = [&](const std::string& content, const std::string& keyword, const std::string& label,
                         const VolumeReadOptions& options = {}) {
    write_file(path, content);
    expect_error(path, options, keyword, label);
  };
  VtiOptions o;
  o.format = "appended-raw";
  const std::string raw = make(o);
  o.zlib = true;
  const std::string raw_z = make(o);
  o.format = "binary";
  const std::string inline_z = make(o);
  o.zlib = false;
  const std::string inline_plain = make(o);
  o.format = "ascii";
  const std::string ascii = make(o);

  // Appended data starts after "   _"; the density array follows the 724-byte velocity array.
  check(raw.substr(0, raw.find("   _") + 4 + 724 + 100), "truncated", "truncated appended");
  check(raw_z.substr(0, raw_z.find("   _") + 4 + 150), "truncated", "truncated appended zlib");
  {
    // Corrupt the first compressed block of the density array (after the velocity array).
    std::string corrupt = raw_z;
    const std::size_t start = corrupt.find("   _") + 4;
    for (std::size_t i = start; i < corrupt.size() - 30; ++i) {
      // zlib streams start with 0x78; damage the bytes after every zlib header.
      if (static_cast<unsigned char>(corrupt[i]) == 0x78 && static_cast<unsigned char>(corrupt[i + 1]) == 0x9c) {
        for (std::size_t j = i + 2; j < i + 8; ++j) corrupt[j] = static_cast<char>(corrupt[j] ^ 0x33);
      }
    }
    check(corrupt, "zlib", "corrupt zlib");
  }
  check(replace(inline_plain, "Name=\"density\" format=\"binary\">\n        ",
                "Name=\"density\" format=\"binary\">\n        !!!!"),
        "base64", "bad base64");
  check(replace(inline_z, "type=\"Float32\" Name=\"density\"", "type=\"Float16\" Name=\"density\""), "unknown data type",
        "unknown type");
  check(replace(inline_z, "type=\"Float32\" Name=\"density\"", "type=\"Int64\" Name=\"density\""), "unsupported data type",
        "int64 type");
  VolumeReadOptions field;
  field.field = "nope";
  check(inline_z, "missing field 'nope'", "missing field", field);
  field.field = "cellvalues";
  check(inline_z, "cell data", "cell field", field);
  field.field = "velocity";
  check(inline_z, "3 components", "vector field", field);
  check(replace(raw, "type=\"ImageData\"", "type=\"PolyData\""), "unsupported VTK XML type", "polydata");
  check("not xml at all", "", "not xml");
  check(replace(raw, "<VTKFile", "<VTKFileX"), "not a VTK XML file", "wrong root");
  check(replace(replace(raw, "WholeExtent=\"-2 2 3 6 0 2\"", "WholeExtent=\"0 99999 0 99999 0 99999\""),
                "<Piece Extent=\"-2 2 3 6 0 2\"", "<Piece Extent=\"0 99999 0 99999 0 99999\""),
        "", "absurd extent");
  check(replace(replace(inline_z, "WholeExtent=\"-2 2 3 6 0 2\"", "WholeExtent=\"0 99999 0 99999 0 99999\""),
                "<Piece Extent=\"-2 2 3 6 0 2\"", "<Piece Extent=\"0 99999 0 99999 0 99999\""),
        "", "absurd extent zlib");
  check(replace(replace(ascii, "WholeExtent=\"-2 2 3 6 0 2\"", "WholeExtent=\"0 99999 0 99999 0 99999\""),
                "<Piece Extent=\"-2 2 3 6 0 2\"", "<Piece Extent=\"0 99999 0 99999 0 99999\""),
        "truncated", "absurd extent ascii");
  check(replace(replace(raw, "WholeExtent=\"-2 2 3 6 0 2\"", "WholeExtent=\"-2 2 3 6 0 1\""),
                "<Piece Extent=\"-2 2 3 6 0 2\"", "<Piece Extent=\"-2 2 3 6 0 1\""),
        "size mismatch", "size mismatch uncompressed");
  check(replace(replace(raw_z, "WholeExtent=\"-2 2 3 6 0 2\"", "WholeExtent=\"-2 2 3 6 0 1\""),
                "<Piece Extent=\"-2 2 3 6 0 2\"", "<Piece Extent=\"-2 2 3 6 0 1\""),
        "size mismatch", "size mismatch compressed");
  check(replace(ascii, "Name=\"density\" format=\"ascii\">\n        ", "Name=\"density\" format=\"ascii\">\n        1 2 x "),
        "bad number", "bad ascii number");
  check(replace(raw, "encoding=\"raw\"", "encoding=\"hex\""), "unsupported AppendedData encoding", "hex appended");
  check(replace(raw_z, "vtkZLibDataCompressor", "vtkLZ4DataCompressor"), "unsupported compressor", "lz4");
  check(replace(raw, "header_type=\"UInt32\"", "header_type=\"UInt16\""), "header_type", "bad header type");
  check(replace(raw, "Direction=\"1 0 0 0 1 0 0 0 1\"", "Direction=\"0 1 0 1 0 0 0 0 1\""), "Direction", "permuted");
  check(replace(raw, "Name=\"density\" format=\"appended\" offset=\"", "Name=\"density\" format=\"appended\" offset=\"9999999"),
        "truncated", "offset past the end");
  check(raw.substr(0, raw.find("<PointData")), "truncated XML", "cut in the XML");
}

TEST(VolumeIo, VdbMalformed) {
  TempDir dir;
  const std::string good_path = dir.file("good.vdb");
  write_vdb(good_path);
  const Bytes good = read_file(good_path);
  const std::string path = dir.file("bad.vdb");
  write_file(path, Bytes(good.begin(), good.begin() + static_cast<long>(good.size() / 2)));
  expect_error(path, {}, "truncated", "truncated vdb");
  write_file(path, std::string("definitely not a vdb file"));
  expect_error(path, {}, "not an OpenVDB file", "not vdb");
  Bytes bad_version = good;
  bad_version[8] = 0x10;  // file version 16
  write_file(path, bad_version);
  expect_error(path, {}, "version", "bad version");

  // Only a vec3 grid: no scalar grid to read.
  init_vdb();
  auto vectors = openvdb::Vec3SGrid::create();
  vectors->setName("velocity");
  vectors->tree().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1, 2, 3));
  openvdb::io::File(path).write(openvdb::GridPtrVec{vectors});
  expect_error(path, {}, "missing field", "no scalar grid");

  // An empty float grid.
  auto empty = openvdb::FloatGrid::create(1.0f);
  empty->setName("empty");
  openvdb::io::File(path).write(openvdb::GridPtrVec{empty});
  expect_error(path, {}, "no active voxels", "empty grid");

  // A root tile makes the active box 4096^3: far too large for a dense copy.
  auto huge = openvdb::FloatGrid::create(1.0f);
  huge->setName("huge");
  huge->tree().addTile(3, openvdb::Coord(0, 0, 0), 2.0f, true);
  huge->tree().setValue(openvdb::Coord(100000, 0, 0), 1.0f);
  openvdb::io::File(path).write(openvdb::GridPtrVec{huge});
  expect_error(path, {}, "too large", "absurd dims");
}

// ---------------------------------------------------------------------------
// Truncation and byte-flip sweeps: a volume or an Error, never anything else.

void sweep(const std::string& path, const VolumeReadOptions& options, const std::string& label,
           const std::string& extra_file = "") {
  const Bytes original = read_file(path);
  ASSERT_FALSE(original.empty()) << label;
  {
    // The untouched file loads.
    const Volume v = read_volume(path, options);
    EXPECT_GT(v.values.size(), 0u) << label;
  }
  std::size_t errors = 0, loaded = 0;
  const auto attempt = [&](const std::string& what) {
    try {
      const Volume v = read_volume(path, options);
      EXPECT_EQ(v.values.size(), v.sample_count()) << label << " " << what;
      ++loaded;
    } catch (const Error& e) {
      ++errors;
      const std::string message = e.what();
      if (message.find(path) == std::string::npos && (extra_file.empty() || message.find(extra_file) == std::string::npos))
        ADD_FAILURE() << label << " " << what << ": the error does not name the file: " << message;
    } catch (const std::exception& e) {
      ADD_FAILURE() << label << " " << what << ": non-isowave exception " << e.what();
    }
  };
  // Every proper prefix, longest first (shrinking the file in place is cheap).
  for (std::size_t length = original.size(); length-- > 0;) {
    fs::resize_file(path, length);
    attempt("prefix " + std::to_string(length));
  }
  // ISOWAVE_SWEEP_MUTATIONS raises the number of random mutations (default 400).
  int trials = 400;
  if (const char* env = std::getenv("ISOWAVE_SWEEP_MUTATIONS")) trials = std::max(1, std::atoi(env));
  std::mt19937 rng(1234);
  for (int trial = 0; trial < trials; ++trial) {
    Bytes mutated = original;
    const int flips = 1 + trial % 3;
    for (int f = 0; f < flips; ++f) {
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, mutated.size() - 1)(rng);
      mutated[at] = trial % 2 ? static_cast<std::uint8_t>(mutated[at] ^ (1u << (rng() % 8)))
                              : static_cast<std::uint8_t>(rng());
    }
    write_file(path, mutated);
    attempt("mutation " + std::to_string(trial));
  }
  write_file(path, original);
  EXPECT_GT(errors, 0u) << label;
  (void)loaded;
}

TEST(VolumeIoSweep, Raw) {
  TempDir dir;
  const std::string path = dir.file("s.raw");
  write_file(path, make_samples(ScalarType::Int16, 60, 1).bytes(false));
  VolumeReadOptions options;
  options.dims = kDims;
  options.type = ScalarType::Int16;
  sweep(path, options, "raw");
}

TEST(VolumeIoSweep, Nrrd) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Float32, 60, 2, true);
  for (const char* encoding : {"raw", "gzip", "ascii"}) {
    NrrdOptions o;
    o.encoding = encoding;
    o.geometry = 2;
    const std::string path = dir.file(std::string("s_") + encoding + ".nrrd");
    write_nrrd(path, s, o);
    sweep(path, {}, std::string("nrrd ") + encoding);
  }
  // Detached: sweep the header, then the data file.
  NrrdOptions o;
  o.encoding = "gzip";
  o.detached = true;
  o.geometry = 1;
  const std::string header = dir.file("d.nhdr");
  write_nrrd(header, s, o);
  sweep(header, {}, "nhdr header");
  const std::string data = dir.file("d.nhdr.raw.gz");
  const Bytes original = read_file(data);
  for (std::size_t length = original.size(); length-- > 0;) {
    fs::resize_file(data, length);
    try {
      read_volume(header);
      ADD_FAILURE() << "truncated gzip data file of " << length << " bytes loaded";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(data), std::string::npos) << e.what();
    }
  }
}

TEST(VolumeIoSweep, Vtk) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Int16, 60, 3);
  for (bool binary : {true, false}) {
    VtkOptions o;
    o.binary = binary;
    o.cell_data = true;
    const std::string path = dir.file(std::string("s_") + (binary ? "binary" : "ascii") + ".vtk");
    write_vtk(path, s, o);
    sweep(path, {}, binary ? "vtk binary" : "vtk ascii");
  }
}

TEST(VolumeIoSweep, Vti) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Float64, 60, 4, true);
  int n = 0;
  for (const char* format : {"ascii", "binary", "appended-raw", "appended-base64"}) {
    for (bool zlib : {false, true}) {
      if (std::string(format) == "ascii" && zlib) continue;
      VtiOptions o;
      o.format = format;
      o.zlib = zlib;
      o.header64 = n % 2 == 1;
      o.extras = false;  // keep the file small: every prefix is tried
      o.block_size = 128;
      const std::string path = dir.file("s" + std::to_string(n++) + ".vti");
      write_vti(path, s, o);
      sweep(path, {}, std::string("vti ") + format + (zlib ? " zlib" : ""));
    }
  }
}

TEST(VolumeIoSweep, Vdb) {
  // The smallest useful VDB file (one leaf, ~10 kB: the internal nodes' masks).
  init_vdb();
  TempDir dir;
  const std::string path = dir.file("s.vdb");
  auto grid = openvdb::FloatGrid::create(-1.0f);
  grid->setName("density");
  grid->setTransform(scale_translate());
  for (int x = 0; x < 4; ++x) grid->tree().setValue(openvdb::Coord(x, x % 2, 1), 0.5f * x);
  grid->tree().setValueOff(openvdb::Coord(5, 5, 5), 3.0f);
  // Default (Blosc + active mask), zip, none, and half floats.
  const std::uint32_t settings[] = {openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK,
                                    openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK,
                                    openvdb::io::COMPRESS_NONE, openvdb::io::COMPRESS_BLOSC};
  for (std::uint32_t compression : settings) {
    grid->setSaveFloatAsHalf(compression == openvdb::io::COMPRESS_BLOSC);
    openvdb::io::File file(path);
    file.setCompression(compression);
    file.write(openvdb::GridPtrVec{grid});
    sweep(path, {}, "vdb compression " + std::to_string(compression));
  }
}

}  // namespace
}  // namespace isowave
