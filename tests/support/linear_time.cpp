#include "support/linear_time.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <unistd.h>

namespace isowave::test {
namespace {

namespace fs = std::filesystem;

double best_seconds(const std::string& path, const std::function<void(const std::string&)>& read) {
  double best = 1e30;
  for (int run = 0; run < 3; ++run) {
    const auto start = std::chrono::steady_clock::now();
    read(path);
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

}  // namespace

void expect_linear_time(const std::string& name, const std::function<std::string(std::size_t)>& make,
                        const std::function<void(const std::string&)>& read) {
  constexpr std::size_t kMiB = 1 << 20;
  const fs::path directory = fs::temp_directory_path() / ("isowave_linear_" + std::to_string(::getpid()));
  fs::create_directories(directory);
  double seconds[2];
  for (int k = 0; k < 2; ++k) {
    const std::string path = (directory / (std::to_string(k) + name)).string();
    std::ofstream(path, std::ios::binary) << make(k == 0 ? 2 * kMiB : 8 * kMiB);
    seconds[k] = best_seconds(path, read);
  }
  fs::remove_all(directory);
  EXPECT_LT(seconds[1], 8 * seconds[0]) << name << ": 2 MiB in " << seconds[0] << " s, 8 MiB in " << seconds[1] << " s";
}

}  // namespace isowave::test
