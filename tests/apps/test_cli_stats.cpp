// isowave stats on the embedded stream of a version 2 file (issue #34): the
// table of D at prefixes of the stream (RDTB) in text and JSON, its plot, and
// the one-line note for a file without one (version 1, or no RDTB).
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli_test_support.h"
#include "isowave/codec/isw_format.h"

namespace isowave {
namespace {

using namespace cli_test;  // CliTest, run, RunResult, write_sphere_nrrd, fs

// One row of stats --json's "stream" array.
struct JsonStreamRow {
  std::uint64_t bytes = 0, stream_bytes = 0;
  double bits_per_isosurface_vertex = 0, bits_per_fine_vertex = 0, d_percent_cell = 0;
  int planes = 0;
};

// stats --json's "stream" array, read by Python's json module.
std::vector<JsonStreamRow> json_stream_rows(const std::string& json, const std::string& scratch) {
  std::ofstream(scratch + ".json") << json;
  const std::string command =
      "python3 -c 'import json,sys\nfor r in json.load(open(sys.argv[1]))[\"stream\"]: print(r[\"bytes\"], "
      "r[\"stream_bytes\"], r[\"bits_per_isosurface_vertex\"], r[\"bits_per_fine_vertex\"], r[\"d_percent_cell\"], "
      "r[\"planes\"])' '" +
      scratch + ".json' > '" + scratch + ".txt'";
  EXPECT_EQ(std::system(command.c_str()), 0) << json;
  std::ifstream fields(scratch + ".txt");
  std::vector<JsonStreamRow> rows;
  JsonStreamRow r;
  while (fields >> r.bytes >> r.stream_bytes >> r.bits_per_isosurface_vertex >> r.bits_per_fine_vertex >>
         r.d_percent_cell >> r.planes)
    rows.push_back(r);
  return rows;
}

std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class StatsStreamTest : public CliTest {
 protected:
  // A sphere converted with the defaults (a version 2 file with an RDTB) and `more` options.
  std::string convert_sphere(const std::string& name, const std::vector<std::string>& more = {}) {
    if (!fs::exists(path("ball.nrrd"))) write_sphere_nrrd(path("ball.nrrd"), 24, 7);
    std::vector<std::string> arguments = {"convert", path("ball.nrrd"), "--iso", "0", "--levels", "2",
                                          "-o",      path(name),        "--quiet"};
    arguments.insert(arguments.end(), more.begin(), more.end());
    const RunResult r = run(arguments, dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return path(name);
  }
};

// The rows: a reader's file bytes ascending and within the file, D not
// growing with them, bits per vertex 8 x bytes / the isosurface's vertices,
// and the stream bytes and complete planes a decode of that many file bytes
// reads; for the whole stream and for one convert --size cut inside its last
// plane (whose statistics were refused as an incomplete decode).
TEST_F(StatsStreamTest, StatsTabulatesDAtPrefixesOfTheEmbeddedStream) {
  const IswStreamInfo whole = read_isw(convert_sphere("whole.isw")).stream;
  ASSERT_GE(whole.plane_ends.size(), 2u);
  const std::uint64_t last_plane = whole.plane_ends.back() - whole.plane_ends[whole.plane_ends.size() - 2];
  const std::string size = std::to_string(fs::file_size(path("whole.isw")) - last_plane / 2);
  const std::string cut_file = convert_sphere("cut.isw", {"--size", size});

  for (const std::string& file : {path("whole.isw"), cut_file}) {
    SCOPED_TRACE(file);
    const IswDecoded decoded = read_isw(file);
    ASSERT_EQ(decoded.major_version, 2);
    ASSERT_GE(decoded.stream.rate_table.size(), 2u);
    const double extracted = decoded.metadata.number("extracted_vertices", 0);
    const double fine = static_cast<double>(decoded.hierarchy->fine_vertex_count());
    ASSERT_GT(extracted, 0);

    const RunResult json = run({"stats", file, "--json"}, dir_);
    ASSERT_EQ(json.exit_code, 0) << json.err;
    const std::vector<JsonStreamRow> rows = json_stream_rows(json.out, path("stream"));
    ASSERT_EQ(rows.size(), decoded.stream.rate_table.size()) << json.out;
    const std::string bytes = file_text(file);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      SCOPED_TRACE(i);
      const JsonStreamRow& r = rows[i];
      if (i > 0) {
        EXPECT_GT(r.bytes, rows[i - 1].bytes);
        EXPECT_LE(r.d_percent_cell, rows[i - 1].d_percent_cell);
      }
      EXPECT_LE(r.bytes, fs::file_size(file));
      EXPECT_GT(r.d_percent_cell, 0);
      // Printed with 6 significant digits.
      EXPECT_NEAR(r.bits_per_isosurface_vertex, 8.0 * double(r.bytes) / extracted, 5e-6 * r.bits_per_isosurface_vertex);
      EXPECT_NEAR(r.bits_per_fine_vertex, 8.0 * double(r.bytes) / fine, 5e-6 * r.bits_per_fine_vertex);
      IswDecodeOptions prefix;
      prefix.max_file_bytes = r.bytes;
      const IswDecoded cut = decode_isw(bytes, file, prefix);
      EXPECT_EQ(cut.stream.decoded, r.stream_bytes);
      EXPECT_EQ(cut.stream.planes_decoded, r.planes);
    }
    const bool cut_by_encoder = file == cut_file;
    EXPECT_EQ(rows.back().planes, decoded.stream.planes - (cut_by_encoder ? 1 : 0));

    // The text: Table 1, then one line per row under the stream table's heading.
    const RunResult text = run({"stats", file}, dir_);
    ASSERT_EQ(text.exit_code, 0) << text.err;
    const std::size_t heading = text.out.find("embedded stream: D against the isosurface at prefixes");
    ASSERT_NE(heading, std::string::npos) << text.out;
    EXPECT_LT(text.out.find("(base mesh"), heading) << text.out;
    std::istringstream lines(text.out.substr(heading));
    std::string line;
    std::getline(lines, line);
    std::getline(lines, line);  // column names
    std::vector<std::uint64_t> printed;
    while (std::getline(lines, line)) printed.push_back(std::stoull(line));
    ASSERT_EQ(printed.size(), rows.size()) << text.out;
    for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(printed[i], rows[i].bytes) << text.out;
  }
}

// The plot of a file with an RDTB: D against bits per isosurface vertex,
// one point per row, the base mesh (row 0) and the whole stream labelled.
TEST_F(StatsStreamTest, StatsPlotDrawsDAgainstBitsPerIsosurfaceVertex) {
  const std::string file = convert_sphere("b.isw");
  const std::size_t rows = read_isw(file).stream.rate_table.size();
  ASSERT_GE(rows, 2u);
  const RunResult r = run({"stats", file, "--plot", path("rd.svg")}, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string svg = file_text(path("rd.svg"));
  EXPECT_NE(svg.find(">bits per isosurface vertex</text>"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">D [% of cell edge]</text>"), std::string::npos) << svg;
  EXPECT_EQ(occurrences(svg, "<circle "), rows) << svg;
  EXPECT_EQ(occurrences(svg, ">whole stream</text>"), 1u) << svg;
  EXPECT_EQ(occurrences(svg, ">base mesh</text>"), 1u) << svg;
}

// A version 1 file (chunks) and a version 2 file without an RDTB: Table 1,
// then one line saying there is no stream table; "stream": [] in JSON; the
// plot is RMSE against percent.
TEST_F(StatsStreamTest, StatsOfAFileWithoutARateTableSaysSoInOneLine) {
  const std::string file = convert_sphere("b.isw");
  const std::string v2 = file_text(file);
  const IswDecoded decoded = decode_isw(v2, "b.isw");
  IswEncodeOptions v1;
  v1.major_version = 1;
  v1.step = decoded.step;
  v1.class_weights = decoded.class_weights;
  std::ofstream(path("v1.isw"), std::ios::binary) << encode_isw(*decoded.hierarchy, decoded.coefficients, decoded.metadata, v1);
  std::ofstream(path("plain.isw"), std::ios::binary) << rewrite_isw(v2, IswRewrite{});
  ASSERT_EQ(read_isw(path("v1.isw")).major_version, 1);
  ASSERT_TRUE(read_isw(path("plain.isw")).stream.rate_table.empty());

  for (const char* name : {"v1.isw", "plain.isw"}) {
    SCOPED_TRACE(name);
    const RunResult text = run({"stats", path(name)}, dir_);
    ASSERT_EQ(text.exit_code, 0) << text.err;
    const std::size_t base = text.out.find("(base mesh");
    ASSERT_NE(base, std::string::npos) << text.out;
    EXPECT_EQ(occurrences(text.out, "embedded stream: "), 1u) << text.out;
    const std::string after_table1 = text.out.substr(text.out.find('\n', base) + 1);
    EXPECT_EQ(occurrences(after_table1, "\n"), 2u) << "a blank line and the note:\n" << text.out;
    EXPECT_EQ(after_table1.find("D [% cell]"), std::string::npos) << text.out;

    const RunResult json = run({"stats", path(name), "--json"}, dir_);
    ASSERT_EQ(json.exit_code, 0) << json.err;
    EXPECT_NE(json.out.find("\"stream\": []"), std::string::npos) << json.out;
    EXPECT_NE(json.out.find("\"rmse_percent_cell\""), std::string::npos) << json.out;

    const std::string plot = path(std::string(name) + ".svg");
    ASSERT_EQ(run({"stats", path(name), "--plot", plot}, dir_).exit_code, 0);
    EXPECT_NE(file_text(plot).find(">RMSE [% of cell edge]</text>"), std::string::npos);
  }
}

}  // namespace
}  // namespace isowave
