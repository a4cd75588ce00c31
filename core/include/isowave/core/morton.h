#pragma once
// The Morton (Z-order) code of a cell of a 2^21-cell cube: the low 21 bits of
// x, y and z interleaved, x in the lowest bit of each triple (bit 3i of the
// code is bit i of x, 3i + 1 of y, 3i + 2 of z). Sorting cells by it keeps
// neighbours near each other in memory (the simplifier's vertex order) and in
// the order (the .isw 2.2 plane groups, docs/FORMAT.md).
#include <cstdint>

namespace isowave {

constexpr std::uint64_t morton_code(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  const auto spread = [](std::uint64_t v) {
    v &= 0x1FFFFF;
    v = (v | v << 32) & 0x1F00000000FFFFull;
    v = (v | v << 16) & 0x1F0000FF0000FFull;
    v = (v | v << 8) & 0x100F00F00F00F00Full;
    v = (v | v << 4) & 0x10C30C30C30C30C3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

}  // namespace isowave
