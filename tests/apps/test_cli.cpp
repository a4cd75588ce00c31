// The isowave command end to end: convert -> decode/stats/info round trips,
// batches with a bad input, interrupted runs, and bad input giving one line
// and a non-zero exit code.
#include <algorithm>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "cli_test_support.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/vec3.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {
namespace {

using cli_test::CliTest;
using cli_test::run;
using cli_test::RunResult;
using cli_test::sphere_centre;
using cli_test::write_nrrd;
using cli_test::write_sphere_nrrd;
namespace fs = std::filesystem;

// Each undirected edge of a polygon mesh and how many faces use it.
std::map<std::pair<std::uint32_t, std::uint32_t>, int> edge_uses(const PolygonMesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (std::size_t f = 0; f < mesh.face_count(); ++f)
    for (std::uint32_t k = 0; k < mesh.face_size(f); ++k) {
      const std::uint32_t a = mesh.face_begin(f)[k], b = mesh.face_begin(f)[(k + 1) % mesh.face_size(f)];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  return uses;
}

TEST_F(CliTest, ConvertDecodeStatsAndInfoRoundTrip) {
  const RunResult convert = run({"convert", "builtin:genus3:64", "-o", path("g.isw"), "--quiet"}, dir_);
  ASSERT_EQ(convert.exit_code, 0) << convert.err;
  ASSERT_TRUE(fs::exists(path("g.isw")));
  const IswDecoded full = read_isw(path("g.isw"));
  EXPECT_FALSE(full.truncated);
  EXPECT_EQ(full.metadata.text("source"), "builtin:genus3:64");

  // decode at 100% writes the finest control mesh; at 0% the subdivided base.
  for (const char* percent : {"100", "20", "0"}) {
    const std::string out = path(std::string("d") + percent + ".ply");
    const RunResult decode = run({"decode", path("g.isw"), "--percent", percent, "-o", out, "--quiet"}, dir_);
    ASSERT_EQ(decode.exit_code, 0) << decode.err;
    const PolygonMesh mesh = read_mesh(out);
    ASSERT_EQ(mesh.vertex_count(), full.hierarchy->fine_vertex_count());
    IswDecodeOptions options;
    options.max_percent = std::atof(percent);
    const IswDecoded part = read_isw(path("g.isw"), options);
    const std::vector<Vec3> expected = reconstruct(part, part.ranked.size());
    // PLY stores float coordinates.
    EXPECT_LE(point_errors(mesh.positions, expected, expected.size()).max, 1e-4) << percent;
  }
  // Limit surface and triangulation.
  const RunResult limit =
      run({"decode", path("g.isw"), "--coefficients", "1000", "--limit", "--triangulate", "-o", path("l.obj")}, dir_);
  ASSERT_EQ(limit.exit_code, 0) << limit.err;
  const PolygonMesh triangles = read_mesh(path("l.obj"));
  for (std::size_t f = 0; f < triangles.face_count(); ++f) ASSERT_EQ(triangles.face_size(f), 3u);

  const RunResult stats = run({"stats", path("g.isw"), "--json", "--plot", path("plot.svg")}, dir_);
  ASSERT_EQ(stats.exit_code, 0) << stats.err;
  EXPECT_NE(stats.out.find("\"rmse_percent_cell\""), std::string::npos);
  EXPECT_NE(stats.out.find("\"base\": true"), std::string::npos);
  std::ifstream svg(path("plot.svg"));
  const std::string svg_text((std::istreambuf_iterator<char>(svg)), {});
  EXPECT_NE(svg_text.find("D [% of cell edge]"), std::string::npos);  // D against bits per vertex (RDTB)

  const RunResult info = run({"info", path("g.isw")}, dir_);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("PLNS"), std::string::npos);
}

TEST_F(CliTest, BatchSkipsAFailingInputAndExitsNonZero) {
  fs::create_directories(path("in"));
  write_sphere_nrrd(path("in/a.nrrd"), 24, 6);
  write_sphere_nrrd(path("in/b.nrrd"), 20, 5);
  std::ofstream(path("in/broken.nrrd")) << "NRRD0004\ntype: float\nsizes: 10 10\n";  // unreadable
  const RunResult r = run({"convert", path("in"), "--iso", "0", "--out-dir", path("out"), "--levels", "2"}, dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("broken.nrrd"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(path("out/a.isw")));
  EXPECT_TRUE(fs::exists(path("out/b.isw")));
  EXPECT_FALSE(fs::exists(path("out/broken.isw")));
  EXPECT_NE(r.out.find("FAILED"), std::string::npos);
  // The summary line lists each distinct reconstruction once, in decreasing
  // percent: the requested 5% lies below this base mesh's share and gives
  // the base mesh, which is listed only as the last entry.
  const std::size_t line_begin = r.out.find(path("out/a.isw"));
  ASSERT_NE(line_begin, std::string::npos) << r.out;
  std::istringstream line(r.out.substr(line_begin, r.out.find('\n', line_begin) - line_begin));
  std::vector<double> percents;
  for (std::string token; line >> token;)
    if (token.size() > 2 && token.compare(token.size() - 2, 2, "%:") == 0) percents.push_back(std::stod(token));
  ASSERT_GE(percents.size(), 2u) << r.out;
  EXPECT_EQ(percents.front(), 100.0);
  for (std::size_t k = 1; k < percents.size(); ++k) EXPECT_LT(percents[k], percents[k - 1]) << r.out;
  EXPECT_GT(percents.back(), 5.0) << "the base mesh of this sphere holds more than 5% of the fine points";
  // So does the stats table, naming the percentages the base mesh stands for.
  const RunResult stats = run({"stats", path("out/a.isw")}, dir_);
  ASSERT_EQ(stats.exit_code, 0) << stats.err;
  std::istringstream table(stats.out.substr(stats.out.find("coefficients")));
  std::vector<std::size_t> kept;
  for (std::string row; std::getline(table, row) && !row.empty();)  // Table 1 ends at a blank line
    if (row.find("coefficients") == std::string::npos) kept.push_back(std::stoul(row));
  ASSERT_EQ(kept.size(), percents.size()) << stats.out;
  for (std::size_t k = 1; k < kept.size(); ++k) EXPECT_LT(kept[k], kept[k - 1]) << stats.out;
  EXPECT_NE(stats.out.find("(base mesh, also for 5%"), std::string::npos) << stats.out;

  // Existing outputs are not overwritten without --force.
  const auto before = fs::last_write_time(path("out/a.isw"));
  const RunResult again = run({"convert", path("in/a.nrrd"), "--iso", "0", "--out-dir", path("out")}, dir_);
  EXPECT_NE(again.exit_code, 0);
  EXPECT_NE(again.err.find("already exists"), std::string::npos);
  EXPECT_EQ(fs::last_write_time(path("out/a.isw")), before);
  const RunResult forced = run({"convert", path("in/a.nrrd"), "--iso", "0", "--out-dir", path("out"), "--force", "--quiet"}, dir_);
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
}

// An empty directory and a pattern that matches nothing are failed inputs of
// the batch: the other inputs convert, the summary and --json name them, and
// the exit code is non-zero.
TEST_F(CliTest, BatchReportsEmptyDirectoriesAndPatternsMatchingNothing) {
  fs::create_directories(path("empty"));
  write_sphere_nrrd(path("a.nrrd"), 20, 5);
  const RunResult r = run({"convert", path("a.nrrd"), path("empty"), path("nothing*.nrrd"), "--iso", "0", "--out-dir",
                           path("out"), "--levels", "1", "--json"},
                          dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(fs::exists(path("out/a.isw")));
  EXPECT_NE(r.err.find("no volume files in this directory"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no file matches this pattern"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("\"converted\": 1, \"failed\": 2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"iso\": null"), std::string::npos) << r.out;
  // The JSON parses (scripts/setup installs python3 for this).
  std::ofstream(path("result.json")) << r.out;
  EXPECT_EQ(std::system(("python3 -m json.tool '" + path("result.json") + "' > /dev/null").c_str()), 0) << r.out;
}

// Signals at several stages, the last ones around the writing of the file:
// a stage's entry on the progress line (stderr, not a terminal) is read,
// then the signal sent. Whatever the run was doing, it leaves no .isw or a complete one, and
// no temporary file (after SIGKILL too, where the file system gives unnamed
// files: see AtomicFileWriter).
TEST_F(CliTest, AnInterruptedRunLeavesNoPartialOutput) {
  const int probe = open(dir_.c_str(), O_TMPFILE | O_WRONLY, 0600);
  const bool unnamed_files = probe >= 0 && access("/proc/self/fd", X_OK) == 0;
  if (probe >= 0) close(probe);
  const std::pair<int, const char*> cases[] = {{SIGTERM, ", normal fit "}, {SIGINT, ", encode "},
                                               {SIGKILL, ", analysis "},    {SIGKILL, ", encode "},
                                               {SIGKILL, ", evaluate "},    {SIGTERM, ", evaluate "}};
  for (const auto& [signal_number, stage] : cases) {
    SCOPED_TRACE(std::string(strsignal(signal_number)) + " after " + stage);
    int progress[2];
    ASSERT_EQ(pipe(progress), 0);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      dup2(progress[1], STDERR_FILENO);
      close(progress[0]);
      const std::string out = path("killed.isw");
      execl(ISOWAVE_BINARY, ISOWAVE_BINARY, "convert", "builtin:mixing:96", "-o", out.c_str(), "--force",
            static_cast<char*>(nullptr));
      _exit(127);
    }
    close(progress[1]);
    std::string seen;
    char buffer[256];
    for (ssize_t n; seen.find(stage) == std::string::npos && (n = read(progress[0], buffer, sizeof buffer)) > 0;)
      seen.append(buffer, static_cast<std::size_t>(n));
    ASSERT_NE(seen.find(stage), std::string::npos) << seen;
    kill(child, signal_number);
    close(progress[0]);
    int status = 0;
    waitpid(child, &status, 0);
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (entry.path().extension() == ".isw") {
        EXPECT_NO_THROW(read_isw(entry.path().string())) << "partial " << name;
      }
      if (signal_number != SIGKILL || unnamed_files) {
        EXPECT_EQ(name.find(".tmp-"), std::string::npos) << "left " << name;
      }
    }
    for (const auto& entry : fs::directory_iterator(dir_)) fs::remove(entry.path());
  }
}

// extract -> simplify -> fit on a sphere, with a base of 1/64 of the
// extracted vertices: the fine control mesh is a closed all-quad mesh
// (Euler: V = F + 2), every fine vertex lies on the sphere to within the
// trilinear interpolant's error (at most h^2 / 8 times the distance field's
// second derivative, 1 / R, along each of the 3 axes: 0.047 cell), and the
// report covers every level. The base simplified as far as it goes (a
// tetrahedron) is far too coarse for 3 levels, and the fit says so.
TEST_F(CliTest, FitWritesAClosedQuadMeshOnTheSphere) {
  const int n = 24;
  const double radius = 8;
  write_sphere_nrrd(path("s.nrrd"), n, radius);
  ASSERT_EQ(run({"extract", path("s.nrrd"), "--iso", "0", "-o", path("s.ply"), "--quiet"}, dir_).exit_code, 0);
  const std::size_t extracted = read_mesh(path("s.ply")).vertex_count();
  for (const std::size_t target : {extracted / 64, std::size_t{0}}) {
    SCOPED_TRACE("base of " + std::to_string(target) + " vertices");
    const RunResult simplify = run({"simplify", path("s.ply"), "--target-vertices", std::to_string(target), "-o",
                                    path("base.ply"), "--quiet", "--force"},
                                   dir_);
    ASSERT_EQ(simplify.exit_code, 0) << simplify.err;
    const RunResult fit = run(
        {"fit", path("s.nrrd"), "--iso", "0", "--base", path("base.ply"), "--levels", "3", "-o", path("fine.ply"), "--force"},
        dir_);
    ASSERT_EQ(fit.exit_code, 0) << fit.err;
    for (const char* line : {"quality:", "the extracted triangles themselves lie", "  level 0:", "  level 3:",
                             "folded faces:", "to the extracted mesh:"})
      EXPECT_NE(fit.out.find(line), std::string::npos) << line << " missing from:\n" << fit.out;
    const PolygonMesh fine = read_mesh(path("fine.ply"));
    EXPECT_EQ(fine.vertex_count(), fine.face_count() + 2);
    for (std::size_t f = 0; f < fine.face_count(); ++f) ASSERT_EQ(fine.face_size(f), 4u) << "face " << f;
    for (const auto& [edge, uses] : edge_uses(fine)) ASSERT_EQ(uses, 2) << edge.first << "-" << edge.second;
    // A base of 1/64 of the extracted vertices gives about as many fine ones
    // at 3 levels; the tetrahedron gives 194.
    const bool coarse = 2 * fine.vertex_count() < extracted;
    EXPECT_EQ(coarse, target == 0) << fine.vertex_count() << " fine vertices for " << extracted;
    EXPECT_EQ(fit.out.find("too coarse") != std::string::npos, coarse) << fit.out;
    if (coarse) continue;
    const Vec3 centre = sphere_centre(n);
    double worst = 0;
    for (const Vec3& p : fine.positions) worst = std::max(worst, std::abs(norm(2.0 * p - centre) - radius));
    EXPECT_LE(worst, 3.0 / (8.0 * radius)) << "cells off the sphere";
  }
}

// A tilted plane through the box: its boundary loop lies on the box's side
// faces, and the four vertices where it turns a box edge are sharp. In the
// fine mesh the base's sharp vertices keep their flag and their place, every
// boundary vertex stays on a side face, and every vertex lies on the plane
// (trilinear interpolation of a linear field is exact).
TEST_F(CliTest, FitKeepsSharpVerticesAndTheBoundaryOnTheBox) {
  const int n = 20;
  const auto plane = [](double x, double y, double z) { return (z - 9.6) - 0.2 * (x - 9.5) - 0.1 * (y - 9.5); };
  write_nrrd(path("p.nrrd"), n, 1.0, plane);
  ASSERT_EQ(run({"extract", path("p.nrrd"), "--iso", "0", "-o", path("p.ply"), "--quiet"}, dir_).exit_code, 0);
  ASSERT_EQ(run({"simplify", path("p.ply"), "--target-vertices", "0", "-o", path("base.ply"), "--quiet"}, dir_).exit_code, 0);
  const RunResult fit = run({"fit", path("p.nrrd"), "--iso", "0", "--base", path("base.ply"), "--levels", "2", "-o",
                             path("fine.ply"), "--quiet"},
                            dir_);
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  EXPECT_TRUE(fit.out.empty()) << fit.out;

  const PolygonMesh base = read_mesh(path("base.ply"));
  const PolygonMesh fine = read_mesh(path("fine.ply"));
  ASSERT_EQ(base.sharp_count(), 4u);
  ASSERT_EQ(fine.sharp.size(), fine.vertex_count());
  EXPECT_EQ(fine.sharp_count(), 4u);
  for (std::size_t v = 0; v < base.vertex_count(); ++v)
    if (base.is_sharp(v)) {
      EXPECT_TRUE(fine.is_sharp(v)) << v;
      EXPECT_EQ(fine.positions[v], base.positions[v]) << v;
    }
  for (const Vec3& p : fine.positions) ASSERT_LE(std::abs(plane(p.x, p.y, p.z)), 1e-4);
  std::size_t boundary_edges = 0;
  for (const auto& [edge, uses] : edge_uses(fine)) {
    if (uses != 1) continue;
    ++boundary_edges;
    for (const std::uint32_t v : {edge.first, edge.second}) {
      const Vec3& p = fine.positions[v];
      EXPECT_LE(std::min({std::abs(p.x), std::abs(p.x - (n - 1)), std::abs(p.y), std::abs(p.y - (n - 1))}), 1e-5) << v;
    }
  }
  EXPECT_GT(boundary_edges, 0u);
}

// Bad fit input: one line, a non-zero exit code and no output file.
TEST_F(CliTest, FitRejectsBadInputWithOneLine) {
  write_sphere_nrrd(path("s.nrrd"), 16, 5);
  ASSERT_EQ(run({"extract", path("s.nrrd"), "--iso", "0", "-o", path("s.ply"), "--quiet"}, dir_).exit_code, 0);
  ASSERT_EQ(run({"extract", path("s.nrrd"), "--iso", "0", "--flip", "-o", path("flipped.ply"), "--quiet"}, dir_).exit_code, 0);
  std::ofstream(path("garbage.ply")) << "ply\nformat ascii 1.0\nelement vertex 99\n";
  std::ofstream(path("nan.ply")) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                     "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                     "end_header\n1 1 1\nnan 2 1\n1 2 2\n3 0 1 2\n";
  std::ofstream(path("far.ply")) << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                     "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                                     "end_header\n100 100 100\n105 100 100\n100 105 100\n100 100 105\n"
                                     "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n";
  const std::string out = path("x.ply");
  const std::vector<std::vector<std::string>> cases = {
      {"fit", path("s.nrrd"), "--iso", "0", "--levels", "1", "-o", out},                                 // no base
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("s.ply"), "-o", out},                         // no levels
      {"fit", path("s.nrrd"), "--base", path("s.ply"), "--levels", "1", "-o", out},                      // no iso
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("s.ply"), "--levels", "9", "-o", out},        // too deep
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("garbage.ply"), "--levels", "1", "-o", out},  // truncated
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("nan.ply"), "--levels", "1", "-o", out},      // NaN
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("far.ply"), "--levels", "1", "-o", out},      // elsewhere
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("flipped.ply"), "--levels", "1", "-o", out},  // --flip
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("missing.ply"), "--levels", "1", "-o", out},
      {"fit", path("missing.nrrd"), "--iso", "0", "--base", path("s.ply"), "--levels", "1", "-o", out},
      {"fit", path("s.nrrd"), "--iso", "1000", "--base", path("s.ply"), "--levels", "1", "-o", out},     // empty
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("s.ply"), "--levels", "1", "--band", "-1", "-o", out},
      {"fit", path("s.nrrd"), "--iso", "0", "--base", path("s.ply"), "--levels", "1", "-o", path("x.xyz")},
  };
  for (const auto& arguments : cases) {
    const RunResult r = run(arguments, dir_);
    std::string command;
    for (const std::string& a : arguments) command += a + " ";
    EXPECT_GT(r.exit_code, 0) << command;
    EXPECT_LT(r.exit_code, 128) << command << "crashed";
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << command << ": " << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(path("x.xyz")));
}

// Every command that writes refuses an existing file without --force (the
// user's file, or the command's own input, stays as it was), and checks its
// outputs before the work.
TEST_F(CliTest, ExistingFilesAreKeptWithoutForce) {
  ASSERT_EQ(run({"convert", "builtin:sphere:24", "-o", path("s.isw"), "--levels", "1", "--quiet"}, dir_).exit_code, 0);
  std::ofstream(path("mine.ply")) << "the user's file";
  const auto contents = [&](const std::string& name) {
    std::ifstream in(path(name), std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string isw = contents("s.isw");
  const std::vector<std::vector<std::string>> refused = {
      {"decode", path("s.isw"), "--percent", "50", "-o", path("mine.ply")},
      {"stats", path("s.isw"), "--plot", path("s.isw")},
      {"extract", "builtin:sphere:24", "-o", path("mine.ply")},
      {"extract", "builtin:sphere:24", "-o", path("new.ply"), "--stats-json", path("new.ply")},
      {"fit", "builtin:sphere:24", "--base", path("any.ply"), "--levels", "1", "-o", path("mine.ply")},
      {"decode", path("s.isw"), "--percent", "50", "-o", path("missing_directory/out.ply")},
  };
  for (const auto& arguments : refused) {
    const RunResult r = run(arguments, dir_);
    EXPECT_NE(r.exit_code, 0) << arguments[0] << ": " << r.out;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_EQ(contents("mine.ply"), "the user's file");
  EXPECT_EQ(contents("s.isw"), isw);
  EXPECT_FALSE(fs::exists(path("new.ply")));
  const RunResult forced = run({"decode", path("s.isw"), "--percent", "50", "-o", path("mine.ply"), "--force", "--quiet"}, dir_);
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_NO_THROW(read_mesh(path("mine.ply")));
}

// decode --view: a camera file refines what it sees; a bad camera is one line
// and no output.
TEST_F(CliTest, DecodeViewRefinesWhatTheCameraSeesAndRefusesBadCameras) {
  ASSERT_EQ(run({"convert", "builtin:sphere:24", "-o", path("s.isw"), "--levels", "2", "--quiet"}, dir_).exit_code, 0);
  std::ofstream(path("cam.json")) << R"({"position":[12,12,-30],"target":[12,12,12],"up":[0,1,0],"fov":30,)"
                                  << R"("viewport":[1920,1080]})";
  const RunResult r = run({"decode", path("s.isw"), "--view", path("cam.json"), "--pixel-error", "0.5", "-o",
                           path("view.ply"), "--triangulate"},
                          dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("view at 0.5 pixels"), std::string::npos) << r.out;
  EXPECT_GT(read_mesh(path("view.ply")).face_count(), 0u);
  std::ofstream(path("bad.json")) << R"({"position":[0,0,0],"target":[0,0,0],"up":[0,1,0],"fov":30,"viewport":[9,9]})";
  for (const std::string& camera : {path("bad.json"), path("missing.json")}) {
    const RunResult bad = run({"decode", path("s.isw"), "--view", camera, "-o", path("bad.ply")}, dir_);
    EXPECT_NE(bad.exit_code, 0);
    EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
    EXPECT_FALSE(fs::exists(path("bad.ply")));
  }
}

TEST_F(CliTest, BadInputGivesOneLineAndANonZeroExitCode) {
  std::ofstream(path("garbage.isw")) << "not an isw file";
  std::ofstream(path("garbage.ply")) << "ply\nformat ascii 1.0\nelement vertex 99\n";
  const std::vector<std::vector<std::string>> cases = {
      {"decode", path("garbage.isw"), "--percent", "5", "-o", path("x.ply")},
      {"decode", path("missing.isw"), "--percent", "5", "-o", path("x.ply")},
      {"decode", path("garbage.isw"), "-o", path("x.ply")},
      {"decode", path("missing.isw"), "--roi", "1,2,3", "-o", path("x.ply")},
      {"decode", path("missing.isw"), "--roi-sphere", "1,2,3,0", "-o", path("x.ply")},
      {"decode", path("missing.isw"), "--pixel-error", "1", "-o", path("x.ply")},
      {"decode", path("missing.isw"), "--cull-back-faces", "-o", path("x.ply")},
      {"decode", path("missing.isw"), "--percent", "5", "--oracle", "best", "-o", path("x.ply")},
      {"decode", path("missing.isw"), "--oracle", "greedy", "-o", path("x.ply")},  // nothing to choose
      {"decode", path("missing.isw"), "--view", path("missing.json"), "--roi", "0,0,0,1,1,1", "-o", path("x.ply")},
      {"stats", path("garbage.isw")},
      {"info", path("garbage.isw")},
      {"subdivide", path("garbage.ply"), "--levels", "2", "-o", path("x.ply")},
      {"convert", "builtin:nonsense", "-o", path("x.isw")},
      {"convert", "builtin:sphere:32", "--levels", "9", "-o", path("x.isw")},
      {"convert", "builtin:sphere:32", "--unfold-limit", "2", "-o", path("x.isw")},  // the fit command's, not convert's
      {"fit", "builtin:sphere:32", "--base", path("garbage.ply"), "--levels", "2", "--unfold-limit", "101", "-o",
       path("x.ply")},
      {"convert", "builtin:sphere:32", "--topology-tolerance", "-1", "-o", path("x.isw")},
      {"extract", "builtin:sphere:32", "--topology-tolerance", "nan", "-o", path("x.ply")},
      {"extract", "builtin:sphere:32", "--topology-tolerance", "abc", "-o", path("x.ply")},
      {"extract", "builtin:sphere:16", "--topology-tolerance", "20", "-o", path("x.ply")},  // removes everything
      {"convert", "builtin:sphere:32", "builtin:sphere:32", "--out-dir", path("x")},  // both would write x/sphere_32.isw
      {"decode", path("garbage.isw"), "--percent", "-o", path("x.ply")},              // -o is no percentage
      {"info", dir_.string()},                                                         // a directory
      {"nonsense"},
  };
  for (const auto& arguments : cases) {
    const RunResult r = run(arguments, dir_);
    EXPECT_NE(r.exit_code, 0) << arguments[0];
    EXPECT_GT(r.exit_code, 0) << arguments[0] << " crashed";
    EXPECT_LT(r.exit_code, 128) << arguments[0] << " crashed";
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << arguments[0] << ": " << r.err;
  }
  EXPECT_FALSE(fs::exists(path("x.ply")));
  EXPECT_FALSE(fs::exists(path("x.isw")));
  EXPECT_FALSE(fs::exists(path("x")));
}

// Without a terminal a batch prints one line per input, "k of N" in it, the
// batch's time left from the second on, the stages and their seconds, then
// what it wrote or why it failed; a failed
// input's error appears once (before, it came again in the summary table,
// and every stage had a "done in" line of its own). The summary ends with the
// totals.
TEST_F(CliTest, BatchPrintsOneLinePerInputAnErrorOnceAndTotals) {
  fs::create_directories(path("in"));
  write_sphere_nrrd(path("in/a.nrrd"), 20, 5);
  write_sphere_nrrd(path("in/b.nrrd"), 16, 4);
  std::ofstream(path("in/broken.nrrd")) << "NRRD0004\ntype: float\nsizes: 10 10\n";  // unreadable
  const RunResult r = run({"convert", path("in"), "--iso", "0", "--out-dir", path("out"), "--levels", "1"}, dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 3) << r.err;
  EXPECT_EQ(r.err.find("done in"), std::string::npos) << r.err;
  std::istringstream lines(r.err);
  std::string line;
  for (const char* expected : {"[1/3] a @0: load ", "[2/3] b @0: about ", "[3/3] broken @0: about "}) {
    ASSERT_TRUE(std::getline(lines, line)) << r.err;
    EXPECT_EQ(line.rfind(expected, 0), 0u) << line;
    // The value range loaded is part of the input's line, not a line of its own.
    if (line.find("FAILED") == std::string::npos) {
      EXPECT_NE(line.find(" s, values "), std::string::npos) << line;
    }
  }
  EXPECT_EQ(r.out.find("values "), std::string::npos) << r.out;
  const std::string error = "broken.nrrd: ";
  const std::string all = r.out + r.err;
  const std::size_t first = all.find(error);
  ASSERT_NE(first, std::string::npos) << all;
  EXPECT_EQ(all.find(error, first + 1), std::string::npos) << "error repeated: " << all;
  // Totals: 3 inputs, 1 failed, the two volumes' float samples in, the two files out.
  const double in = 4.0 * (20 * 20 * 20 + 16 * 16 * 16) / 1e6;
  const double out = double(fs::file_size(path("out/a.isw")) + fs::file_size(path("out/b.isw"))) / 1e6;
  char totals[128];
  std::snprintf(totals, sizeof totals, "3 inputs, 1 failed; volumes %.3g MB in, %.3g MB out (%.1f : 1)", in, out,
                in / out);
  EXPECT_NE(r.out.find(totals), std::string::npos) << totals << "\n" << r.out;
}

// Six levels of the mixing layer's whole isosurface (a base mesh as large
// as the 70,880 extracted vertices) make at least 290 M fine points, about
// 87 GB at 300 bytes each, more than a test machine has: one line naming
// the levels, at once, where a bare std::bad_alloc came after the base mesh
// had been made.
TEST_F(CliTest, ConvertRefusesAFineMeshLargerThanMemoryWithOneLine) {
  const RunResult r = run(
      {"convert", "builtin:mixing", "--levels", "6", "--base-vertices", "1000000", "-o", path("x.isw")}, dir_);
  EXPECT_EQ(r.exit_code, 2);  // a usage error, as fit and subdivide report --levels beyond memory
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("6 levels"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("more than this machine's"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("alloc"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("x.isw")));
}

// The torus from 9 base vertices at 3 levels folds over half its fine faces:
// the file would be a crumpled sheet. convert says so as a failure, with the
// remedy, writes nothing and exits non-zero; --allow-folded writes it, with
// the warning, the share in fixed notation.
TEST_F(CliTest, ConvertRefusesAFitThatMostlyFolds) {
  const std::vector<std::string> arguments = {"convert", "builtin:torus:160", "--base-vertices", "9", "--levels",
                                              "3", "-o", path("x.isw")};
  const RunResult refused = run(arguments, dir_);
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("unusable"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("a larger base mesh"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(path("x.isw")));
  std::vector<std::string> allowed = arguments;
  allowed.push_back("--allow-folded");
  const RunResult written = run(allowed, dir_);
  EXPECT_EQ(written.exit_code, 0) << written.err;
  EXPECT_TRUE(fs::exists(path("x.isw")));
  const std::size_t fold = written.err.find("% of the fine faces fold");
  ASSERT_NE(fold, std::string::npos) << written.err;
  const std::size_t begin = written.err.rfind(' ', fold) + 1;
  const std::string share = written.err.substr(begin, fold - begin);  // e.g. 57.12
  EXPECT_GT(std::stod(share), 50.0) << share;
  EXPECT_EQ(share.find('e'), std::string::npos) << share;
  EXPECT_EQ(share.size() - share.find('.'), 3u) << share;
}

// A missing input names its real cause (not its file name's ending), with
// the path said once.
TEST_F(CliTest, AMissingInputSaysSoOnce) {
  const std::string missing = path("no_such_volume");
  const RunResult r = run({"convert", missing, "--iso", "0", "-o", path("x.isw")}, dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot open: No such file or directory"), std::string::npos) << r.err;
  const std::size_t first = r.err.find(missing);
  ASSERT_NE(first, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(missing, first + missing.size()), std::string::npos) << "path repeated: " << r.err;
  EXPECT_FALSE(fs::exists(path("x.isw")));
}

TEST_F(CliTest, VersionPrintsTheProjectVersion) {
  const RunResult r = run({"--version"}, dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, std::string("isowave ") + ISOWAVE_VERSION + "\n");
}

}  // namespace
}  // namespace isowave
