#pragma once
// What the end-to-end tests of the isowave command share: running the built
// binary, a fixture with its own temporary directory, and test volumes.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "isowave/core/vec3.h"

namespace isowave::cli_test {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

// Runs isowave with arguments, capturing stdout and stderr.
inline RunResult run(const std::vector<std::string>& arguments, const fs::path& directory) {
  const fs::path out = directory / "stdout.txt", err = directory / "stderr.txt";
  std::string command = std::string(ISOWAVE_BINARY);
  for (const std::string& a : arguments) command += " '" + a + "'";
  command += " >'" + out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(command.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream o(out), e(err);
  r.out.assign(std::istreambuf_iterator<char>(o), {});
  r.err.assign(std::istreambuf_iterator<char>(e), {});
  return r;
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("isowave_cli_" + std::to_string(getpid()) + "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

// A small raw float NRRD volume of n^3 samples at `spacing`, value
// field(i, j, k) at sample (i, j, k), written by the test.
template <class Field>
void write_nrrd(const std::string& file, int n, double spacing, const Field& field) {
  std::ofstream out(file, std::ios::binary);
  out << "NRRD0004\ntype: float\ndimension: 3\nsizes: " << n << " " << n << " " << n
      << "\nencoding: raw\nendian: little\nspacings: " << spacing << " " << spacing << " " << spacing << "\n\n";
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const float v = static_cast<float>(field(double(i), double(j), double(k)));
        out.write(reinterpret_cast<const char*>(&v), 4);
      }
}

// The sphere of write_sphere_nrrd: its centre in sample units.
inline Vec3 sphere_centre(int n) { return {n / 2.0 - 0.31, n / 2.0 - 0.17, n / 2.0 - 0.23}; }

// A sphere's distance field (surface at 0, radius in samples), spacing 0.5.
inline void write_sphere_nrrd(const std::string& file, int n, double radius) {
  const Vec3 centre = sphere_centre(n);
  write_nrrd(file, n, 0.5, [&](double i, double j, double k) { return radius - norm(Vec3{i, j, k} - centre); });
}

}  // namespace isowave::cli_test
