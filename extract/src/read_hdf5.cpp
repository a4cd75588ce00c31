// HDF5 (.h5, .hdf5) through libhdf5: one 3-D dataset of any integer or
// floating-point type, contiguous or chunked, with whatever filters the
// library decodes (deflate, shuffle, ...), converted to float by the library.
#include <hdf5.h>

#include <optional>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "volume_io_internal.h"

namespace isowave::detail {
namespace {

// An HDF5 identifier, closed when it goes out of scope.
class Hid {
 public:
  Hid(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Hid() {
    if (id_ >= 0) close_(id_);
  }
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// The message of the innermost entry of this thread's HDF5 error stack (the
// place the problem was found), then the stack is cleared.
std::string library_message() {
  std::string message;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* entry, void* data) -> herr_t {
        if (n == 0 && entry->desc) *static_cast<std::string*>(data) = entry->desc;
        return 0;
      },
      &message);
  H5Eclear2(H5E_DEFAULT);
  if (message.size() > 200) message.resize(200);
  return message.empty() ? "HDF5 error" : message;
}

[[noreturn]] void hdf5_error(const std::string& path, const std::string& what) {
  format_error(path, what + " (" + library_message() + ")");
}

// True for an IEEE 754 binary16/32/64 layout. Other layouts (and integers
// with padding bits) take libhdf5's soft conversions, which corrupt files
// can drive out of bounds (stack smashing in H5T__conv_i_f, 1.10.8).
bool is_ieee_float(hid_t type, std::size_t size) {
  std::size_t sign = 0, exponent_at = 0, exponent_bits = 0, mantissa_at = 0, mantissa_bits = 0;
  if (H5Tget_fields(type, &sign, &exponent_at, &exponent_bits, &mantissa_at, &mantissa_bits) < 0) return false;
  const std::size_t bits = 8 * size;
  const std::size_t exponent = size == 2 ? 5 : size == 4 ? 8 : 11;
  return sign == bits - 1 && exponent_bits == exponent && exponent_at == bits - 1 - exponent && mantissa_at == 0 &&
         mantissa_bits == exponent_at && H5Tget_ebias(type) == (std::size_t{1} << (exponent - 1)) - 1 &&
         H5Tget_norm(type) == H5T_NORM_IMPLIED;
}

// The dataset's sample type, or nothing if it is not a number (compound,
// string, enum, ...) of a standard layout: little- or big-endian integers of
// 1, 2, 4 or 8 bytes using every bit, IEEE floats of 2, 4 or 8 bytes.
std::optional<ScalarType> sample_type(hid_t dataset) {
  const Hid type(H5Dget_type(dataset), H5Tclose);
  if (!type.valid()) return std::nullopt;
  const H5T_class_t type_class = H5Tget_class(type.get());
  const std::size_t size = H5Tget_size(type.get());
  const H5T_order_t order = H5Tget_order(type.get());
  if ((size != 1 && size != 2 && size != 4 && size != 8) || H5Tget_precision(type.get()) != 8 * size ||
      H5Tget_offset(type.get()) != 0 || (size > 1 && order != H5T_ORDER_LE && order != H5T_ORDER_BE)) {
    H5Eclear2(H5E_DEFAULT);
    return std::nullopt;
  }
  if (type_class == H5T_FLOAT && size > 1 && is_ieee_float(type.get(), size)) {
    if (size == 2) return ScalarType::Float16;
    if (size == 4) return ScalarType::Float32;
    if (size == 8) return ScalarType::Float64;
  } else if (type_class == H5T_INTEGER) {
    const bool is_signed = H5Tget_sign(type.get()) == H5T_SGN_2;
    if (size == 1) return is_signed ? ScalarType::Int8 : ScalarType::UInt8;
    if (size == 2) return is_signed ? ScalarType::Int16 : ScalarType::UInt16;
    if (size == 4) return is_signed ? ScalarType::Int32 : ScalarType::UInt32;
    if (size == 8) return is_signed ? ScalarType::Int64 : ScalarType::UInt64;
  }
  H5Eclear2(H5E_DEFAULT);
  return std::nullopt;
}

// The dataset's extents, slowest first, or nothing if it has no simple
// dataspace (scalar, null).
std::optional<std::vector<hsize_t>> extents(hid_t dataset) {
  const Hid space(H5Dget_space(dataset), H5Sclose);
  if (!space.valid() || H5Sget_simple_extent_type(space.get()) != H5S_SIMPLE) return std::nullopt;
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0 || rank > H5S_MAX_RANK) return std::nullopt;
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr) != rank) return std::nullopt;
  return dims;
}

bool is_volume_dataset(hid_t dataset) {
  const auto dims = extents(dataset);
  return dims && dims->size() == 3 && sample_type(dataset);
}

// Every 3-D numeric dataset reachable by hard links, as absolute paths.
std::vector<std::string> volume_datasets(hid_t file) {
  std::vector<std::string> found;
  H5Lvisit(
      file, H5_INDEX_NAME, H5_ITER_NATIVE,
      [](hid_t group, const char* name, const H5L_info_t* info, void* data) -> herr_t {
        if (info->type != H5L_TYPE_HARD) return 0;
        const Hid object(H5Oopen(group, name, H5P_DEFAULT), H5Oclose);
        if (object.valid() && H5Iget_type(object.get()) == H5I_DATASET && is_volume_dataset(object.get()))
          static_cast<std::vector<std::string>*>(data)->push_back("/" + std::string(name));
        return 0;
      },
      &found);
  H5Eclear2(H5E_DEFAULT);
  return found;
}

std::string list_text(const std::vector<std::string>& names) {
  if (names.empty()) return "none";
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < 10; ++i) text += (i ? ", " : "") + names[i];
  if (names.size() > 10) text += ", ... (" + std::to_string(names.size()) + " in all)";
  return text;
}

// The dataset `name`, or the file's only 3-D numeric dataset when empty.
std::string choose_dataset(hid_t file, const std::string& name, const std::string& path) {
  if (!name.empty()) return name;
  const std::vector<std::string> found = volume_datasets(file);
  if (found.size() != 1)
    format_error(path, std::string(found.empty() ? "no 3-D numeric dataset in the file"
                                                 : "several 3-D numeric datasets; name one as FILE.h5:/DATASET (" +
                                                       list_text(found) + ")"));
  return found[0];
}

}  // namespace

Volume read_hdf5(const std::string& path, const std::string& selection, const VolumeReadOptions& options) {
  const std::uint64_t file_bytes = InputFile(path).size();  // a missing or special file fails here, plainly
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);              // errors become Error, not text on stderr

  const Hid access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);  // closing the file closes whatever is left open
  const Hid file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, access.get()), H5Fclose);
  if (!file.valid()) hdf5_error(path, "not a readable HDF5 file");

  const std::string name = choose_dataset(file.get(), selection, path);
  const std::string what = "dataset '" + name + "'";
  const htri_t exists = H5Lexists(file.get(), name.c_str(), H5P_DEFAULT);
  const Hid dataset(exists > 0 ? H5Dopen2(file.get(), name.c_str(), H5P_DEFAULT) : H5I_INVALID_HID, H5Dclose);
  if (!dataset.valid()) {
    H5Eclear2(H5E_DEFAULT);
    format_error(path, "no " + what + " (3-D numeric datasets: " + list_text(volume_datasets(file.get())) + ")");
  }

  const auto dims = extents(dataset.get());
  if (!dims) hdf5_error(path, what + " has no readable dataspace");
  if (dims->size() != 3)
    format_error(path, what + " has " + std::to_string(dims->size()) + " dimensions: only 3-D datasets are volumes");
  const std::optional<ScalarType> type = sample_type(dataset.get());
  if (!type)
    format_error(path, what + " does not hold integers of 1, 2, 4 or 8 bytes or IEEE floats of 2, 4 or 8 bytes");

  // HDF5 lists extents slowest first: (z, y, x).
  Volume volume;
  volume.dims = {static_cast<std::size_t>((*dims)[2]), static_cast<std::size_t>((*dims)[1]),
                 static_cast<std::size_t>((*dims)[0])};
  for (int a = 0; a < 3; ++a)
    if ((*dims)[a] != volume.dims[2 - a]) format_error(path, what + " is too large");
  volume.source_type = *type;
  const std::size_t count = checked_stored_count(path, what, volume.dims, scalar_type_size(*type), file_bytes);
  reserve_samples(volume.values, count, path);
  volume.values.resize(count);
  if (H5Dread(dataset.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, volume.values.data()) < 0)
    hdf5_error(path, "cannot read " + what);
  (void)options;
  return volume;
}

}  // namespace isowave::detail
