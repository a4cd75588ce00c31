// read_volume(): dispatch by extension or the builtin: prefix, plus the
// helpers every reader shares (checked file access, sample decoding, text
// number scanning, geometry checks).
#include "isowave/extract/volume_io.h"

#include <cassert>
#include <cstdio>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

#include "isowave/core/error.h"
#include "isowave/extract/builtin_fields.h"
#include "volume_io_internal.h"

namespace isowave {
namespace detail {

void format_error(const std::string& path, const std::string& what) {
  throw Error(ErrorKind::Format, path + ": " + what);
}

void io_error(const std::string& path, const std::string& what) { throw Error(ErrorKind::Io, path + ": " + what); }

std::uint64_t max_inflated_size(std::uint64_t compressed) {
  // Deflate codes a 258-byte match in at least 2 bits: at most 1032:1.
  constexpr std::uint64_t kRatio = 1032;
  if (compressed > std::numeric_limits<std::uint64_t>::max() / kRatio - 4096) return std::numeric_limits<std::uint64_t>::max();
  return compressed * kRatio + 4096;
}

// ---------------------------------------------------------------------------
// InputFile

InputFile::InputFile(std::string path) : path_(std::move(path)) {
  struct stat info {};
  if (::stat(path_.c_str(), &info) != 0) io_error(path_, std::string("cannot open: ") + std::strerror(errno));
  if (!S_ISREG(info.st_mode)) io_error(path_, "cannot read: not a regular file");
  file_ = std::fopen(path_.c_str(), "rb");
  if (!file_) io_error(path_, std::string("cannot open: ") + std::strerror(errno));
  size_ = static_cast<std::uint64_t>(info.st_size);
}

InputFile::~InputFile() {
  if (file_) std::fclose(file_);
}

std::uint64_t InputFile::tell() const {
  const auto position = ::ftello(file_);
  if (position < 0) io_error(path_, std::string("cannot read: ") + std::strerror(errno));
  return static_cast<std::uint64_t>(position);
}

void InputFile::seek(std::uint64_t offset) {
  if (offset > size_) format_error(path_, "truncated (offset " + std::to_string(offset) + " is past the end of the file)");
  if (::fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0)
    io_error(path_, std::string("cannot seek: ") + std::strerror(errno));
}

std::size_t InputFile::read_some(void* data, std::size_t bytes) {
  if (bytes == 0) return 0;
  const std::size_t got = std::fread(data, 1, bytes, file_);
  if (got < bytes && std::ferror(file_)) io_error(path_, std::string("read failed: ") + std::strerror(errno));
  return got;
}

void InputFile::read_exact(void* data, std::size_t bytes, const char* what) {
  if (read_some(data, bytes) != bytes) format_error(path_, std::string("truncated ") + what);
}

int InputFile::get() {
  const int c = std::getc(file_);
  if (c == EOF && std::ferror(file_)) io_error(path_, std::string("read failed: ") + std::strerror(errno));
  return c == EOF ? -1 : c;
}

std::vector<char> InputFile::read_all() {
  if (size_ > std::numeric_limits<std::size_t>::max() / 2) io_error(path_, "file too large to read");
  std::vector<char> data(static_cast<std::size_t>(size_));
  seek(0);
  const std::size_t got = read_some(data.data(), data.size());
  if (got != data.size()) io_error(path_, "read failed: the file shrank while being read");
  return data;
}

// ---------------------------------------------------------------------------
// Samples

std::size_t checked_sample_count(const std::array<std::size_t, 3>& dims, std::size_t bytes_per_sample,
                                 const std::string& path) {
  const std::string text = std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " + std::to_string(dims[2]);
  if (dims[0] == 0 || dims[1] == 0 || dims[2] == 0) format_error(path, "empty grid dimensions " + text);
  std::size_t count = 1;
  for (std::size_t d : dims) {
    if (__builtin_mul_overflow(count, d, &count)) format_error(path, "grid dimensions " + text + " are too large");
  }
  std::size_t bytes = 0;
  if (__builtin_mul_overflow(count, std::max<std::size_t>(bytes_per_sample, 1), &bytes) ||
      bytes > std::numeric_limits<std::size_t>::max() / 8)
    format_error(path, "grid dimensions " + text + " are too large");
  return count;
}

std::size_t checked_stored_count(const std::string& path, const std::string& what, const std::array<std::size_t, 3>& dims,
                                 std::size_t bytes_per_sample, std::uint64_t file_bytes) {
  const std::size_t count = checked_sample_count(dims, bytes_per_sample, path);
  const std::uint64_t bytes = static_cast<std::uint64_t>(count) * bytes_per_sample;
  if (bytes > max_inflated_size(file_bytes))
    format_error(path, what + " declares " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                           std::to_string(dims[2]) + " samples (" + std::to_string(bytes) + " bytes), more than a " +
                           std::to_string(file_bytes) + "-byte file can hold even compressed");
  return count;
}

namespace {

constexpr bool host_is_big_endian() {
#if defined(__BYTE_ORDER__) && defined(__ORDER_BIG_ENDIAN__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  return true;
#else
  return false;
#endif
}

template <typename U>
U byte_swap(U v) {
  if constexpr (sizeof(U) == 1) return v;
  if constexpr (sizeof(U) == 2) return static_cast<U>(__builtin_bswap16(v));
  if constexpr (sizeof(U) == 4) return static_cast<U>(__builtin_bswap32(v));
  if constexpr (sizeof(U) == 8) return static_cast<U>(__builtin_bswap64(v));
}

template <typename T, typename U>
void decode_typed(const std::uint8_t* src, std::size_t count, bool swap, float* dst) {
  static_assert(sizeof(T) == sizeof(U));
  if (!swap) {
    for (std::size_t i = 0; i < count; ++i) {
      T v;
      std::memcpy(&v, src + i * sizeof(T), sizeof(T));
      dst[i] = static_cast<float>(v);
    }
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      U bits;
      std::memcpy(&bits, src + i * sizeof(T), sizeof(T));
      bits = byte_swap(bits);
      T v;
      std::memcpy(&v, &bits, sizeof(T));
      dst[i] = static_cast<float>(v);
    }
  }
}

// IEEE 754 binary16 to float (exact: every half is a float).
float half_to_float(std::uint16_t h) {
  const int exponent = (h >> 10) & 0x1f;
  const int mantissa = h & 0x3ff;
  float magnitude;
  if (exponent == 0) magnitude = std::ldexp(static_cast<float>(mantissa), -24);
  else if (exponent == 31) magnitude = mantissa ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
  else magnitude = std::ldexp(static_cast<float>(mantissa | 0x400), exponent - 25);
  return (h & 0x8000) ? -magnitude : magnitude;
}

void decode_half(const std::uint8_t* src, std::size_t count, bool swap, float* dst) {
  for (std::size_t i = 0; i < count; ++i) {
    std::uint16_t bits;
    std::memcpy(&bits, src + i * 2, 2);
    dst[i] = half_to_float(swap ? byte_swap(bits) : bits);
  }
}

}  // namespace

void decode_samples(const std::uint8_t* src, std::size_t count, ScalarType type, bool big_endian, float* dst) {
  const bool swap = big_endian != host_is_big_endian();
  switch (type) {
    case ScalarType::UInt8: decode_typed<std::uint8_t, std::uint8_t>(src, count, false, dst); break;
    case ScalarType::Int8: decode_typed<std::int8_t, std::uint8_t>(src, count, false, dst); break;
    case ScalarType::UInt16: decode_typed<std::uint16_t, std::uint16_t>(src, count, swap, dst); break;
    case ScalarType::Int16: decode_typed<std::int16_t, std::uint16_t>(src, count, swap, dst); break;
    case ScalarType::UInt32: decode_typed<std::uint32_t, std::uint32_t>(src, count, swap, dst); break;
    case ScalarType::Int32: decode_typed<std::int32_t, std::uint32_t>(src, count, swap, dst); break;
    case ScalarType::Float32: decode_typed<float, std::uint32_t>(src, count, swap, dst); break;
    case ScalarType::Float64: decode_typed<double, std::uint64_t>(src, count, swap, dst); break;
    case ScalarType::Int64: decode_typed<std::int64_t, std::uint64_t>(src, count, swap, dst); break;
    case ScalarType::UInt64: decode_typed<std::uint64_t, std::uint64_t>(src, count, swap, dst); break;
    case ScalarType::Float16: decode_half(src, count, swap, dst); break;
  }
}

SampleDecoder::SampleDecoder(float* out, std::size_t count, ScalarType type, bool big_endian)
    : out_(out),
      type_(type),
      big_endian_(big_endian),
      sample_size_(scalar_type_size(type)),
      remaining_bytes_(static_cast<std::uint64_t>(count) * scalar_type_size(type)) {}

SampleDecoder::SampleDecoder(std::vector<float>& grow, std::size_t count, ScalarType type, bool big_endian)
    : SampleDecoder(grow.data(), count, type, big_endian) {
  assert(grow.empty() && grow.capacity() >= count);  // data() stays put as it grows
  grow_ = &grow;
}

void reserve_samples(std::vector<float>& values, std::size_t count, const std::string& where) {
  try {
    values.reserve(count);
  } catch (const std::bad_alloc&) {
    format_error(where, "the header declares " + std::to_string(count) + " samples, more than this machine can hold");
  } catch (const std::length_error&) {
    format_error(where, "the header declares " + std::to_string(count) + " samples, more than this machine can hold");
  }
}

void SampleDecoder::push(const std::uint8_t* data, std::size_t bytes) {
  if (bytes > remaining_bytes_) bytes = static_cast<std::size_t>(remaining_bytes_);  // callers bound this; be safe
  remaining_bytes_ -= bytes;
  if (grow_) grow_->resize(grow_->size() + (carry_size_ + bytes) / sample_size_);
  if (carry_size_ > 0) {
    const std::size_t take = std::min(bytes, sample_size_ - carry_size_);
    std::memcpy(carry_ + carry_size_, data, take);
    carry_size_ += take;
    data += take;
    bytes -= take;
    if (carry_size_ < sample_size_) return;
    decode_samples(carry_, 1, type_, big_endian_, out_++);
    carry_size_ = 0;
  }
  const std::size_t whole = bytes / sample_size_;
  decode_samples(data, whole, type_, big_endian_, out_);
  out_ += whole;
  const std::size_t rest = bytes - whole * sample_size_;
  std::memcpy(carry_, data + whole * sample_size_, rest);
  carry_size_ = rest;
}

void read_binary_samples(InputFile& file, float* out, std::size_t count, ScalarType type, bool big_endian,
                         const char* what) {
  SampleDecoder decoder(out, count, type, big_endian);
  std::vector<std::uint8_t> chunk(std::size_t{1} << 20);
  while (!decoder.full()) {
    const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(chunk.size(), decoder.bytes_remaining()));
    const std::size_t got = file.read_some(chunk.data(), want);
    if (got == 0) format_error(file.path(), std::string("truncated ") + what);
    decoder.push(chunk.data(), got);
  }
}

// ---------------------------------------------------------------------------
// Text

std::string to_lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view text) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return text;
}

std::vector<std::string_view> split_whitespace(std::string_view text) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    const std::size_t start = i;
    while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i > start) tokens.push_back(text.substr(start, i - start));
  }
  return tokens;
}

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  }
  return true;
}

namespace {

template <typename T>
bool parse_float_token(const char* begin, const char* end, T& value) {
  if (begin < end && *begin == '+') {
    ++begin;
    if (begin < end && (*begin == '-' || *begin == '+')) return false;
  }
  if (begin == end) return false;
  const auto result = std::from_chars(begin, end, value, std::chars_format::general);
  return result.ec == std::errc() && result.ptr == end;
}

}  // namespace

bool parse_double(std::string_view text, double& value) {
  text = trim(text);
  return parse_float_token(text.data(), text.data() + text.size(), value);
}

bool parse_int64(std::string_view text, std::int64_t& value) {
  text = trim(text);
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (begin < end && *begin == '+') ++begin;
  if (begin == end) return false;
  const auto result = std::from_chars(begin, end, value);
  return result.ec == std::errc() && result.ptr == end;
}

void parse_text_samples(const char* begin, const char* end, std::size_t count, ScalarType type, bool allow_commas,
                        bool exact, float* out, const std::string& path, const std::string& what) {
  const auto is_separator = [allow_commas](char c) {
    return c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\f' || c == '\v' || (allow_commas && c == ',');
  };
  const char* p = begin;
  for (std::size_t i = 0; i < count; ++i) {
    while (p < end && is_separator(*p)) ++p;
    if (p == end) {
      format_error(path, "truncated " + what + ": found " + std::to_string(i) + " of " + std::to_string(count) +
                             " values");
    }
    const char* start = p;
    while (p < end && !is_separator(*p)) ++p;
    bool ok;
    if (type == ScalarType::Float32) {
      float v = 0;
      ok = parse_float_token(start, p, v);
      out[i] = v;
    } else {
      double v = 0;
      ok = parse_float_token(start, p, v);
      out[i] = static_cast<float>(v);
    }
    if (!ok) {
      const std::string token(start, static_cast<std::size_t>(std::min<std::ptrdiff_t>(p - start, 40)));
      format_error(path, "bad number '" + token + "' in " + what + " (value " + std::to_string(i) + ")");
    }
  }
  if (exact) {
    while (p < end && is_separator(*p)) ++p;
    if (p != end) format_error(path, what + " holds more than the " + std::to_string(count) + " declared values");
  }
}

// ---------------------------------------------------------------------------
// Geometry

namespace {
double& axis(Vec3& v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }
}  // namespace

void make_spacing_positive(Volume& volume) {
  for (int a = 0; a < 3; ++a) {
    double& s = axis(volume.spacing, a);
    if (!(s < 0)) continue;
    const std::size_t n = volume.dims[a];
    axis(volume.origin, a) += s * static_cast<double>(n - 1);
    s = -s;
    if (n < 2 || volume.values.empty()) continue;
    const std::size_t nx = volume.dims[0], ny = volume.dims[1], nz = volume.dims[2];
    if (a == 0) {
      for (std::size_t r = 0; r < ny * nz; ++r) std::reverse(volume.values.begin() + r * nx, volume.values.begin() + (r + 1) * nx);
    } else if (a == 1) {
      for (std::size_t k = 0; k < nz; ++k)
        for (std::size_t j = 0; j < ny / 2; ++j)
          std::swap_ranges(volume.values.begin() + volume.index(0, j, k), volume.values.begin() + volume.index(0, j, k) + nx,
                           volume.values.begin() + volume.index(0, ny - 1 - j, k));
    } else {
      const std::size_t slice = nx * ny;
      for (std::size_t k = 0; k < nz / 2; ++k)
        std::swap_ranges(volume.values.begin() + k * slice, volume.values.begin() + (k + 1) * slice,
                         volume.values.begin() + (nz - 1 - k) * slice);
    }
  }
}

void check_geometry(const Volume& volume, const std::string& path) {
  const Vec3& s = volume.spacing;
  if (!(std::isfinite(s.x) && std::isfinite(s.y) && std::isfinite(s.z) && s.x > 0 && s.y > 0 && s.z > 0))
    format_error(path, "invalid spacing (" + std::to_string(s.x) + ", " + std::to_string(s.y) + ", " + std::to_string(s.z) +
                           "): must be finite and non-zero");
  if (!is_finite(volume.origin)) format_error(path, "invalid (non-finite) origin");
}

}  // namespace detail

// ---------------------------------------------------------------------------

ScalarType parse_scalar_type(const std::string& name) {
  const std::string n = detail::to_lower(name);
  if (n == "uint8" || n == "uchar") return ScalarType::UInt8;
  if (n == "int8" || n == "char") return ScalarType::Int8;
  if (n == "uint16" || n == "ushort") return ScalarType::UInt16;
  if (n == "int16" || n == "short") return ScalarType::Int16;
  if (n == "uint32" || n == "uint") return ScalarType::UInt32;
  if (n == "int32" || n == "int") return ScalarType::Int32;
  if (n == "float32" || n == "float") return ScalarType::Float32;
  if (n == "float64" || n == "double") return ScalarType::Float64;
  if (n == "int64") return ScalarType::Int64;
  if (n == "uint64") return ScalarType::UInt64;
  if (n == "float16" || n == "half") return ScalarType::Float16;
  throw Error(ErrorKind::InvalidArgument,
              "unknown sample type '" + name +
                  "' (expected uint8, int8, uint16, int16, uint32, int32, int64, uint64, float16, float32 or float64)");
}

namespace {

Volume read_builtin(const std::string& spec) {
  // builtin:NAME[:N]
  std::string rest = spec.substr(std::strlen("builtin:"));
  std::size_t n = 128;
  const auto colon = rest.find(':');
  if (colon != std::string::npos) {
    const std::string count = rest.substr(colon + 1);
    std::int64_t value = 0;
    if (count.empty() || count.find_first_not_of("0123456789") != std::string::npos || !detail::parse_int64(count, value))
      throw Error(ErrorKind::InvalidArgument, spec + ": bad grid size '" + count + "' (expected builtin:NAME[:N])");
    n = static_cast<std::size_t>(value);
    rest = rest.substr(0, colon);
  }
  if (rest.empty()) throw Error(ErrorKind::InvalidArgument, spec + ": missing field name (expected builtin:NAME[:N])");
  return make_builtin_field(rest, n);
}

}  // namespace

SelectedPath split_selection(const std::string& path) {
  const std::string lower = detail::to_lower(path);
  std::size_t colon = std::string::npos;
  for (const char* ext : {".h5:", ".hdf5:", ".nc:"}) {
    const std::size_t at = lower.find(ext);
    if (at != std::string::npos) colon = std::min(colon, at + std::strlen(ext) - 1);
  }
  struct stat info {};
  if (colon == std::string::npos || (::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode))) return {path, ""};
  return {path.substr(0, colon), path.substr(colon + 1)};
}

namespace {

std::string extension_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return detail::to_lower(path.substr(dot));
}

void check_option_vec(const Vec3& v, bool positive, const char* what) {
  const bool finite = is_finite(v);
  if (!finite || (positive && !(v.x > 0 && v.y > 0 && v.z > 0)))
    throw Error(ErrorKind::InvalidArgument, std::string("invalid ") + what +
                                                (positive ? " (must be finite and positive)" : " (must be finite)"));
  const double low = positive ? detail::kMinSpacing : -detail::kMaxCoordinate;
  const double high = positive ? detail::kMaxSpacing : detail::kMaxCoordinate;
  for (int k = 0; k < 3; ++k)
    if (v[k] < low || v[k] > high) {
      char range[64];
      std::snprintf(range, sizeof range, " (each must be in %g..%g)", low, high);
      throw Error(ErrorKind::InvalidArgument, std::string("invalid ") + what + range);
    }
}

bool is_dataset_container(const std::string& file) {
  const std::string ext = extension_of(file);
  return ext == ".h5" || ext == ".hdf5" || ext == ".nc";
}

// HDF5 and NetCDF: the dataset or variable named in the path or by --field.
Volume read_dataset(const SelectedPath& selected, const VolumeReadOptions& options) {
  if (!selected.selection.empty() && !options.field.empty())
    throw Error(ErrorKind::InvalidArgument, selected.file + ": the dataset is named twice ('" + selected.selection +
                                                "' in the path and '" + options.field + "' by --field)");
  const std::string& name = selected.selection.empty() ? options.field : selected.selection;
  if (extension_of(selected.file) == ".nc") return detail::read_netcdf(selected.file, name, options);
  return detail::read_hdf5(selected.file, name, options);
}

}  // namespace

bool has_volume_extension(const std::string& path) {
  const std::string ext = extension_of(path);
  return ext == ".raw" || ext == ".nrrd" || ext == ".nhdr" || ext == ".vtk" || ext == ".vti" || ext == ".vdb" ||
         ext == ".npy" || ext == ".h5" || ext == ".hdf5" || ext == ".nc";
}

Volume read_volume(const std::string& path, const VolumeReadOptions& options) {
  if (options.spacing) check_option_vec(*options.spacing, true, "spacing");
  if (options.origin) check_option_vec(*options.origin, false, "origin");

  Volume volume;
  if (path.rfind("builtin:", 0) == 0) {
    volume = read_builtin(path);
  } else if (const SelectedPath selected = split_selection(path); is_dataset_container(selected.file)) {
    volume = read_dataset(selected, options);
  } else {
    const std::string ext = extension_of(path);
    // Given the raw geometry, a file of no other known format is raw samples (.bin, .dat, .f32, ...).
    if (ext == ".raw" || (options.dims && options.type && !has_volume_extension(path))) {
      volume = detail::read_raw(path, options);
    } else if (ext == ".nrrd" || ext == ".nhdr") {
      volume = detail::read_nrrd(path, options);
    } else if (ext == ".vtk") {
      volume = detail::read_vtk_legacy(path, options);
    } else if (ext == ".vti") {
      volume = detail::read_vti(path, options);
    } else if (ext == ".vdb") {
      volume = detail::read_vdb(path, options);
    } else if (ext == ".npy") {
      volume = detail::read_npy(path, options);
    } else {
      // A missing file says so, rather than that its name has no known ending.
      struct stat info {};
      if (::stat(path.c_str(), &info) != 0) detail::io_error(path, std::string("cannot open: ") + std::strerror(errno));
      if (!S_ISREG(info.st_mode)) detail::io_error(path, "cannot read: not a regular file");
      throw Error(ErrorKind::InvalidArgument,
                  path + ": unknown volume format '" + ext +
                      "' (use .raw, .nrrd, .nhdr, .vtk, .vti, .vdb, .npy, .h5, .hdf5, .nc or builtin:NAME[:N]; "
                      "--dims and --type read any file as raw)");
    }
  }

  if (options.spacing) volume.spacing = *options.spacing;
  if (options.origin) volume.origin = *options.origin;
  char text[160];
  for (int k = 0; k < 3; ++k) {
    if (volume.spacing[k] < detail::kMinSpacing || volume.spacing[k] > detail::kMaxSpacing) {
      std::snprintf(text, sizeof text, ": spacing %g is outside %g..%g (override it with --spacing)", volume.spacing[k],
                    detail::kMinSpacing, detail::kMaxSpacing);
      throw Error(ErrorKind::Format, path + text);
    }
    if (std::abs(volume.origin[k]) > detail::kMaxCoordinate) {
      std::snprintf(text, sizeof text, ": origin %g is outside +-%g (override it with --origin)", volume.origin[k],
                    detail::kMaxCoordinate);
      throw Error(ErrorKind::Format, path + text);
    }
  }

  std::size_t nonfinite = 0;
  for (const float v : volume.values) nonfinite += std::isfinite(v) ? 0 : 1;
  volume.nonfinite_count = nonfinite;
  return volume;
}

}  // namespace isowave
