#pragma once
// A dense scalar volume: vertex-centred samples on a regular grid, x varying
// fastest. Samples are stored as float whatever the file held (half the memory
// of double; isosurface extraction needs no more precision); the original
// sample type is kept for reports.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "isowave/core/vec3.h"

namespace isowave {

// Float16 is IEEE 754 binary16; Int64/UInt64 samples beyond float's 24-bit
// mantissa are rounded to the nearest float like every other type.
enum class ScalarType : std::uint8_t { UInt8, Int8, UInt16, Int16, UInt32, Int32, Float32, Float64, Int64, UInt64, Float16 };

const char* to_string(ScalarType type);
std::size_t scalar_type_size(ScalarType type);

struct Volume {
  std::array<std::size_t, 3> dims{0, 0, 0};  // samples along x, y, z; the readers give >= 1 each
  Vec3 spacing{1, 1, 1};                      // world units between samples; finite, > 0 (readers flip negative axes)
  Vec3 origin{0, 0, 0};                       // world position of sample (0, 0, 0); finite
  ScalarType source_type = ScalarType::Float32;  // the file's sample type, for reports only
  std::vector<float> values;                  // dims[0] * dims[1] * dims[2] samples; NaN/Inf allowed
  std::size_t nonfinite_count = 0;            // NaN/Inf samples found on load

  std::size_t sample_count() const { return dims[0] * dims[1] * dims[2]; }
  std::size_t index(std::size_t i, std::size_t j, std::size_t k) const { return i + dims[0] * (j + dims[1] * k); }
  float at(std::size_t i, std::size_t j, std::size_t k) const { return values[index(i, j, k)]; }
  Vec3 world(double i, double j, double k) const {
    return {origin.x + spacing.x * i, origin.y + spacing.y * j, origin.z + spacing.z * k};
  }
  // Edge length of one cell in world units; the geometric mean of the
  // spacings on anisotropic grids. Every "% of a cell" and "cells" figure the
  // tools print is relative to this.
  double cell_size() const;
};

}  // namespace isowave
