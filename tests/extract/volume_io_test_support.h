#pragma once
// Shared by the volume reader tests (test_read_*.cpp): temporary files,
// generated samples with the floats a reader must produce, expectations on a
// read volume or its Error, gzip, and the truncation / byte-flip sweep.
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/extract/volume_io.h"

namespace isowave::volume_io_test {

using Bytes = std::vector<std::uint8_t>;

constexpr ScalarType kAllTypes[] = {ScalarType::UInt8,  ScalarType::Int8,  ScalarType::UInt16,  ScalarType::Int16,
                                    ScalarType::UInt32, ScalarType::Int32, ScalarType::Float32, ScalarType::Float64};
// Every sample type (the NumPy, HDF5 and NetCDF readers take them all).
constexpr ScalarType kEveryType[] = {ScalarType::UInt8,  ScalarType::Int8,    ScalarType::UInt16,  ScalarType::Int16,
                                     ScalarType::UInt32, ScalarType::Int32,   ScalarType::Int64,   ScalarType::UInt64,
                                     ScalarType::Float16, ScalarType::Float32, ScalarType::Float64};
// The dimensions of the generated test volumes.
constexpr std::array<std::size_t, 3> kDims{5, 4, 3};

// A fresh directory (in /dev/shm when writable), removed with its files.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// Whole-file writes (a failed write is a test failure) and reads.
void write_file(const std::string& path, const void* data, std::size_t size);
void write_file(const std::string& path, const Bytes& data);
void write_file(const std::string& path, const std::string& data);
Bytes read_file(const std::string& path);

void append(Bytes& out, const std::string& text);
void append(Bytes& out, const Bytes& bytes);

// Generated samples: little-endian bytes, exact decimal text, and the floats a
// reader must produce (static_cast<float> of the stored value).
struct Samples {
  ScalarType type = ScalarType::Float32;
  Bytes little;
  std::vector<std::string> text;
  std::vector<float> expected;

  Bytes bytes(bool big_endian) const;
  std::string joined_text(const char* separator = " ") const;
};

// Distinct values over each type's whole range, including its extremes;
// `nonfinite` puts NaN, +Inf and -Inf into the float types.
Samples make_samples(ScalarType type, std::size_t count, std::uint32_t seed, bool nonfinite = false);

std::size_t count_nonfinite(const std::vector<float>& values);

// Expects the volume's samples to be `expected` (NaN matching NaN) and its
// nonfinite count to agree.
void expect_values(const Volume& volume, const std::vector<float>& expected, const std::string& label);
void expect_geometry(const Volume& volume, std::array<std::size_t, 3> dims, Vec3 spacing, Vec3 origin,
                     const std::string& label);

// Expects read_volume to throw isowave::Error whose message names `path`
// (or `named` if given) and contains `keyword` if given.
void expect_error(const std::string& path, const VolumeReadOptions& options, const std::string& keyword,
                  const std::string& label, const std::string& named = "");

// A gzip stream of `data` (zlib, level 6).
Bytes gzip(const Bytes& data);

// `text` with the first `from` replaced by `to` (a test failure if absent).
std::string replace(std::string text, const std::string& from, const std::string& to);
std::string as_string(const Bytes& b);

// Reads every proper prefix of the file at `path` and random byte flips of it:
// each must load or throw an isowave::Error naming `path` (or `extra_file`),
// and at least one must throw. Restores the file. Mutations touch only the
// bytes in `mutable_bytes`, none if it is empty (for libraries that crash on
// corrupt metadata; see docs/CLI.md).
struct ByteRange {
  std::size_t begin = 0, end = SIZE_MAX;
};
void sweep(const std::string& path, const VolumeReadOptions& options, const std::string& label,
           const std::string& extra_file = "", ByteRange mutable_bytes = {});

}  // namespace isowave::volume_io_test
