#pragma once
// Which way an extracted isosurface's face normals point relative to its
// scalar field: extraction's default is toward lower values (out of the
// region f >= iso); with --flip (SignedDistanceField::flip) toward higher
// values. A face whose normal disagrees with the field gradient at its
// centroid is "folded".
#include <cstdint>

namespace isowave {

enum class Orientation : std::uint8_t {
  TowardLower = 0,   // normals point against the gradient (the default)
  TowardHigher = 1,  // normals point along the gradient (--flip)
};

// The orientation extraction with `flip` gives.
inline Orientation orientation_from_flip(bool flip) {
  return flip ? Orientation::TowardHigher : Orientation::TowardLower;
}

}  // namespace isowave
