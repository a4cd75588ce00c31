// isowave stats: the paper's Table 1 for an .isw file and, for a version 2
// file, D at prefixes of its embedded stream (RDTB); as text, CSV or JSON,
// optionally plotted as SVG.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>

#include "cli.h"
#include "commands.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/atomic_file.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "rate_distortion_plot.h"

namespace isowave::commands {
namespace {

// What errors and rates are reported against.
struct Scale {
  double cell = 1;         // world units per cell edge; 1 when unknown
  bool cell_known = false;
  double fine = 0;         // fine control points
  double extracted = 0;    // vertices of the extracted isosurface; 0 when unknown
  double percent(double world) const { return 100.0 * world / cell; }
  // 8 bytes / vertices; NaN when the count is unknown.
  static double bits(std::uint64_t bytes, double vertices) {
    return vertices > 0 ? 8.0 * static_cast<double>(bytes) / vertices : std::numeric_limits<double>::quiet_NaN();
  }
};

Scale scale_of(const IswDecoded& decoded) {
  // A cell size that is not a positive finite number (a damaged or hostile
  // file) counts as unknown: errors stay in world units.
  const double stored = decoded.metadata.number("cell_size", 1.0);
  Scale s;
  s.cell_known = decoded.metadata.values.count("cell_size") != 0 && std::isfinite(stored) && stored > 0 &&
                 std::isfinite(1.0 / stored);
  s.cell = s.cell_known ? stored : 1.0;
  s.fine = static_cast<double>(decoded.hierarchy->fine_vertex_count());
  s.extracted = decoded.metadata.number("extracted_vertices", 0);
  return s;
}

// A row of the file's RDTB: D at a prefix of the plane stream.
struct StreamRow {
  std::uint64_t bytes = 0;         // file bytes a reader needs (decode --bytes): stream offset + stream_bytes
  std::uint64_t stream_bytes = 0;  // of the plane stream
  double error = 0;                // D against the isosurface, world units (as convert measured it)
  int planes = 0;                  // bit planes complete within the prefix
};

std::vector<StreamRow> stream_rows(const IswDecoded& decoded) {
  const IswStreamInfo& stream = decoded.stream;
  std::vector<StreamRow> rows;
  for (const IswRatePoint& point : stream.rate_table) {
    StreamRow row;
    row.stream_bytes = point.stream_bytes;
    // Saturates: a hostile table may name any count.
    row.bytes = point.stream_bytes > UINT64_MAX - stream.offset ? UINT64_MAX : stream.offset + point.stream_bytes;
    row.error = point.error;
    // Packets that end within the prefix, less a last one its encoder cut (which the whole decode leaves incomplete).
    const auto ended = std::count_if(stream.plane_ends.begin(), stream.plane_ends.end(),
                                     [&](std::uint64_t end) { return end <= point.stream_bytes; });
    row.planes = std::min(static_cast<int>(ended), stream.planes_decoded);
    rows.push_back(row);
  }
  return rows;
}

// The line that stands for the stream table when there is none.
std::string no_stream_note(const IswDecoded& decoded) {
  if (decoded.major_version < 2) return "embedded stream: none (a version 1 file: chunks, tabulated above)";
  return "embedded stream: the file records no D at its prefixes (no RDTB section)";
}

// `value` as a JSON number ("null" when not finite).
std::string json_number(double value) {
  char text[32] = "null";
  if (std::isfinite(value)) std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

void print_json(const std::string& input, const IswDecoded& decoded, const ErrorTable& errors,
                const std::vector<StreamRow>& stream, const Scale& s) {
  const std::string note = decoded.metadata.text("cell_size_note");
  std::printf("{\"file\": %s, \"cell_size\": %.9g, \"cell_size_known\": %s, %s\"fine_vertices\": %.0f, "
              "\"base_vertices\": %zu, \"levels\": %d, \"extracted_vertices\": %.0f, \"rows\": [",
              cli::json_string(input).c_str(), s.cell, s.cell_known ? "true" : "false",
              note.empty() ? "" : ("\"cell_size_note\": " + cli::json_string(note) + ", ").c_str(), s.fine,
              decoded.hierarchy->vertex_count(0), decoded.levels, s.extracted);
  for (std::size_t i = 0; i < errors.rows.size(); ++i) {
    const auto& r = errors.rows[i];
    std::printf("%s{\"coefficients\": %zu, \"percent\": %.4f, \"rmse_percent_cell\": %.6g, \"max_percent_cell\": %.6g, "
                "\"bytes\": %llu, \"bits_per_fine_vertex\": %.5g, \"bits_per_isosurface_vertex\": %.5g, \"base\": %s}",
                i ? ", " : "", r.kept, r.percent, s.percent(r.rms), s.percent(r.max),
                static_cast<unsigned long long>(r.bytes), Scale::bits(r.bytes, s.fine),
                s.extracted > 0 ? Scale::bits(r.bytes, s.extracted) : 0.0, r.is_base ? "true" : "false");
  }
  const bool quantization = errors.quantization.recorded;
  std::printf("], \"quantization_rmse_percent_cell\": %s, \"quantization_max_percent_cell\": %s, "
              "\"stream_planes\": %d, \"stream\": [",
              quantization ? json_number(s.percent(errors.quantization.rms)).c_str() : "null",
              quantization ? json_number(s.percent(errors.quantization.max)).c_str() : "null", decoded.stream.planes);
  for (std::size_t i = 0; i < stream.size(); ++i) {
    const StreamRow& r = stream[i];
    std::printf("%s{\"bytes\": %llu, \"stream_bytes\": %llu, \"bits_per_isosurface_vertex\": %s, "
                "\"bits_per_fine_vertex\": %s, \"d_percent_cell\": %s, \"planes\": %d}",
                i ? ", " : "", static_cast<unsigned long long>(r.bytes), static_cast<unsigned long long>(r.stream_bytes),
                json_number(Scale::bits(r.bytes, s.extracted)).c_str(), json_number(Scale::bits(r.bytes, s.fine)).c_str(),
                json_number(s.percent(r.error)).c_str(), r.planes);
  }
  std::printf("]}\n");
}

void print_csv(const ErrorTable& errors, const Scale& s) {
  std::printf("coefficients,percent,rmse_percent_cell,max_percent_cell,bytes,bits_per_fine_vertex,bits_per_isosurface_vertex,base\n");
  for (const auto& r : errors.rows)
    std::printf("%zu,%.4f,%.6g,%.6g,%llu,%.5g,%.5g,%d\n", r.kept, r.percent, s.percent(r.rms), s.percent(r.max),
                static_cast<unsigned long long>(r.bytes), Scale::bits(r.bytes, s.fine),
                s.extracted > 0 ? Scale::bits(r.bytes, s.extracted) : 0.0, r.is_base ? 1 : 0);
}

// A rate in bits per vertex as a table cell, "-" when unknown.
void print_bits(double bits) {
  if (std::isfinite(bits)) std::printf(" %12.3f", bits);
  else std::printf(" %12s", "-");
}

void print_table1(const std::string& input, const IswDecoded& decoded, const ErrorTable& errors,
                  const std::vector<double>& percents, const Scale& s) {
  const std::vector<RateDistortionRow>& rows = errors.rows;
  const std::string note = decoded.metadata.text("cell_size_note");
  std::printf("%s: %s, isovalue %s, %d levels, %zu base vertices, %.0f fine control points\n", input.c_str(),
              decoded.metadata.text("source", "unknown source").c_str(), decoded.metadata.text("isovalue", "?").c_str(),
              decoded.levels, decoded.hierarchy->vertex_count(0), s.fine);
  std::printf("cell edge %.6g%s\n", s.cell,
              s.cell_known ? (note.empty() ? "" : (" (" + note + ")").c_str())
                           : " (not recorded in the file: errors are in world units x 100)");
  std::printf("%s\n\n", describe_quantization_error(errors.quantization, s.cell).c_str());
  std::printf("%12s %8s %14s %13s %12s %10s %12s\n", "coefficients", "percent", "RMSE [% cell]", "max [% cell]", "bytes",
              "bits/fine", "bits/isovtx");
  // A percentage at or below the base mesh's share gives the base mesh:
  // named in its row (the last) rather than printed as copies of it.
  std::string below_base;
  std::size_t previous_kept = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const RateDistortionRow& r = rows[i];
    if (!r.is_base && r.kept == rows.back().kept) {
      char requested[32];
      std::snprintf(requested, sizeof requested, "%s%g%%", below_base.empty() ? "" : ", ", percents[i]);
      below_base += requested;
      continue;
    }
    if (!r.is_base && r.kept == previous_kept) continue;
    previous_kept = r.kept;
    std::printf("%12zu %8.2f %14.3f %13.3f %12llu %10.3f", r.kept, r.percent, s.percent(r.rms), s.percent(r.max),
                static_cast<unsigned long long>(r.bytes), Scale::bits(r.bytes, s.fine));
    print_bits(Scale::bits(r.bytes, s.extracted));
    if (!r.is_base) std::printf("\n");
    else if (below_base.empty()) std::printf("  (base mesh)\n");
    else std::printf("  (base mesh, also for %s: at or below its share)\n", below_base.c_str());
  }
}

void print_stream_table(const IswDecoded& decoded, const std::vector<StreamRow>& stream, const Scale& s) {
  if (stream.empty()) {
    std::printf("\n%s\n", no_stream_note(decoded).c_str());
    return;
  }
  std::printf("\nembedded stream: D against the isosurface at prefixes (as convert measured it)\n");
  std::printf("%12s %12s %10s %11s %8s\n", "bytes", "bits/isovtx", "bits/fine", "D [% cell]", "planes");
  for (const StreamRow& r : stream) {
    std::printf("%12llu", static_cast<unsigned long long>(r.bytes));
    print_bits(Scale::bits(r.bytes, s.extracted));
    std::printf(" %10.3f %11.3f %5d/%d\n", Scale::bits(r.bytes, s.fine), s.percent(r.error), r.planes,
                decoded.stream.planes);
  }
}

// D against bits per isosurface vertex (per fine vertex when the isosurface's
// count is unknown) at the rows, the last row (the whole stream the file
// holds) labelled, and a first row of no stream bytes (the base mesh alone).
cli::Plot stream_plot(const std::vector<StreamRow>& stream, const Scale& s, const std::string& y_unit,
                      const std::string& name) {
  const bool per_isovertex = s.extracted > 0;
  cli::Plot plot{"D against bits per vertex: " + name,
                 per_isovertex ? "bits per isosurface vertex" : "bits per fine vertex", "D [" + y_unit + "]", {}};
  for (const StreamRow& r : stream)
    plot.points.push_back({Scale::bits(r.bytes, per_isovertex ? s.extracted : s.fine), s.percent(r.error), ""});
  plot.points.back().label = "whole stream";
  if (stream.size() > 1 && stream.front().stream_bytes == 0) plot.points.front().label = "base mesh";
  return plot;
}

void write_plot(const std::string& path, const std::string& input, const IswDecoded& decoded,
                const std::vector<StreamRow>& stream, const Scale& s) {
  const std::string name = std::filesystem::path(decoded.metadata.text("source", input)).filename().string();
  const std::string y_unit = s.cell_known ? "% of cell edge" : "world units x 100";
  cli::Plot plot;
  if (!stream.empty()) {
    plot = stream_plot(stream, s, y_unit, name);
  } else {
    const std::vector<double> percents = {2, 3, 5, 7.5, 10, 15, 20, 30, 50, 75, 100};
    plot = cli::truncation_plot(error_table(decoded, percents).rows, s.cell, y_unit,
                                "RMSE against coefficients kept: " + name);
  }
  AtomicFileWriter file(path);
  file.write(cli::plot_svg(plot));
  file.commit();
}

}  // namespace

int stats(const Args& raw) {
  const cli::CommandSpec spec{
      "stats",
      "IN.isw [--percents 100,20,10,5] [--csv | --json] [--plot FILE.svg]",
      "Prints the paper's Table 1 for IN.isw: coefficients kept (base vertices included), percent of full\n"
      "resolution, RMSE and maximum error in percent of the volume cell edge (over the fine control points,\n"
      "against the full-resolution decode, so 100% is 0), bytes a progressive reader needs, bits per fine\n"
      "vertex and per vertex of the extracted isosurface; the base-mesh row last. Above the table, the\n"
      "quantization error: the full-resolution decode against the fitted surface, as convert measured it\n"
      "(--json has it too). convert prints the same figures (docs/FORMAT.md, \"Errors\"). The cell edge is\n"
      "the grid spacing (the geometric mean on anisotropic grids). Below it, for a version 2 file, D against\n"
      "the isosurface at prefixes of the embedded stream as convert measured them: the file bytes a reader\n"
      "needs (decode --bytes), bits per isosurface and fine vertex, D in percent of the cell edge, and the\n"
      "bit planes complete (--json: \"stream\"; --csv prints Table 1 only).",
      {{"percents", true, "percentages of full resolution to tabulate", "LIST"},
       {"csv", false, "print CSV (Table 1 only)", ""},
       {"json", false, "print one JSON object", ""},
       {"plot", true, "draw D against bits per vertex (RMSE against percent without a stream table) as SVG",
        "FILE.svg"},
       cli::force_option()},
      1,
      1,
      "stats engine.isw --percents 20,10,5 --plot engine_rd.svg"};
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  if (args.has("plot")) {
    if (!cli::has_extension(args.get("plot"), ".svg"))
      throw Error(ErrorKind::InvalidArgument, args.get("plot") + ": --plot writes SVG (name the file FILE.svg)");
    cli::check_outputs(args, {args.get("plot")});
  }
  if (args.has("csv") && args.has("json")) throw Error(ErrorKind::InvalidArgument, "give at most one of --csv and --json");
  const std::vector<double> percents = args.get_double_list("percents", "100,20,10,5", 0, 100);
  const std::string& input = args.positional()[0];
  const std::string bytes = read_file_bytes(input);
  const IswDecoded decoded = decode_isw(bytes, input);
  if (decoded.truncated) throw Error(ErrorKind::Format, input + ": " + decoded.truncation_note + "; stats need the whole file");
  const ErrorTable errors = error_table(decoded, percents, nullptr, nullptr, decode_prefixes(bytes));
  const Scale scale = scale_of(decoded);
  const std::vector<StreamRow> stream = stream_rows(decoded);

  if (args.has("json")) {
    print_json(input, decoded, errors, stream, scale);
  } else if (args.has("csv")) {
    print_csv(errors, scale);
  } else {
    print_table1(input, decoded, errors, percents, scale);
    print_stream_table(decoded, stream, scale);
  }
  if (args.has("plot")) write_plot(args.get("plot"), input, decoded, stream, scale);
  return 0;
}

}  // namespace isowave::commands
