// The mesh readers on hostile bytes (core/src/mesh_io.cpp): a file starting
// "ply" is read as PLY, one starting "OFF"/"COFF"/"NOFF" as OFF, anything else
// as OBJ.
#include "fuzz_support.h"
#include "isowave/core/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string head(reinterpret_cast<const char*>(data), size < 4 ? size : 4);
  const char* extension = head.rfind("ply", 0) == 0 ? ".ply"
                          : head.find("OFF") != std::string::npos ? ".off" : ".obj";
  const std::string path = isowave::fuzz::write_input(data, size, extension);
  isowave::fuzz::expect_clean([&] { isowave::read_mesh(path); });
  return 0;
}
