// isowave info: what a file holds without converting it. An .isw file (by
// its magic bytes or its name): metadata, counts and the bytes per section.
// A volume: dims, sample type, geometry, value range and a histogram, to
// choose an isovalue and to catch a misread raw file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "cli.h"
#include "commands.h"
#include "isowave/codec/isw_format.h"
#include "isowave/extract/volume_io.h"
#include "isowave/extract/volume_summary.h"
#include "volume_options.h"

namespace isowave::commands {
namespace {

// The first bytes of the .isw magic (docs/FORMAT.md).
bool starts_like_isw(const std::string& path) {
  char head[4] = {};
  std::ifstream file(path, std::ios::binary);
  return file.read(head, sizeof head) && std::memcmp(head, "\x89ISW", sizeof head) == 0;
}

void print_isw_info(const std::string& input) {
  IswDecodeOptions options;
  options.headers_only = true;
  const IswDecoded decoded = read_isw(input, options);
  std::printf("%s: isowave .isw format %u.%u\n", input.c_str(), decoded.major_version, decoded.minor_version);
  for (const auto& [key, value] : decoded.metadata.values) std::printf("  %-22s %s\n", key.c_str(), value.c_str());
  std::printf("base mesh:        %zu vertices, %zu faces, %zu sharp vertices\n", decoded.base.vertex_count(),
              decoded.base.face_count(), decoded.base.sharp_count());
  std::printf("levels:           %d (%zu fine control points)\n", decoded.levels, decoded.fine_vertices);
  std::printf("coefficients:     %llu non-zero in %zu chunks, quantization step %.6g\n",
              static_cast<unsigned long long>(decoded.coefficients_total), decoded.chunks_total, decoded.step);
  std::printf("\n%-6s %12s %12s %14s\n", "section", "offset", "bytes", "coefficients");
  std::uint64_t total = 16;
  for (const IswSectionInfo& s : decoded.sections) {
    std::printf("%-6s %12llu %12llu", s.tag.c_str(), static_cast<unsigned long long>(s.offset),
                static_cast<unsigned long long>(s.bytes));
    if (s.tag == "CHNK") std::printf(" %14llu", static_cast<unsigned long long>(s.coefficients));
    std::printf("\n");
    total += s.bytes;
  }
  std::printf("total  %25llu bytes\n", static_cast<unsigned long long>(total));
  if (decoded.truncated) std::printf("warning: %s\n", decoded.truncation_note.c_str());
}

void print_volume_info(const std::string& input, const Volume& volume, int bins) {
  std::printf("%s: %zu x %zu x %zu %s samples, spacing %g %g %g, origin %g %g %g\n", input.c_str(), volume.dims[0],
              volume.dims[1], volume.dims[2], to_string(volume.source_type), volume.spacing.x, volume.spacing.y,
              volume.spacing.z, volume.origin.x, volume.origin.y, volume.origin.z);
  const ValueSummary summary = cli::report_loaded_volume("info", input, volume, cli::LoadReport::RangeAndWarnings);
  if (summary.finite == 0) return;
  const std::vector<std::size_t> counts = value_histogram(volume, summary, bins);
  const std::size_t largest = *std::max_element(counts.begin(), counts.end());
  const double width = (summary.max - summary.min) / bins;
  std::printf("histogram of the finite values (samples >= an isovalue are inside):\n");
  for (int b = 0; b < bins; ++b) {
    const std::size_t count = counts[static_cast<std::size_t>(b)];
    const int bar = static_cast<int>(std::ceil(40.0 * double(count) / double(largest)));
    std::printf("  %12.6g .. %-12.6g %12zu  %s\n", summary.min + b * width, summary.min + (b + 1) * width, count,
                std::string(static_cast<std::size_t>(bar), '#').c_str());
  }
}

}  // namespace

int info(const Args& raw) {
  cli::CommandSpec spec{
      "info",
      "IN.isw | VOLUME [reader options] [--bins N]",
      "For an .isw file (known by its first bytes or its name): the header, metadata, counts and the bytes\n"
      "of every section. For a volume (any input convert and extract read, builtin:NAME[:N] included): its\n"
      "dimensions, sample type, spacing, origin, value range with NaN/Inf counts and a histogram, to choose\n"
      "an isovalue without converting; values that look misread (a wrong --endian or --type) add a warning.",
      {{"bins", true, "histogram bins for a volume, 1..200 (default 16)", "N"}},
      1,
      1,
      "info engine.nrrd --bins 32"};
  cli::add_volume_options(spec.options);
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  const std::string& input = args.positional()[0];
  const int bins = args.get_int("bins", 16, 1, 200);
  if (!cli::is_builtin_volume(input) && (cli::has_extension(input, ".isw") || starts_like_isw(input))) {
    print_isw_info(input);
    return 0;
  }
  print_volume_info(input, read_volume(input, cli::volume_read_options(args)), bins);
  return 0;
}

}  // namespace isowave::commands
