#include "isowave/core/volume.h"

#include <cmath>

namespace isowave {

const char* to_string(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: return "uint8";
    case ScalarType::Int8: return "int8";
    case ScalarType::UInt16: return "uint16";
    case ScalarType::Int16: return "int16";
    case ScalarType::UInt32: return "uint32";
    case ScalarType::Int32: return "int32";
    case ScalarType::Float32: return "float32";
    case ScalarType::Float64: return "float64";
    case ScalarType::Int64: return "int64";
    case ScalarType::UInt64: return "uint64";
    case ScalarType::Float16: return "float16";
  }
  return "unknown";
}

std::size_t scalar_type_size(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: case ScalarType::Int8: return 1;
    case ScalarType::UInt16: case ScalarType::Int16: case ScalarType::Float16: return 2;
    case ScalarType::UInt32: case ScalarType::Int32: case ScalarType::Float32: return 4;
    case ScalarType::Float64: case ScalarType::Int64: case ScalarType::UInt64: return 8;
  }
  return 1;
}

double Volume::cell_size() const { return std::cbrt(spacing.x * spacing.y * spacing.z); }

}  // namespace isowave
