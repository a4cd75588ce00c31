// The NumPy .npy reader on hostile bytes (extract/src/read_npy.cpp).
#include "fuzz_support.h"
#include "isowave/extract/volume_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = isowave::fuzz::write_input(data, size, ".npy");
  isowave::fuzz::expect_clean([&] { isowave::read_volume(path); });
  return 0;
}
