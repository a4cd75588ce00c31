// NetCDF (.nc, classic, 64-bit offset, CDF-5 or NetCDF-4) through
// libnetcdf: one numeric variable, 3-D (z, y, x) or 4-D (time, z, y, x) with
// a time index. A classic header is checked here before libnetcdf parses it.
#include <netcdf.h>

#include <algorithm>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "volume_io_internal.h"

namespace isowave::detail {
namespace {

// libnetcdf is not thread-safe: one reader at a time.
std::mutex& library_mutex() {
  static std::mutex mutex;
  return mutex;
}

void check(int status, const std::string& path, const std::string& what) {
  if (status != NC_NOERR) format_error(path, what + " (" + nc_strerror(status) + ")");
}

class NcFile {
 public:
  explicit NcFile(const std::string& path) {
    check(nc_open(path.c_str(), NC_NOWRITE, &id_), path, "not a readable NetCDF file");
  }
  ~NcFile() { nc_close(id_); }
  NcFile(const NcFile&) = delete;
  NcFile& operator=(const NcFile&) = delete;
  int id() const { return id_; }

 private:
  int id_ = -1;
};

// "name@T" -> name and time index T; "name" -> name alone.
struct Selection {
  std::string name;
  std::optional<std::size_t> time;
};

Selection parse_selection(const std::string& text, const std::string& path) {
  const std::size_t at = text.rfind('@');
  if (at == std::string::npos) return {text, std::nullopt};
  const std::string index = text.substr(at + 1);
  std::int64_t t = 0;
  if (index.empty() || index.find_first_not_of("0123456789") != std::string::npos || !parse_int64(index, t))
    throw Error(ErrorKind::InvalidArgument, path + ": bad time index '" + index + "' (expected FILE.nc:VARIABLE@T, T >= 0)");
  return {text.substr(0, at), static_cast<std::size_t>(t)};
}

// A variable that can be a volume: numeric, and 3-D or 4-D with the unlimited
// (or a 'time') dimension first.
struct VolumeVariable {
  int id = -1;
  std::string name;
  nc_type type = NC_NAT;
  std::vector<std::size_t> lengths;  // slowest first: (z, y, x) or (time, z, y, x)
};

std::optional<ScalarType> sample_type(nc_type type) {
  switch (type) {
    case NC_BYTE: return ScalarType::Int8;
    case NC_UBYTE: return ScalarType::UInt8;
    case NC_SHORT: return ScalarType::Int16;
    case NC_USHORT: return ScalarType::UInt16;
    case NC_INT: return ScalarType::Int32;
    case NC_UINT: return ScalarType::UInt32;
    case NC_INT64: return ScalarType::Int64;
    case NC_UINT64: return ScalarType::UInt64;
    case NC_FLOAT: return ScalarType::Float32;
    case NC_DOUBLE: return ScalarType::Float64;
    default: return std::nullopt;  // char, string, user-defined types
  }
}

bool is_time_dimension(int file, int dim) {
  int count = 0;
  if (nc_inq_unlimdims(file, &count, nullptr) == NC_NOERR && count > 0) {
    std::vector<int> unlimited(static_cast<std::size_t>(count));
    if (nc_inq_unlimdims(file, &count, unlimited.data()) == NC_NOERR &&
        std::find(unlimited.begin(), unlimited.end(), dim) != unlimited.end())
      return true;
  }
  char name[NC_MAX_NAME + 1] = {};
  return nc_inq_dimname(file, dim, name) == NC_NOERR && iequals(name, "time");
}

// The variable `id` as a volume, or nothing (with the reason in `why`).
std::optional<VolumeVariable> volume_variable(int file, int id, std::string* why = nullptr) {
  VolumeVariable v;
  v.id = id;
  char name[NC_MAX_NAME + 1] = {};
  int rank = 0;
  if (nc_inq_varname(file, id, name) != NC_NOERR || nc_inq_vartype(file, id, &v.type) != NC_NOERR ||
      nc_inq_varndims(file, id, &rank) != NC_NOERR || rank < 0 || rank > NC_MAX_VAR_DIMS)
    return std::nullopt;
  v.name = name;
  const auto reject = [&](const std::string& reason) -> std::optional<VolumeVariable> {
    if (why) *why = reason;
    return std::nullopt;
  };
  if (!sample_type(v.type)) return reject("does not hold numbers");
  if (rank != 3 && rank != 4) return reject("has " + std::to_string(rank) + " dimensions (3-D, or 4-D with time first, are volumes)");
  std::vector<int> dims(static_cast<std::size_t>(rank));
  if (nc_inq_vardimid(file, id, dims.data()) != NC_NOERR) return reject("has unreadable dimensions");
  if (rank == 4 && !is_time_dimension(file, dims[0]))
    return reject("is 4-D but its first dimension is neither unlimited nor named time");
  for (const int d : dims) {
    std::size_t length = 0;
    if (nc_inq_dimlen(file, d, &length) != NC_NOERR) return reject("has unreadable dimensions");
    v.lengths.push_back(length);
  }
  return v;
}

std::vector<VolumeVariable> volume_variables(int file) {
  int count = 0;
  std::vector<VolumeVariable> found;
  if (nc_inq_nvars(file, &count) != NC_NOERR) return found;
  for (int id = 0; id < count; ++id)
    if (auto v = volume_variable(file, id)) found.push_back(std::move(*v));
  return found;
}

std::string list_text(const std::vector<VolumeVariable>& variables) {
  if (variables.empty()) return "none";
  std::string text;
  for (std::size_t i = 0; i < variables.size() && i < 10; ++i) text += (i ? ", " : "") + variables[i].name;
  if (variables.size() > 10) text += ", ... (" + std::to_string(variables.size()) + " in all)";
  return text;
}

VolumeVariable choose_variable(int file, const std::string& name, const std::string& path) {
  if (name.empty()) {
    std::vector<VolumeVariable> found = volume_variables(file);
    if (found.size() != 1)
      format_error(path, found.empty() ? std::string("no 3-D (or time-dependent 3-D) numeric variable in the file")
                                       : "several volume variables; name one as FILE.nc:VARIABLE (" + list_text(found) + ")");
    return std::move(found[0]);
  }
  int id = -1;
  if (nc_inq_varid(file, name.c_str(), &id) != NC_NOERR)
    format_error(path, "no variable '" + name + "' (volume variables: " + list_text(volume_variables(file)) + ")");
  std::string why;
  std::optional<VolumeVariable> v = volume_variable(file, id, &why);
  if (!v) format_error(path, "variable '" + name + "' " + (why.empty() ? "cannot be read" : why));
  return std::move(*v);
}

// Reads the (z, y, x) block at `start` as float. Doubles are read as doubles
// and narrowed here, so that values beyond float's range become +-Inf (the
// library would substitute its fill value), a bounded slab at a time.
void read_block(int file, const VolumeVariable& v, std::vector<std::size_t> start, const std::array<std::size_t, 3>& dims,
                float* out, const std::string& path) {
  std::vector<std::size_t> count(v.lengths.size(), 1);
  const std::size_t z_axis = v.lengths.size() - 3;
  count[z_axis] = dims[2];
  count[z_axis + 1] = dims[1];
  count[z_axis + 2] = dims[0];
  const std::string what = "cannot read variable '" + v.name + "'";
  if (v.type != NC_DOUBLE) {
    check(nc_get_vara_float(file, v.id, start.data(), count.data(), out), path, what);
    return;
  }
  // Slabs of whole chunks along z (when chunked) of about a million samples.
  const std::size_t slice = dims[0] * dims[1];
  std::size_t depth = std::max<std::size_t>(1, (std::size_t{1} << 20) / slice);
  int storage = NC_CONTIGUOUS;
  std::vector<std::size_t> chunks(v.lengths.size(), 1);
  if (nc_inq_var_chunking(file, v.id, &storage, chunks.data()) == NC_NOERR && storage == NC_CHUNKED &&
      chunks[z_axis] > 0)
    depth = (depth + chunks[z_axis] - 1) / chunks[z_axis] * chunks[z_axis];
  depth = std::min(depth, dims[2]);
  std::vector<double> slab(depth * slice);
  for (std::size_t z = 0; z < dims[2]; z += depth) {
    const std::size_t n = std::min(depth, dims[2] - z);
    start[z_axis] = z;
    count[z_axis] = n;
    check(nc_get_vara_double(file, v.id, start.data(), count.data(), slab.data()), path, what);
    std::transform(slab.begin(), slab.begin() + static_cast<std::ptrdiff_t>(n * slice), out + z * slice,
                   [](double value) { return static_cast<float>(value); });
  }
}

// A walk over a classic (CDF-1, CDF-2, CDF-5) header that checks every count
// and length against the bytes left, before libnetcdf parses it: libnetcdf
// 4.9.0 crashes on some corrupt counts (SIGSEGV in nc_open for a dimension
// count of 0x40000004). Other files (NetCDF-4 is HDF5) are left to the library.
class ClassicHeaderCheck {
 public:
  // Thrown when the header runs past `bytes`, a prefix of the file.
  struct NeedMoreBytes {};

  ClassicHeaderCheck(const std::vector<char>& bytes, std::uint64_t file_size, const std::string& path)
      : bytes_(bytes), truncated_window_(bytes.size() < file_size), path_(path) {}

  void run() {
    if (bytes_.size() < 4 || bytes_[0] != 'C' || bytes_[1] != 'D' || bytes_[2] != 'F') return;  // not classic
    const int version = bytes_[3];
    if (version != 1 && version != 2 && version != 5) return;  // libnetcdf names the problem
    wide_ = version == 5;
    at_ = 4;
    count(0);  // numrecs
    const std::uint64_t dims = list(kDimension, 4 + (wide_ ? 16 : 8));
    for (std::uint64_t d = 0; d < dims; ++d) name(), count(0);
    attributes();
    const std::uint64_t variables = list(kVariable, 4 + (wide_ ? 32 : 20));
    for (std::uint64_t v = 0; v < variables; ++v) {
      name();
      const std::uint64_t rank = count(wide_ ? 8 : 4);
      if (rank > NC_MAX_VAR_DIMS) fail("a variable has " + std::to_string(rank) + " dimensions");
      for (std::uint64_t r = 0; r < rank; ++r)
        if (count(0) >= dims) fail("a variable names dimension " + std::to_string(r) + " that does not exist");
      attributes();
      type();
      count(0);                             // vsize
      skip(version == 1 ? 4 : 8, "begin");  // the data's offset
    }
  }

 private:
  static constexpr std::uint32_t kDimension = 0x0a, kVariable = 0x0b, kAttribute = 0x0c;

  [[noreturn]] void fail(const std::string& what) const {
    format_error(path_, "corrupt NetCDF header: " + what);
  }
  void skip(std::uint64_t n, const char* what) {
    if (n > bytes_.size() - at_) {
      if (truncated_window_) throw NeedMoreBytes{};
      fail(std::string("the file ends within ") + what);
    }
    at_ += static_cast<std::size_t>(n);
  }
  std::uint64_t word(std::size_t size, const char* what) {
    const std::size_t start = at_;
    skip(size, what);
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < size; ++i) value = value << 8 | static_cast<unsigned char>(bytes_[start + i]);
    return value;
  }
  // A count (nelems, a length) whose items take at least `item_bytes` each.
  std::uint64_t count(std::size_t item_bytes) {
    const std::uint64_t n = word(wide_ ? 8 : 4, "a count");
    if (item_bytes > 0 && n > (bytes_.size() - at_) / item_bytes) {
      if (truncated_window_) throw NeedMoreBytes{};
      fail("a count of " + std::to_string(n) + " is more than the file holds");
    }
    return n;
  }
  // ABSENT (two zero words) or TAG and a count of items of at least `item_bytes`.
  std::uint64_t list(std::uint32_t tag, std::size_t item_bytes) {
    const std::uint64_t found = word(4, "a list tag");
    if (found != 0 && found != tag) fail("a list tag " + std::to_string(found) + " where " + std::to_string(tag) + " belongs");
    const std::uint64_t n = count(item_bytes);
    if (found == 0 && n != 0) fail("an absent list with " + std::to_string(n) + " items");
    return n;
  }
  void name() {
    const std::uint64_t length = count(1);
    if (length == 0 || length > NC_MAX_NAME) fail("a name of " + std::to_string(length) + " bytes");
    skip((length + 3) / 4 * 4, "a name");
  }
  std::size_t type() {
    const std::uint64_t t = word(4, "a type");
    static constexpr std::size_t kSizes[] = {0, 1, 1, 2, 4, 4, 8, 1, 2, 4, 8, 8};  // NC_BYTE .. NC_UINT64
    if (t < 1 || t > (wide_ ? 11u : 6u)) fail("unknown type " + std::to_string(t));
    return kSizes[t];
  }
  void attributes() {
    const std::uint64_t n = list(kAttribute, wide_ ? 24 : 16);
    for (std::uint64_t a = 0; a < n; ++a) {
      name();
      const std::size_t size = type();
      const std::uint64_t values = count(size);
      skip((values * size + 3) / 4 * 4, "attribute values");
    }
  }

  const std::vector<char>& bytes_;
  bool truncated_window_;
  const std::string& path_;
  bool wide_ = false;
  std::size_t at_ = 0;
};

// Reads as much of the file as the header needs (64 KiB, 1 MiB, ... the whole
// file), so that the check costs next to nothing on large files.
void check_classic_header(const std::string& path) {
  InputFile file(path);
  for (std::uint64_t window = 64 << 10;; window *= 16) {
    std::vector<char> head(static_cast<std::size_t>(std::min(file.size(), window)));
    file.seek(0);
    file.read_exact(head.data(), head.size(), "NetCDF header");
    try {
      ClassicHeaderCheck(head, file.size(), path).run();
      return;
    } catch (const ClassicHeaderCheck::NeedMoreBytes&) {
    }
  }
}

}  // namespace

Volume read_netcdf(const std::string& path, const std::string& selection, const VolumeReadOptions& options) {
  const std::uint64_t file_bytes = InputFile(path).size();  // a missing or special file fails here, plainly
  const Selection selected = parse_selection(selection, path);
  check_classic_header(path);
  const std::lock_guard<std::mutex> lock(library_mutex());
  const NcFile file(path);
  const VolumeVariable v = choose_variable(file.id(), selected.name, path);
  const std::string what = "variable '" + v.name + "'";

  std::vector<std::size_t> start(v.lengths.size(), 0);
  if (v.lengths.size() == 4) {
    if (!selected.time)
      throw Error(ErrorKind::InvalidArgument, path + ": " + what + " has " + std::to_string(v.lengths[0]) +
                                                  " time steps; choose one as FILE.nc:" + v.name + "@T");
    if (*selected.time >= v.lengths[0])
      format_error(path, "time index " + std::to_string(*selected.time) + " is out of range for " + what +
                             (v.lengths[0] == 0 ? " (it has no time steps)"
                                                : " (0.." + std::to_string(v.lengths[0] - 1) + ")"));
    start[0] = *selected.time;
  } else if (selected.time) {
    throw Error(ErrorKind::InvalidArgument, path + ": " + what + " is 3-D; it takes no time index");
  }

  // NetCDF lists dimensions slowest first: (z, y, x).
  Volume volume;
  const std::size_t z_axis = v.lengths.size() - 3;
  volume.dims = {v.lengths[z_axis + 2], v.lengths[z_axis + 1], v.lengths[z_axis]};
  volume.source_type = *sample_type(v.type);
  const std::size_t count = checked_stored_count(path, what, volume.dims, scalar_type_size(volume.source_type), file_bytes);
  reserve_samples(volume.values, count, path);
  volume.values.resize(count);
  read_block(file.id(), v, start, volume.dims, volume.values.data(), path);
  (void)options;
  return volume;
}

}  // namespace isowave::detail
