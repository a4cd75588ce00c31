// Headerless raw volumes: the geometry and sample type come from the options.
#include "isowave/core/error.h"
#include "volume_io_internal.h"

namespace isowave::detail {

Volume read_raw(const std::string& path, const VolumeReadOptions& options) {
  if (!options.dims || !options.type)
    throw Error(ErrorKind::InvalidArgument, path + ": a .raw volume needs its dimensions and sample type (--dims X,Y,Z --type T)");
  Volume volume;
  volume.dims = *options.dims;
  volume.source_type = *options.type;
  for (std::size_t d : volume.dims) {
    if (d == 0) throw Error(ErrorKind::InvalidArgument, path + ": dimensions must be positive");
  }
  const std::size_t sample_size = scalar_type_size(volume.source_type);
  const std::size_t count = checked_sample_count(volume.dims, sample_size, path);

  InputFile file(path);
  const std::uint64_t expected = static_cast<std::uint64_t>(count) * sample_size;
  if (file.size() != expected) {
    format_error(path, "size mismatch: the file holds " + std::to_string(file.size()) + " bytes but " +
                           std::to_string(volume.dims[0]) + " x " + std::to_string(volume.dims[1]) + " x " +
                           std::to_string(volume.dims[2]) + " " + to_string(volume.source_type) + " samples need " +
                           std::to_string(expected));
  }
  volume.values.resize(count);
  read_binary_samples(file, volume.values.data(), count, volume.source_type, options.big_endian, "raw sample data");
  return volume;
}

}  // namespace isowave::detail
