#pragma once
// Shared pieces of the volume readers (not installed): error helpers, a
// checked file reader, byte-to-float sample decoding and text scanning.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "isowave/core/volume.h"
#include "isowave/extract/volume_io.h"

namespace isowave::detail {

// Error(Format, "PATH: WHAT") and Error(Io, "PATH: WHAT").
[[noreturn]] void format_error(const std::string& path, const std::string& what);

// The geometry every stage handles (squares and cubes of lengths stay far
// from double's limits); check_geometry() and the options enforce it.
constexpr double kMinSpacing = 1e-30, kMaxSpacing = 1e30, kMaxCoordinate = 1e30;
[[noreturn]] void io_error(const std::string& path, const std::string& what);

// The most bytes a zlib/gzip stream of `compressed` bytes can inflate to
// (deflate's limit is 1032:1, plus slack for headers); used to refuse
// allocations a compressed file cannot justify.
std::uint64_t max_inflated_size(std::uint64_t compressed);

// A regular file opened for reading; every failure is an Error naming it.
class InputFile {
 public:
  explicit InputFile(std::string path);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::string& path() const { return path_; }
  std::uint64_t size() const { return size_; }
  std::uint64_t tell() const;
  void seek(std::uint64_t offset);
  // Reads up to `bytes`; returns fewer only at the end of the file.
  std::size_t read_some(void* data, std::size_t bytes);
  // Reads exactly `bytes` or throws Error(Format) "truncated ... (WHAT)".
  void read_exact(void* data, std::size_t bytes, const char* what);
  // One byte, or -1 at the end of the file.
  int get();
  // The whole file (its size justifies the allocation).
  std::vector<char> read_all();

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0;
};

// The product of the dimensions, or Error(Format) when a dimension is zero or
// the product (times `bytes_per_sample`) overflows.
std::size_t checked_sample_count(const std::array<std::size_t, 3>& dims, std::size_t bytes_per_sample,
                                 const std::string& path);

// Converts `count` samples of `type` starting at `src` to float.
void decode_samples(const std::uint8_t* src, std::size_t count, ScalarType type, bool big_endian, float* dst);

// Turns a byte stream delivered in arbitrary pieces into float samples.
class SampleDecoder {
 public:
  SampleDecoder(float* out, std::size_t count, ScalarType type, bool big_endian);
  // Into `grow` (empty, with capacity for `count`, see reserve_samples()),
  // which grows as samples arrive: memory follows the data actually decoded,
  // not what a (possibly lying) header declares.
  SampleDecoder(std::vector<float>& grow, std::size_t count, ScalarType type, bool big_endian);
  // Consumes bytes; the caller never pushes more than bytes_remaining().
  void push(const std::uint8_t* data, std::size_t bytes);
  std::uint64_t bytes_remaining() const { return remaining_bytes_; }
  bool full() const { return remaining_bytes_ == 0; }

 private:
  float* out_;
  std::vector<float>* grow_ = nullptr;
  ScalarType type_;
  bool big_endian_;
  std::size_t sample_size_;
  std::uint64_t remaining_bytes_;
  std::uint8_t carry_[8] = {};
  std::size_t carry_size_ = 0;
};

// Reserves (without touching) room for `count` samples of a compressed array
// in the empty `values`; Error(Format) naming `where` when the machine cannot.
void reserve_samples(std::vector<float>& values, std::size_t count, const std::string& where);

// Reads count samples from the file's current position (the caller has
// checked that the file holds them).
void read_binary_samples(InputFile& file, float* out, std::size_t count, ScalarType type, bool big_endian,
                         const char* what);

// Whitespace-separated (and, if allowed, comma-separated) numbers parsed into
// floats; nan/inf are accepted. Fails with Error(Format) on a bad token, on
// too few numbers and (when `exact`) on extra non-blank text.
void parse_text_samples(const char* begin, const char* end, std::size_t count, ScalarType type, bool allow_commas,
                        bool exact, float* out, const std::string& path, const std::string& what);

// A number parsed strictly from a whole token (no trailing characters).
bool parse_double(std::string_view text, double& value);
bool parse_int64(std::string_view text, std::int64_t& value);

std::string to_lower(std::string_view text);
std::string_view trim(std::string_view text);
std::vector<std::string_view> split_whitespace(std::string_view text);
bool iequals(std::string_view a, std::string_view b);

// Reverses the axes whose spacing is negative so that every spacing is
// positive and world positions of the samples are unchanged.
void make_spacing_positive(Volume& volume);

// Throws Error(Format) unless the spacing is finite and positive and the
// origin finite (negative spacings must have been flipped first).
void check_geometry(const Volume& volume, const std::string& path);

// The readers behind read_volume(); each returns a volume with values filled
// in (nonfinite_count and option overrides are applied by read_volume()).
Volume read_raw(const std::string& path, const VolumeReadOptions& options);
Volume read_nrrd(const std::string& path, const VolumeReadOptions& options);
Volume read_vtk_legacy(const std::string& path, const VolumeReadOptions& options);
Volume read_vti(const std::string& path, const VolumeReadOptions& options);
Volume read_vdb(const std::string& path, const VolumeReadOptions& options);
Volume read_npy(const std::string& path, const VolumeReadOptions& options);
// `selection` is the dataset (HDF5) or variable[@time] (NetCDF) named after
// the file's ':' or by options.field; empty: the file's only candidate.
Volume read_hdf5(const std::string& path, const std::string& selection, const VolumeReadOptions& options);
Volume read_netcdf(const std::string& path, const std::string& selection, const VolumeReadOptions& options);

// The sample count of a dataset (HDF5, NetCDF) in a `file_bytes`-byte file;
// Error(Format) naming `what` when it is empty, overflows, or holds more
// bytes (`bytes_per_sample` each) than max_inflated_size(file_bytes): chunks
// may be deflated, but no file justifies more.
std::size_t checked_stored_count(const std::string& path, const std::string& what, const std::array<std::size_t, 3>& dims,
                                 std::size_t bytes_per_sample, std::uint64_t file_bytes);

}  // namespace isowave::detail
