// isowave info: what an .isw file holds, without decoding the coefficients.
#include <cstdio>

#include "cli.h"
#include "commands.h"
#include "isowave/codec/isw_format.h"

namespace isowave::commands {

int info(const Args& raw) {
  const cli::CommandSpec spec{"info", "IN.isw",
                              "Prints the header, metadata, counts and the bytes of every section of IN.isw.",
                              {},
                              1,
                              1};
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  const std::string& input = args.positional()[0];
  IswDecodeOptions options;
  options.headers_only = true;
  const IswDecoded decoded = read_isw(input, options);
  std::printf("%s: isowave .isw format %u.%u\n", input.c_str(), decoded.major_version, decoded.minor_version);
  for (const auto& [key, value] : decoded.metadata.values) std::printf("  %-22s %s\n", key.c_str(), value.c_str());
  std::printf("base mesh:        %zu vertices, %zu faces, %zu sharp vertices\n", decoded.base.vertex_count(),
              decoded.base.face_count(), decoded.base.sharp_count());
  std::printf("levels:           %d (%zu fine control points)\n", decoded.levels, decoded.hierarchy->fine_vertex_count());
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
  return 0;
}

}  // namespace isowave::commands
