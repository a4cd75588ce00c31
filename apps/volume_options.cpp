#include "volume_options.h"

#include <charconv>
#include <cmath>
#include <cstdio>

#include "isowave/core/error.h"

namespace isowave::cli {
namespace {

[[noreturn]] void bad_value(const std::string& option, const std::string& text, const std::string& expected) {
  throw Error(ErrorKind::InvalidArgument, "--" + option + " expects " + expected + ", got '" + text + "'");
}

// Splits "a,b,c" into exactly three fields.
std::vector<std::string> three_fields(const std::string& option, const std::string& text, const std::string& expected) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    fields.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (fields.size() != 3) bad_value(option, text, expected);
  return fields;
}

Vec3 parse_vec3(const std::string& option, const std::string& text, bool positive) {
  const std::string expected = positive ? "three positive numbers X,Y,Z" : "three numbers X,Y,Z";
  const std::vector<std::string> fields = three_fields(option, text, expected);
  double value[3];
  for (int i = 0; i < 3; ++i) {
    const std::string& field = fields[static_cast<std::size_t>(i)];
    const auto result = std::from_chars(field.data(), field.data() + field.size(), value[i]);
    if (field.empty() || result.ec != std::errc() || result.ptr != field.data() + field.size() ||
        !std::isfinite(value[i]) || (positive && !(value[i] > 0)))
      bad_value(option, text, expected);
  }
  return {value[0], value[1], value[2]};
}

}  // namespace

void add_volume_options(std::vector<OptionSpec>& options) {
  options.push_back({"dims", true, "raw input: samples along x, y, z (with --type, any file name is raw)", "X,Y,Z"});
  options.push_back({"type", true, "raw input: [u]int8|16|32|64 or float16|32|64 (e.g. uint16, float32)", "T"});
  options.push_back({"endian", true, "raw input: little (default) or big", "E"});
  options.push_back({"spacing", true, "world units between samples (overrides the file)", "SX,SY,SZ"});
  options.push_back({"origin", true, "world position of the first sample (overrides the file)", "OX,OY,OZ"});
  options.push_back({"field", true, ".vtk/.vti: the point-data array; .h5: the dataset; .nc: the variable[@TIME]", "NAME"});
  options.push_back({"grid", true, ".vdb input: the grid to read", "NAME"});
}

VolumeReadOptions volume_read_options(const Arguments& args) {
  VolumeReadOptions options;
  if (args.has("dims")) {
    const std::string text = args.get("dims");
    const std::string expected = "three positive integers X,Y,Z";
    const std::vector<std::string> fields = three_fields("dims", text, expected);
    std::array<std::size_t, 3> dims{};
    for (int i = 0; i < 3; ++i) {
      const std::string& field = fields[static_cast<std::size_t>(i)];
      unsigned long long value = 0;
      const auto result = std::from_chars(field.data(), field.data() + field.size(), value);
      if (field.empty() || result.ec != std::errc() || result.ptr != field.data() + field.size() || value == 0)
        bad_value("dims", text, expected);
      dims[static_cast<std::size_t>(i)] = static_cast<std::size_t>(value);
    }
    options.dims = dims;
  }
  if (args.has("type")) options.type = parse_scalar_type(args.get("type"));
  if (args.has("endian")) {
    const std::string endian = args.get("endian");
    if (endian != "little" && endian != "big") bad_value("endian", endian, "little or big");
    options.big_endian = endian == "big";
  }
  if (args.has("spacing")) options.spacing = parse_vec3("spacing", args.get("spacing"), true);
  if (args.has("origin")) options.origin = parse_vec3("origin", args.get("origin"), false);
  options.field = args.get("field");
  options.grid = args.get("grid");
  return options;
}

ValueSummary report_loaded_volume(const std::string& command, const std::string& input, const Volume& volume,
                                  LoadReport report, ConsoleProgress* progress) {
  if (report == LoadReport::Nothing) return {};
  const ValueSummary summary = summarize_values(volume);
  if (report == LoadReport::RangeAndWarnings) {
    if (progress) {
      progress->note(value_range_text(summary));
    } else {
      std::printf("%s: %s\n", input.c_str(), value_range_text(summary).c_str());
      std::fflush(stdout);  // before the warnings on stderr and the progress lines
    }
  }
  for (const std::string& warning : value_warnings(summary)) {
    const std::string line = "isowave " + command + ": warning: " + input + ": " + warning;
    if (progress) progress->message(line);
    else std::fprintf(stderr, "%s\n", line.c_str());
  }
  return summary;
}

bool is_builtin_volume(const std::string& input) { return input.rfind("builtin:", 0) == 0; }

void add_extraction_options(std::vector<OptionSpec>& options) {
  options.push_back({"min-component-vertices", true, "drop connected components with fewer vertices", "N"});
  options.push_back({"smooth", true, "Gaussian pre-filter of the field, standard deviation in voxels", "SIGMA"});
  options.push_back({"topology-tolerance", true,
                     "remove handles, tunnels, specks and bubbles smaller than T cells (0: exact topology)", "T"});
  options.push_back({"flip", false, "orient normals toward higher values", ""});
}

void add_unfold_option(std::vector<OptionSpec>& options) {
  options.push_back({"unfold-limit", true,
                     "unfold the finest level's folds a few faces wide when its untangling left at most PERCENT of "
                     "its faces folded; 0 never, 100 always (default 2: above, the unfold costs seconds on large "
                     "meshes and raises the wavelet RMSE by 7-12%)",
                     "PERCENT"});
}

void set_unfold_limit(const Arguments& args, ShrinkWrapOptions& options) {
  const double percent = args.get_double("unfold-limit", 100.0 * options.unfold_max_folded_fraction);
  if (!(percent >= 0 && percent <= 100))
    throw Error(ErrorKind::InvalidArgument, "--unfold-limit must be in 0..100 percent, got " + args.get("unfold-limit"));
  options.unfold_max_folded_fraction = percent / 100.0;
  if (percent == 0) options.unfold_rounds = 0;
}

IsosurfaceOptions extraction_options(const Arguments& args) {
  IsosurfaceOptions options;
  options.flip = args.has("flip");
  options.min_component_vertices = static_cast<std::size_t>(args.get_int("min-component-vertices", 0, 0, 1 << 30));
  options.smooth_sigma = args.get_double("smooth", 0.0);
  if (!(options.smooth_sigma == 0 || (options.smooth_sigma >= 0.1 && options.smooth_sigma <= 100)))
    throw Error(ErrorKind::InvalidArgument, "--smooth must be 0 (off) or in 0.1..100 voxels, got " + args.get("smooth"));
  options.topology_tolerance = args.get_double("topology-tolerance", options.topology_tolerance);
  if (!(options.topology_tolerance >= 0 && options.topology_tolerance <= 100))
    throw Error(ErrorKind::InvalidArgument,
                "--topology-tolerance must be in 0..100 cells, got " + args.get("topology-tolerance"));
  return options;
}

std::string topology_tolerance_line(const IsosurfaceReport& r) {
  if (r.topology_tolerance <= 0) return "";
  const TopologyCleanup& t = r.topology;
  char line[512];
  std::snprintf(line, sizeof line,
                "topology tolerance %g cells: cut %zu handles, filled %zu tunnels, removed %zu specks, filled %zu "
                "bubbles (%zu samples changed, %.2f s); the surface moved D = %.2f%% of a cell, area %+.3g%%",
                r.topology_tolerance, t.handles_cut, t.tunnels_filled, t.specks_removed, t.bubbles_filled,
                t.samples_changed, t.seconds, 100 * r.topology_d,
                r.before.area > 0 ? 100 * r.topology_area_change / r.before.area : 0.0);
  return line;
}

std::string topology_tolerance_json(const IsosurfaceReport& r) {
  const TopologyCleanup& t = r.topology;
  char json[640];
  std::snprintf(json, sizeof json,
                "{\"cells\": %.9g, \"handles_cut\": %zu, \"tunnels_filled\": %zu, \"specks_removed\": %zu, "
                "\"bubbles_filled\": %zu, \"samples_changed\": %zu, \"seconds\": %.6g, "
                "\"d_percent_cell\": %.6g, \"area_change\": %.9g, \"genus_before\": %lld, \"genus_after\": %lld, "
                "\"components_before\": %zu, \"components_after\": %zu}",
                r.topology_tolerance, t.handles_cut, t.tunnels_filled, t.specks_removed, t.bubbles_filled,
                t.samples_changed, t.seconds, 100 * r.topology_d, r.topology_area_change,
                static_cast<long long>(r.before.genus), static_cast<long long>(r.after.genus), r.before.components,
                r.after.components);
  return json;
}

}  // namespace isowave::cli
