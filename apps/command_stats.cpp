// isowave stats: the paper's Table 1 for an .isw file, as text, CSV or JSON,
// optionally plotted as SVG.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli.h"
#include "commands.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/atomic_file.h"
#include "isowave/core/error.h"
#include "rate_distortion_plot.h"

namespace isowave::commands {

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
      "the grid spacing (the geometric mean on anisotropic grids).",
      {{"percents", true, "percentages of full resolution to tabulate", "LIST"},
       {"csv", false, "print CSV", ""},
       {"json", false, "print one JSON object", ""},
       {"plot", true, "draw RMSE against percent as SVG", "FILE.svg"},
       cli::force_option()},
      1,
      1,
      "stats engine.isw --percents 20,10,5 --plot engine_rmse.svg"};
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
  const IswDecoded decoded = read_isw(input);
  if (decoded.truncated) throw Error(ErrorKind::Format, input + ": " + decoded.truncation_note + "; stats need the whole file");
  const ErrorTable errors = error_table(decoded, percents);
  const std::vector<RateDistortionRow>& rows = errors.rows;

  // A cell size that is not a positive finite number (a damaged or hostile
  // file) counts as unknown: errors stay in world units.
  const double stored_cell = decoded.metadata.number("cell_size", 1.0);
  const bool cell_known = decoded.metadata.values.count("cell_size") != 0 && std::isfinite(stored_cell) &&
                          stored_cell > 0 && std::isfinite(1.0 / stored_cell);
  const double cell = cell_known ? stored_cell : 1.0;
  const double fine = static_cast<double>(decoded.hierarchy->fine_vertex_count());
  const double extracted = decoded.metadata.number("extracted_vertices", 0);
  const auto pct = [&](double world) { return 100.0 * world / cell; };
  const auto json_percent = [&](bool known, double world) {
    char text[32] = "null";
    if (known && std::isfinite(world)) std::snprintf(text, sizeof text, "%.6g", pct(world));
    return std::string(text);
  };

  if (args.has("json")) {
    const std::string note = decoded.metadata.text("cell_size_note");
    std::printf("{\"file\": %s, \"cell_size\": %.9g, \"cell_size_known\": %s, %s\"fine_vertices\": %.0f, "
                "\"base_vertices\": %zu, \"levels\": %d, \"extracted_vertices\": %.0f, \"rows\": [",
                cli::json_string(input).c_str(), cell, cell_known ? "true" : "false",
                note.empty() ? "" : ("\"cell_size_note\": " + cli::json_string(note) + ", ").c_str(), fine,
                decoded.hierarchy->vertex_count(0), decoded.levels, extracted);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto& r = rows[i];
      std::printf("%s{\"coefficients\": %zu, \"percent\": %.4f, \"rmse_percent_cell\": %.6g, \"max_percent_cell\": %.6g, "
                  "\"bytes\": %llu, \"bits_per_fine_vertex\": %.5g, \"bits_per_isosurface_vertex\": %.5g, \"base\": %s}",
                  i ? ", " : "", r.kept, r.percent, pct(r.rms), pct(r.max), static_cast<unsigned long long>(r.bytes),
                  8.0 * static_cast<double>(r.bytes) / fine,
                  extracted > 0 ? 8.0 * static_cast<double>(r.bytes) / extracted : 0.0, r.is_base ? "true" : "false");
    }
    std::printf("], \"quantization_rmse_percent_cell\": %s, \"quantization_max_percent_cell\": %s}\n",
                json_percent(errors.quantization.recorded, errors.quantization.rms).c_str(),
                json_percent(errors.quantization.recorded, errors.quantization.max).c_str());
  } else if (args.has("csv")) {
    std::printf("coefficients,percent,rmse_percent_cell,max_percent_cell,bytes,bits_per_fine_vertex,bits_per_isosurface_vertex,base\n");
    for (const auto& r : rows)
      std::printf("%zu,%.4f,%.6g,%.6g,%llu,%.5g,%.5g,%d\n", r.kept, r.percent, pct(r.rms), pct(r.max),
                  static_cast<unsigned long long>(r.bytes), 8.0 * static_cast<double>(r.bytes) / fine,
                  extracted > 0 ? 8.0 * static_cast<double>(r.bytes) / extracted : 0.0, r.is_base ? 1 : 0);
  } else {
    std::printf("%s: %s, isovalue %s, %d levels, %zu base vertices, %.0f fine control points\n", input.c_str(),
                decoded.metadata.text("source", "unknown source").c_str(), decoded.metadata.text("isovalue", "?").c_str(),
                decoded.levels, decoded.hierarchy->vertex_count(0), fine);
    std::printf("cell edge %.6g%s\n", cell,
                cell_known ? (decoded.metadata.text("cell_size_note").empty() ? "" : (" (" + decoded.metadata.text("cell_size_note") + ")").c_str())
                           : " (not recorded in the file: errors are in world units x 100)");
    std::printf("%s\n\n", describe_quantization_error(errors.quantization, cell).c_str());
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
      std::printf("%12zu %8.2f %14.3f %13.3f %12llu %10.3f", r.kept, r.percent, pct(r.rms), pct(r.max),
                  static_cast<unsigned long long>(r.bytes), 8.0 * static_cast<double>(r.bytes) / fine);
      if (extracted > 0) std::printf(" %12.3f", 8.0 * static_cast<double>(r.bytes) / extracted);
      else std::printf(" %12s", "-");
      if (!r.is_base) std::printf("\n");
      else if (below_base.empty()) std::printf("  (base mesh)\n");
      else std::printf("  (base mesh, also for %s: at or below its share)\n", below_base.c_str());
    }
  }
  if (args.has("plot")) {
    std::vector<double> plot_percents = {2, 3, 5, 7.5, 10, 15, 20, 30, 50, 75, 100};
    const std::vector<RateDistortionRow> curve = error_table(decoded, plot_percents).rows;
    AtomicFileWriter file(args.get("plot"));
    const std::string name = std::filesystem::path(decoded.metadata.text("source", input)).filename().string();
    file.write(cli::rate_distortion_svg(curve, cell, "RMSE against coefficients kept: " + name));
    file.commit();
  }
  return 0;
}

}  // namespace isowave::commands
