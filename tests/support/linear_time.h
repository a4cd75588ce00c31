#pragma once
// Readers run in time linear in their input: a generated hostile file of
// 2 MiB and one of 8 MiB, the larger parsed in under 8x the smaller's time
// (4x is linear; a ratio, not a time, so the host's speed does not matter).
// Small-input fuzzing cannot show quadratic behaviour; these inputs do.
#include <cstddef>
#include <functional>
#include <string>

namespace isowave::test {

// Writes make(bytes) for 2 and 8 MiB to a file named `name` (its extension
// picks the reader) in a temporary directory, times read(path) on each (best
// of three, wall clock) and expects the ratio under 8. `read` parses the whole
// file and checks what it read with gtest assertions.
void expect_linear_time(const std::string& name, const std::function<std::string(std::size_t bytes)>& make,
                        const std::function<void(const std::string& path)>& read);

}  // namespace isowave::test
