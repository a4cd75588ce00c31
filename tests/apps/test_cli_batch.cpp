// convert's batch feedback: "k of N" with the batch's time left on each
// job's line, the totals at the end (inputs, jobs, failures, bytes in and
// out, their ratio) in the table and in --json, checked against the sizes of
// the files on disk; a failed job is one line and the others go on.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_test_support.h"
#include "isowave/core/vec3.h"

namespace isowave {
namespace {

using cli_test::CliTest;
using cli_test::run;
using cli_test::RunResult;
namespace fs = std::filesystem;

// Raw little-endian int16 samples, n^3, of 100 times a sphere's distance
// field (radius in samples): the file is the samples and nothing else.
void write_int16_sphere(const std::string& file, int n, double radius) {
  std::ofstream out(file, std::ios::binary);
  const Vec3 centre{n / 2.0 - 0.31, n / 2.0 - 0.17, n / 2.0 - 0.23};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const auto v = static_cast<std::int16_t>(std::lround(100 * (radius - norm(Vec3{double(i), double(j), double(k)} - centre))));
        const unsigned char bytes[2] = {static_cast<unsigned char>(v & 0xff), static_cast<unsigned char>((v >> 8) & 0xff)};
        out.write(reinterpret_cast<const char*>(bytes), 2);
      }
}

std::uintmax_t file_sizes(const std::vector<std::string>& files) {
  std::uintmax_t sum = 0;
  for (const std::string& f : files) sum += fs::file_size(f);
  return sum;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Two raw volumes and a missing one, each at two isovalues: six jobs. The
// missing input's two jobs fail with one line each and the others go on;
// the totals count three inputs, six jobs, two failures, each volume's bytes
// once however many isovalues (the raw files' sizes) and the four files
// written, in the table and in --json.
TEST_F(CliTest, BatchTotalsCountEachVolumeOnceAndTheFilesWritten) {
  write_int16_sphere(path("a.raw"), 18, 5);
  write_int16_sphere(path("b.raw"), 18, 6);
  const std::vector<std::string> common = {path("a.raw"), path("missing.raw"), path("b.raw"), "--dims", "18,18,18",
                                           "--type", "int16", "--iso", "0,50", "--levels", "1"};
  std::vector<std::string> table_run = {"convert", "--out-dir", path("table")};
  table_run.insert(table_run.end(), common.begin(), common.end());
  const RunResult r = run(table_run, dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;  // a missing file is not a usage error
  const std::vector<std::string> written = {path("table/a_iso0.isw"), path("table/a_iso50.isw"),
                                            path("table/b_iso0.isw"), path("table/b_iso50.isw")};
  for (const std::string& f : written) ASSERT_TRUE(fs::exists(f)) << f << "\n" << r.err;
  EXPECT_FALSE(fs::exists(path("table/missing_iso0.isw")));
  const std::vector<std::string> err = lines_of(r.err);
  ASSERT_EQ(err.size(), 6u) << r.err;  // one line per job, a failure's too
  for (int j : {2, 3}) {
    EXPECT_NE(err[std::size_t(j)].find("FAILED: "), std::string::npos) << err[std::size_t(j)];
    EXPECT_NE(err[std::size_t(j)].find("missing.raw"), std::string::npos) << err[std::size_t(j)];
  }

  const double in = double(file_sizes({path("a.raw"), path("b.raw")})) / 1e6;
  const double out = double(file_sizes(written)) / 1e6;
  char totals[160];
  std::snprintf(totals, sizeof totals, "\n3 inputs, 6 jobs, 2 failed; volumes %.3g MB in, %.3g MB out (%.1f : 1)", in,
                out, in / out);
  EXPECT_NE(r.out.find(totals), std::string::npos) << totals << "\n" << r.out;

  std::vector<std::string> json_run = {"convert", "--out-dir", path("json"), "--json"};
  json_run.insert(json_run.end(), common.begin(), common.end());
  const RunResult j = run(json_run, dir_);
  EXPECT_EQ(j.exit_code, 1) << j.err;
  EXPECT_EQ(lines_of(j.err).size(), 2u) << j.err;  // only the failures
  std::ofstream(path("result.json")) << j.out;
  ASSERT_EQ(std::system(("python3 -c 'import json,sys; d = json.load(open(sys.argv[1])); "
                         "print(d[\"inputs\"], d[\"jobs\"], d[\"converted\"], d[\"failed\"], d[\"volume_bytes\"], "
                         "d[\"bytes\"], round(d[\"ratio\"], 3))' '" +
                         path("result.json") + "' > '" + path("fields.txt") + "'")
                            .c_str()),
            0)
      << j.out;
  std::ifstream fields(path("fields.txt"));
  std::size_t inputs = 0, jobs = 0, converted = 0, failed = 0, volume_bytes = 0, bytes = 0;
  double ratio = 0;
  fields >> inputs >> jobs >> converted >> failed >> volume_bytes >> bytes >> ratio;
  EXPECT_EQ(inputs, 3u);
  EXPECT_EQ(jobs, 6u);
  EXPECT_EQ(converted, 4u);
  EXPECT_EQ(failed, 2u);
  EXPECT_EQ(volume_bytes, file_sizes({path("a.raw"), path("b.raw")}));
  EXPECT_EQ(bytes, file_sizes({path("json/a_iso0.isw"), path("json/a_iso50.isw"), path("json/b_iso0.isw"),
                               path("json/b_iso50.isw")}));
  EXPECT_NEAR(ratio, double(volume_bytes) / double(bytes), 1e-3);
}

// Each dataset and time step of one HDF5 or NetCDF file gets its own output
// name (the files here are missing, so the jobs fail, but their outputs are
// planned: two jobs writing one file would be refused before any runs).
TEST_F(CliTest, BatchNamesEachDatasetAndTimeStepApart) {
  const RunResult r = run({"convert", path("run.nc:rho@0"), path("run.nc:rho@1"), path("f.h5:/g/v"), "--iso", "0",
                           "--out-dir", path("out"), "--json"},
                          dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;  // missing files, not a usage error
  for (const char* name : {"run_rho_0.isw", "run_rho_1.isw", "f_g_v.isw"})
    EXPECT_NE(r.out.find(path(std::string("out/") + name)), std::string::npos) << name << "\n" << r.out;
}

// Every job's line after the first tells the batch's time left, before the
// job's stages; the estimate (the time per finished job times the jobs left)
// cannot exceed twice the whole run's time. Jobs side by side (--jobs 2)
// write their lines whole and tell it after the job: every line but the
// last job's to finish.
TEST_F(CliTest, BatchLinesTellTheTimeLeft) {
  for (const char* name : {"a.raw", "b.raw", "c.raw"}) write_int16_sphere(path(name), 18, 5);
  const std::vector<std::string> inputs = {path("a.raw"), path("b.raw"), path("c.raw"), "--dims", "18,18,18",
                                           "--type", "int16", "--iso", "0", "--levels", "1"};
  std::vector<std::string> serial = {"convert", "--out-dir", path("serial")};
  serial.insert(serial.end(), inputs.begin(), inputs.end());
  const auto start = std::chrono::steady_clock::now();
  const RunResult r = run(serial, dir_);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = lines_of(r.err);
  ASSERT_EQ(lines.size(), 3u) << r.err;
  EXPECT_EQ(lines[0].find(" left"), std::string::npos) << lines[0];
  const std::regex left_before("^\\[([23])/3\\] [abc] @0: about ([0-9]+) s left, load ");
  for (std::size_t k = 1; k < 3; ++k) {
    std::smatch match;
    ASSERT_TRUE(std::regex_search(lines[k], match, left_before)) << lines[k];
    EXPECT_EQ(std::stoul(match[1].str()), k + 1);
    EXPECT_LE(std::stod(match[2].str()), 2 * wall + 1) << lines[k];
  }

  std::vector<std::string> parallel = {"convert", "--out-dir", path("parallel"), "--jobs", "2"};
  parallel.insert(parallel.end(), inputs.begin(), inputs.end());
  const RunResult p = run(parallel, dir_);
  ASSERT_EQ(p.exit_code, 0) << p.err;
  const std::vector<std::string> whole = lines_of(p.err);
  ASSERT_EQ(whole.size(), 3u) << p.err;
  const std::regex left_after("\\.isw \\([0-9]+ bytes, [0-9.]+ s\\); about [0-9]+ s left$");
  EXPECT_EQ(std::count_if(whole.begin(), whole.end(), [&](const std::string& l) { return std::regex_search(l, left_after); }),
            2)
      << p.err;
  EXPECT_TRUE(std::regex_search(whole.back(), std::regex("\\.isw \\([0-9]+ bytes, [0-9.]+ s\\)$"))) << p.err;
}

}  // namespace
}  // namespace isowave
