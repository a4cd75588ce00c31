#pragma once
// What every harness shares: the readers take paths, so each input is written
// to a per-process file in /dev/shm (or $TMPDIR) first; an isowave::Error is
// the readers' answer to bad input, anything else reaches libFuzzer as a
// finding (an uncaught exception aborts).
#include <cstddef>
#include <cstdint>
#include <string>

#include "isowave/core/error.h"

namespace isowave::fuzz {

// Writes the bytes to this process's file with the given extension (".vtk")
// and returns its path. The file is rewritten by the next call.
std::string write_input(const std::uint8_t* data, std::size_t size, const std::string& extension);

// Runs read(), swallowing only isowave::Error.
template <typename Read>
void expect_clean(Read&& read) {
  try {
    read();
  } catch (const Error&) {
  }
}

}  // namespace isowave::fuzz
