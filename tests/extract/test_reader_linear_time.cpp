// Readers run in time linear in their input: a generated hostile file of
// 2 MiB and one of 8 MiB, the larger parsed in under 8x the smaller's time
// (4x is linear; a ratio, not a time, so the host's speed does not matter).
// Small-input fuzzing cannot show quadratic behaviour; these inputs do.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#include "isowave/extract/volume_io.h"

namespace isowave {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMiB = 1 << 20;

// Best of three wall-clock seconds of read_volume(path); the file is valid,
// so the whole of it is parsed.
double read_seconds(const std::string& path) {
  double best = 1e30;
  for (int run = 0; run < 3; ++run) {
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(read_volume(path).values.size(), 8u) << path;
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

// Writes make(bytes) for 2 and 8 MiB and checks the ratio of their read times.
void expect_linear(const std::string& name, const std::function<std::string(std::size_t)>& make) {
  const fs::path directory = fs::temp_directory_path() / ("isowave_linear_" + std::to_string(::getpid()));
  fs::create_directories(directory);
  double seconds[2];
  for (int k = 0; k < 2; ++k) {
    const std::string path = (directory / (std::to_string(k) + name)).string();
    std::ofstream(path, std::ios::binary) << make(k == 0 ? 2 * kMiB : 8 * kMiB);
    seconds[k] = read_seconds(path);
  }
  fs::remove_all(directory);
  EXPECT_LT(seconds[1], 8 * seconds[0]) << name << ": 2 MiB in " << seconds[0] << " s, 8 MiB in " << seconds[1] << " s";
}

// A valid VTI file whose one extra attribute is `bytes` of '&' (each '&'
// used to start a search to the end of the attribute for its ';').
TEST(ReaderLinearTime, VtiAttributeOfAmpersands) {
  expect_linear(".vti", [](std::size_t bytes) {
    return "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
           "<ImageData WholeExtent=\"0 1 0 1 0 1\" Origin=\"0 0 0\" Spacing=\"1 1 1\" Note=\"" +
           std::string(bytes, '&') +
           "\">\n<Piece Extent=\"0 1 0 1 0 1\"><PointData Scalars=\"s\">"
           "<DataArray type=\"Float32\" Name=\"s\" format=\"ascii\">0 1 2 3 4 5 6 7</DataArray>"
           "</PointData></Piece>\n</ImageData>\n</VTKFile>\n";
  });
}

// A NRRD header of unique unknown fields, `bytes` long (each field used to be
// compared with every field before it).
TEST(ReaderLinearTime, NrrdHeaderOfUniqueFields) {
  expect_linear(".nrrd", [](std::size_t bytes) {
    std::string text = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: raw\nendian: little\n";
    for (std::size_t k = 0; text.size() < bytes; ++k) text += "field" + std::to_string(k) + ": 1\n";
    return text + "\n" + std::string(8 * sizeof(float), '\0');
  });
}

}  // namespace
}  // namespace isowave
