// The isowave command as a new user meets it: raw files of any name, the
// value range and warnings on load, `info VOLUME`, output names checked,
// one exit-code rule, the decode note below the base mesh's share, the
// stats plot, and --help texts that fit a terminal.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_test_support.h"
#include "isowave/codec/isw_format.h"

namespace isowave {
namespace {

using cli_test::CliTest;
using cli_test::run;
using cli_test::RunResult;
using cli_test::write_sphere_nrrd;

constexpr int kN = 20;

// The distance field of a sphere of radius 6 samples on kN^3 samples, as
// float32 with the given byte order; the samples, for the test's own range.
std::vector<float> write_sphere_raw(const std::string& file, bool big_endian) {
  std::vector<float> samples;
  std::ofstream out(file, std::ios::binary);
  for (int k = 0; k < kN; ++k)
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) {
        const float v = static_cast<float>(6.0 - std::sqrt((i - 9.7) * (i - 9.7) + (j - 9.4) * (j - 9.4) + (k - 9.6) * (k - 9.6)));
        samples.push_back(v);
        unsigned char bytes[4];
        std::memcpy(bytes, &v, 4);
        if (big_endian) std::reverse(bytes, bytes + 4);
        out.write(reinterpret_cast<const char*>(bytes), 4);
      }
  return samples;
}

std::size_t count_lines(const std::string& text) { return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')); }

// "values LOW .. HIGH, N NaN, M Inf" from a command's output.
struct PrintedRange {
  double low = 0, high = 0;
  long nan = -1, inf = -1;
};
PrintedRange printed_range(const std::string& out) {
  PrintedRange r;
  std::smatch m;
  const std::regex pattern(R"(values (\S+) \.\. (\S+), (\d+) NaN, (\d+) Inf)");
  if (std::regex_search(out, m, pattern)) r = {std::stod(m[1]), std::stod(m[2]), std::stol(m[3]), std::stol(m[4])};
  return r;
}

// Raw samples in a file named .f32 (or .bin, .dat) are read given --dims and
// --type, and every command that loads a volume prints its value range: the
// range the test wrote. Read with the wrong byte order, the same file warns
// (NaN/Inf, values near the float limits or noise) on stderr.
TEST_F(CliTest, RawFilesOfAnyNameLoadAndAWrongEndianWarns) {
  const std::vector<float> samples = write_sphere_raw(path("sphere.f32"), false);
  const auto [low, high] = std::minmax_element(samples.begin(), samples.end());
  const std::string dims = std::to_string(kN) + "," + std::to_string(kN) + "," + std::to_string(kN);
  for (const char* name : {"sphere.f32", "sphere.bin", "sphere.dat"}) {
    if (std::string(name) != "sphere.f32") std::filesystem::copy_file(path("sphere.f32"), path(name));
    const RunResult r = run({"extract", path(name), "--dims", dims, "--type", "float32", "--iso", "0", "-o",
                             path(std::string(name) + ".ply")},
                            dir_);
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    const PrintedRange range = printed_range(r.out);
    EXPECT_FLOAT_EQ(range.low, *low) << r.out;
    EXPECT_FLOAT_EQ(range.high, *high) << r.out;
    EXPECT_EQ(range.nan, 0) << r.out;
    EXPECT_EQ(range.inf, 0) << r.out;
    EXPECT_EQ(r.err, "") << name;
  }
  const std::vector<std::string> reader = {"--dims", dims, "--type", "float32", "--endian", "big"};
  for (const std::vector<std::string>& command :
       {std::vector<std::string>{"extract", path("sphere.f32"), "--iso", "0", "-o", path("swapped.ply")},
        std::vector<std::string>{"convert", path("sphere.f32"), "--iso", "0", "--levels", "1", "-o", path("swapped.isw")},
        std::vector<std::string>{"info", path("sphere.f32")}}) {
    std::vector<std::string> arguments = command;
    arguments.insert(arguments.end(), reader.begin(), reader.end());
    const RunResult r = run(arguments, dir_);
    EXPECT_NE(r.err.find("warning: " + path("sphere.f32") + ":"), std::string::npos) << command[0] << ": " << r.err;
    EXPECT_NE(r.err.find("a wrong --endian or --type?"), std::string::npos) << command[0] << ": " << r.err;
  }
}

// info VOLUME: dims, type, the range the test wrote and a histogram whose
// counts add up to the samples, in the requested number of bins; and an
// .isw file with any name is still described as one (by its magic bytes).
TEST_F(CliTest, InfoDescribesAVolumeWithoutConvertingIt) {
  const std::vector<float> samples = write_sphere_raw(path("sphere.raw"), false);
  const auto [low, high] = std::minmax_element(samples.begin(), samples.end());
  const std::string dims = std::to_string(kN) + "," + std::to_string(kN) + "," + std::to_string(kN);
  const RunResult r = run({"info", path("sphere.raw"), "--dims", dims, "--type", "float32", "--bins", "8"}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("20 x 20 x 20 float32 samples"), std::string::npos) << r.out;
  const PrintedRange range = printed_range(r.out);
  EXPECT_FLOAT_EQ(range.low, *low) << r.out;
  EXPECT_FLOAT_EQ(range.high, *high) << r.out;
  // Histogram rows: "LOW .. HIGH COUNT ###".
  std::istringstream lines(r.out.substr(r.out.find("histogram")));
  std::string line;
  std::getline(lines, line);
  std::size_t total = 0, rows = 0;
  const double width = (*high - *low) / 8;
  std::vector<std::size_t> expected(8, 0);
  for (const float v : samples) ++expected[std::min<std::size_t>(7, static_cast<std::size_t>((v - *low) / width))];
  for (; std::getline(lines, line); ++rows) {
    std::istringstream fields(line);
    double from = 0, to = 0;
    std::string dots;
    std::size_t count = 0;
    fields >> from >> dots >> to >> count;
    ASSERT_EQ(dots, "..") << line;
    ASSERT_LT(rows, expected.size()) << r.out;
    // Samples within float rounding of a bin edge may fall either side.
    EXPECT_NEAR(double(count), double(expected[rows]), 2.0) << line;
    total += count;
  }
  EXPECT_EQ(rows, 8u) << r.out;
  EXPECT_EQ(total, samples.size()) << r.out;

  ASSERT_EQ(run({"convert", "builtin:sphere:24", "--levels", "1", "-o", path("s.isw"), "--quiet"}, dir_).exit_code, 0);
  std::filesystem::copy_file(path("s.isw"), path("renamed.dat"));
  const RunResult isw = run({"info", path("renamed.dat")}, dir_);
  ASSERT_EQ(isw.exit_code, 0) << isw.err;
  EXPECT_NE(isw.out.find("isowave .isw format"), std::string::npos) << isw.out;
}

// convert writes .isw and stats --plot writes SVG: another name is a usage
// error (one line, exit code 2) and nothing is written.
TEST_F(CliTest, OutputNamesMustMatchWhatIsWritten) {
  ASSERT_EQ(run({"convert", "builtin:sphere:24", "--levels", "1", "-o", path("s.isw"), "--quiet"}, dir_).exit_code, 0);
  const std::vector<std::vector<std::string>> cases = {
      {"convert", "builtin:sphere:24", "--levels", "1", "-o", path("out.ply")},
      {"stats", path("s.isw"), "--plot", path("plot.png")},
  };
  for (const auto& arguments : cases) {
    const RunResult r = run(arguments, dir_);
    EXPECT_EQ(r.exit_code, 2) << arguments[0] << ": " << r.err;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(path("out.ply")));
  EXPECT_FALSE(std::filesystem::exists(path("plot.png")));
}

// One rule for the exit code: 2 for usage errors, 1 for everything else. An
// isovalue outside the values gives an empty isosurface (exit 1, naming the
// range) in every command that extracts; a missing or unreadable file is 1.
TEST_F(CliTest, TheSameFailureGivesTheSameExitCodeInEveryCommand) {
  write_sphere_nrrd(path("s.nrrd"), 16, 5);
  ASSERT_EQ(run({"extract", path("s.nrrd"), "--iso", "0", "-o", path("base.ply"), "--quiet"}, dir_).exit_code, 0);
  std::ofstream(path("broken.nrrd")) << "NRRD0004\ntype: float\nsizes: 10 10\n";
  const auto with_input = [&](const std::string& input, const std::string& iso) {
    return std::vector<std::vector<std::string>>{
        {"extract", input, "--iso", iso, "-o", path("x.ply")},
        {"convert", input, "--iso", iso, "-o", path("x.isw")},
        {"fit", input, "--iso", iso, "--base", path("base.ply"), "--levels", "1", "-o", path("x.ply")},
    };
  };
  // The range of the samples write_sphere_nrrd wrote, as the error prints it.
  float low = HUGE_VALF, high = -HUGE_VALF;
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i) {
        const float v = static_cast<float>(5 - norm(Vec3{double(i), double(j), double(k)} - cli_test::sphere_centre(16)));
        low = std::min(low, v);
        high = std::max(high, v);
      }
  char range[64];
  std::snprintf(range, sizeof range, "%.9g .. %.9g)", double(low), double(high));
  for (const auto& arguments : with_input(path("s.nrrd"), "1000")) {
    const RunResult r = run(arguments, dir_);
    EXPECT_EQ(r.exit_code, 1) << arguments[0] << ": " << r.err;
    EXPECT_NE(r.err.find("the isosurface at 1000 is empty"), std::string::npos) << arguments[0] << ": " << r.err;
    EXPECT_NE(r.err.find(range), std::string::npos) << arguments[0] << " names the range " << range << ": " << r.err;
  }
  for (const std::string& input : {path("missing.nrrd"), path("broken.nrrd")}) {
    auto cases = with_input(input, "0");
    cases.push_back({"info", input});
    for (const auto& arguments : cases) {
      const RunResult r = run(arguments, dir_);
      EXPECT_EQ(r.exit_code, 1) << arguments[0] << " " << input << ": " << r.err;
    }
  }
  // A usage error about the one input (an unknown generated field, raw samples without --type): 2 everywhere.
  std::ofstream(path("samples.bin")) << std::string(64, '\0');
  for (const std::string& input : {std::string("builtin:nonsense"), path("samples.bin")}) {
    auto cases = with_input(input, "0");
    cases.push_back({"info", input});
    for (auto arguments : cases) {
      if (input == path("samples.bin")) arguments.insert(arguments.end(), {"--dims", "4,4,4"});
      const RunResult r = run(arguments, dir_);
      EXPECT_EQ(r.exit_code, 2) << arguments[0] << " " << input << ": " << r.err;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(path("x.ply")));
  EXPECT_FALSE(std::filesystem::exists(path("x.isw")));
}

// decode --percent below the base mesh's share writes the base mesh and says
// so, with the share computed here from the file's counts.
TEST_F(CliTest, DecodeSaysWhenAPercentageIsBelowTheBaseMesh) {
  ASSERT_EQ(run({"convert", "builtin:sphere:24", "--levels", "1", "-o", path("s.isw"), "--quiet"}, dir_).exit_code, 0);
  IswDecodeOptions headers;
  headers.headers_only = true;
  const IswDecoded decoded = read_isw(path("s.isw"), headers);
  const double share = 100.0 * double(decoded.base_vertices) / double(decoded.fine_vertices);
  ASSERT_GT(share, 1.0);
  char expected[128];
  std::snprintf(expected, sizeof expected, "1%% is below the base mesh's share (%.2f%% of the fine control points)", share);
  const RunResult below = run({"decode", path("s.isw"), "--percent", "1", "-o", path("b.ply")}, dir_);
  ASSERT_EQ(below.exit_code, 0) << below.err;
  EXPECT_NE(below.out.find(expected), std::string::npos) << below.out;
  const RunResult above = run({"decode", path("s.isw"), "--percent", "100", "-o", path("f.ply")}, dir_);
  ASSERT_EQ(above.exit_code, 0) << above.err;
  EXPECT_EQ(above.out.find("below the base mesh's share"), std::string::npos) << above.out;
}

// The SVG plot of a file without a rate table (RDTB): RMSE against percent,
// titled with the source's file name (not its directories); tick labels 0,
// s, 2s, ... with s from the 1-2-5 series; each point drawn once, and the
// base mesh labelled once.
TEST_F(CliTest, StatsPlotHasRoundTicksAndOneLabelledBasePoint) {
  std::filesystem::create_directories(path("a/long/directory"));
  write_sphere_nrrd(path("a/long/directory/ball.nrrd"), 24, 7);
  ASSERT_EQ(run({"convert", path("a/long/directory/ball.nrrd"), "--iso", "0", "--levels", "2", "-o", path("rd.isw"),
                 "--quiet"},
                dir_)
                .exit_code,
            0);
  std::ifstream in(path("rd.isw"), std::ios::binary);
  std::ofstream(path("b.isw"), std::ios::binary) << rewrite_isw({std::istreambuf_iterator<char>(in), {}}, IswRewrite{});
  ASSERT_EQ(run({"stats", path("b.isw"), "--plot", path("b.svg")}, dir_).exit_code, 0);
  std::ifstream file(path("b.svg"));
  const std::string svg((std::istreambuf_iterator<char>(file)), {});
  EXPECT_NE(svg.find(">RMSE against coefficients kept: ball.nrrd</text>"), std::string::npos) << svg;
  EXPECT_EQ(svg.find("directory"), std::string::npos);
  for (const char* axis : {"x-tick", "y-tick"}) {
    SCOPED_TRACE(axis);
    std::vector<double> ticks;
    const std::regex label(std::string("class=\"") + axis + "\"[^>]*>([^<]*)<");
    for (auto it = std::sregex_iterator(svg.begin(), svg.end(), label); it != std::sregex_iterator(); ++it)
      ticks.push_back(std::stod((*it)[1]));
    ASSERT_GE(ticks.size(), 3u) << svg;
    const double step = ticks[1] - ticks[0];
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step)));
    EXPECT_EQ(ticks[0], 0.0);
    EXPECT_TRUE(std::abs(mantissa - 1) < 1e-9 || std::abs(mantissa - 2) < 1e-9 || std::abs(mantissa - 5) < 1e-9) << step;
    for (std::size_t k = 0; k < ticks.size(); ++k) EXPECT_NEAR(ticks[k], k * step, 1e-9 * step) << k;
  }
  std::set<std::pair<std::string, std::string>> points;
  std::size_t circles = 0;
  const std::regex circle("<circle cx=\"([^\"]*)\" cy=\"([^\"]*)\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), circle); it != std::sregex_iterator(); ++it, ++circles)
    points.insert({(*it)[1], (*it)[2]});
  EXPECT_GE(circles, 3u);
  EXPECT_EQ(points.size(), circles) << "a point drawn twice";
  std::size_t labels = 0;
  for (std::size_t at = svg.find(">base mesh<"); at != std::string::npos; at = svg.find(">base mesh<", at + 1)) ++labels;
  EXPECT_EQ(labels, 1u);
}

// Every command's --help (and the overview) fits in 100 columns, and each
// command's gives an example.
TEST_F(CliTest, EveryHelpFitsIn100ColumnsAndGivesAnExample) {
  const RunResult overview = run({"--help"}, dir_);
  ASSERT_EQ(overview.exit_code, 0);
  std::vector<std::string> commands;
  std::istringstream lines(overview.out);
  bool in_list = false;
  for (std::string line; std::getline(lines, line);) {
    EXPECT_LE(line.size(), 100u) << line;
    if (line == "commands:") in_list = true;
    else if (line.empty()) in_list = false;
    else if (in_list) commands.push_back(line.substr(2, line.find(' ', 2) - 2));
  }
  ASSERT_EQ(commands.size(), 8u) << overview.out;
  for (const std::string& command : commands) {
    SCOPED_TRACE(command);
    const RunResult help = run({command, "--help"}, dir_);
    ASSERT_EQ(help.exit_code, 0) << help.err;
    EXPECT_NE(help.out.find("\nExample:\n  isowave " + command + " "), std::string::npos) << help.out;
    std::istringstream text(help.out);
    for (std::string line; std::getline(text, line);) EXPECT_LE(line.size(), 100u) << line;
  }
}


// A damaged or hostile file whose metadata says the cell is 0 wide: stats
// and its plots (RMSE against percent without an RDTB, D against bits per
// vertex with one) treat the cell size as unknown instead of dividing by it
// (the plot's ticks were computed from infinities and it read past an empty
// vector).
TEST_F(CliTest, StatsSurvivesAZeroCellSizeInTheMetadata) {
  write_sphere_nrrd(path("ball.nrrd"), 20, 6);
  ASSERT_EQ(run({"convert", path("ball.nrrd"), "--iso", "0", "--levels", "1", "-o", path("b.isw"), "--quiet"}, dir_)
                .exit_code,
            0);
  std::ifstream in(path("b.isw"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const IswDecoded decoded = decode_isw(bytes, "b.isw");
  ASSERT_FALSE(decoded.stream.rate_table.empty());
  IswMetadata metadata = decoded.metadata;
  ASSERT_GT(metadata.number("cell_size", 0), 0);
  metadata.values["cell_size"] = "0";
  for (const bool rate_table : {false, true}) {
    SCOPED_TRACE(rate_table ? "with an RDTB" : "without an RDTB");
    IswRewrite rewrite;
    rewrite.metadata = &metadata;
    if (rate_table) rewrite.rate_table = decoded.stream.rate_table;
    std::ofstream(path("zero.isw"), std::ios::binary | std::ios::trunc) << rewrite_isw(bytes, rewrite);

    const RunResult r = run({"stats", path("zero.isw"), "--plot", path("zero.svg"), "--force"}, dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_FALSE(std::regex_search(r.out, std::regex("\\b(-?nan|inf)\\b"))) << r.out;
    std::ifstream file(path("zero.svg"));
    const std::string svg((std::istreambuf_iterator<char>(file)), {});
    EXPECT_NE(svg.find("</svg>"), std::string::npos) << svg;
    EXPECT_NE(svg.find(rate_table ? ">D [world units x 100]<" : ">RMSE [world units x 100]<"), std::string::npos) << svg;
    EXPECT_EQ(svg.find("nan"), std::string::npos) << svg;
    EXPECT_EQ(svg.find("inf"), std::string::npos) << svg;
  }
}

}  // namespace
}  // namespace isowave
