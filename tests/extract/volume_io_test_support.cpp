// The shared helpers of the volume reader tests (volume_io_test_support.h).
#include "volume_io_test_support.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <type_traits>

#include "isowave/core/error.h"

namespace isowave::volume_io_test {
namespace {

namespace fs = std::filesystem;

bool host_is_little_endian() {
  const std::uint16_t one = 1;
  std::uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

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
  using Wide = std::conditional_t<std::is_signed_v<T>, long long, unsigned long long>;
  std::uniform_int_distribution<Wide> dist(static_cast<Wide>(lo), static_cast<Wide>(hi));
  for (std::size_t i = 0; i < count; ++i) {
    T v = i == 0 ? lo : i == 1 ? hi : i == 2 ? T(0) : static_cast<T>(dist(rng));
    push_value<T>(s, v);
  }
}

}  // namespace

TempDir::TempDir() {
  static int counter = 0;
  // Prefer a RAM directory: the sweeps write thousands of small files.
  std::error_code ec;
  const fs::path shm = "/dev/shm";
  const fs::path base = fs::is_directory(shm, ec) && ::access(shm.c_str(), W_OK) == 0 ? shm : fs::temp_directory_path();
  path_ = base / ("isowave_volume_io_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

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

Bytes Samples::bytes(bool big_endian) const {
  if (!big_endian) return little;
  Bytes out = little;
  const std::size_t size = scalar_type_size(type);
  for (std::size_t i = 0; i < out.size(); i += size) std::reverse(out.begin() + i, out.begin() + i + size);
  return out;
}

std::string Samples::joined_text(const char* separator) const {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) out += (i ? separator : "") + text[i];
  return out;
}

Samples make_samples(ScalarType type, std::size_t count, std::uint32_t seed, bool nonfinite) {
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
    case ScalarType::Int64: fill_integers<std::int64_t>(s, count, rng); break;
    case ScalarType::UInt64: fill_integers<std::uint64_t>(s, count, rng); break;
    case ScalarType::Float16: {
      // The compiler's _Float16 is the reference for the expected floats.
      for (std::size_t i = 0; i < count; ++i) {
        std::uint16_t bits = static_cast<std::uint16_t>(rng());
        if ((bits & 0x7c00) == 0x7c00) bits &= 0xbfff;  // finite unless asked
        if (i == 1) bits = 0x7bff;                        // 65504, the largest half
        if (i == 2) bits = 0x8001;                        // -2^-24, the smallest subnormal
        if (i == 3) bits = 0x3555;                        // 0.333251953125
        if (nonfinite && i == 4) bits = 0x7e00;
        if (nonfinite && i == 5) bits = 0x7c00;
        if (nonfinite && i == 6) bits = 0xfc00;
        _Float16 half;
        std::memcpy(&half, &bits, 2);
        s.little.push_back(static_cast<std::uint8_t>(bits));
        s.little.push_back(static_cast<std::uint8_t>(bits >> 8));
        const float value = static_cast<float>(half);
        char buffer[32];
        std::snprintf(buffer, sizeof buffer, "%.9g", static_cast<double>(value));
        s.text.emplace_back(buffer);
        s.expected.push_back(value);
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

void expect_error(const std::string& path, const VolumeReadOptions& options, const std::string& keyword,
                  const std::string& label, const std::string& named) {
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

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::string as_string(const Bytes& b) { return std::string(b.begin(), b.end()); }

void sweep(const std::string& path, const VolumeReadOptions& options, const std::string& label,
           const std::string& extra_file, ByteRange mutable_bytes) {
  const Bytes original = read_file(path);
  ASSERT_FALSE(original.empty()) << label;
  mutable_bytes.end = std::min(mutable_bytes.end, original.size());
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
  if (mutable_bytes.begin >= mutable_bytes.end) trials = 0;
  std::mt19937 rng(1234);
  for (int trial = 0; trial < trials; ++trial) {
    Bytes mutated = original;
    const int flips = 1 + trial % 3;
    for (int f = 0; f < flips; ++f) {
      const std::size_t at = std::uniform_int_distribution<std::size_t>(mutable_bytes.begin, mutable_bytes.end - 1)(rng);
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

}  // namespace isowave::volume_io_test
