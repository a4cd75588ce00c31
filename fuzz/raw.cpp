// The raw reader on hostile bytes (extract/src/read_raw.cpp). The first two
// bytes choose the dims (1 to 8 each), the sample type and the byte order; the
// rest is the file.
#include "fuzz_support.h"
#include "isowave/extract/volume_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  static const isowave::ScalarType kTypes[] = {
      isowave::ScalarType::UInt8, isowave::ScalarType::Int8,   isowave::ScalarType::UInt16,  isowave::ScalarType::Int16,
      isowave::ScalarType::UInt32, isowave::ScalarType::Int32, isowave::ScalarType::Float32, isowave::ScalarType::Float64};
  isowave::VolumeReadOptions options;
  options.dims = {{std::size_t(1) + (data[0] & 7), std::size_t(1) + ((data[0] >> 3) & 7), std::size_t(1) + (data[1] & 7)}};
  options.type = kTypes[(data[1] >> 3) & 7];
  options.big_endian = (data[1] >> 6) & 1;
  const std::string path = isowave::fuzz::write_input(data + 2, size - 2, ".raw");
  isowave::fuzz::expect_clean([&] { isowave::read_volume(path, options); });
  return 0;
}
