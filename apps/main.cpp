// isowave: compress isosurfaces with bicubic subdivision-surface wavelets.
#include <csignal>
#include <cstdio>
#include <unistd.h>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "commands.h"
#include "isowave/core/atomic_file.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"

namespace {

struct Subcommand {
  const char* name;
  int (*run)(const isowave::commands::Args&);
  const char* summary;
};

const Subcommand kSubcommands[] = {
    {"convert", isowave::commands::convert, "convert volumes' isosurfaces into wavelet-compressed .isw files"},
    {"decode", isowave::commands::decode, "reconstruct a mesh from an .isw file at a chosen coefficient percentage"},
    {"stats", isowave::commands::stats, "rate-distortion table of an .isw file (the paper's Table 1)"},
    {"info", isowave::commands::info, "what an .isw file or a volume holds (a volume's range and histogram)"},
    {"extract", isowave::commands::extract, "extract a manifold isosurface from a volume"},
    {"simplify", isowave::commands::simplify, "build a base mesh by edge collapse and edge removal (paper Sec. 4.1)"},
    {"fit", isowave::commands::fit, "shrink-wrap a base mesh's subdivision hierarchy onto an isosurface"},
    {"subdivide", isowave::commands::subdivide, "apply the wavelet subdivision operator S to a control mesh"},
};

// An interrupted run leaves no half-written output: uncommitted temporary
// files are removed before the process ends.
extern "C" void remove_temporaries_and_exit(int signal_number) {
  isowave::remove_uncommitted_temporary_files();
  _exit(128 + signal_number);
}

void print_overview() {
  std::printf("usage: isowave COMMAND [ARGS...]\n\ncommands:\n");
  for (const Subcommand& command : kSubcommands) std::printf("  %-12s %s\n", command.name, command.summary);
  std::printf("\n'isowave COMMAND --help' describes a command; 'isowave --version' prints the version.\n");
}

}  // namespace

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  std::signal(SIGINT, remove_temporaries_and_exit);
  std::signal(SIGTERM, remove_temporaries_and_exit);
  if (argc < 2) {
    print_overview();
    return 2;
  }
  const std::string name = argv[1];
  if (name == "-h" || name == "--help" || name == "help") {
    print_overview();
    return 0;
  }
  if (name == "--version") {
    std::printf("isowave %s\n", ISOWAVE_VERSION);
    return 0;
  }
  for (const Subcommand& command : kSubcommands) {
    if (name != command.name) continue;
    try {
      return command.run(isowave::commands::Args(argv + 2, argv + argc));
    } catch (const isowave::Error& error) {
      std::fprintf(stderr, "isowave %s: %s\n", command.name, error.what());
      return error.kind() == isowave::ErrorKind::InvalidArgument ? 2 : 1;
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "isowave %s: out of memory\n", command.name);
      return 1;
    } catch (const std::exception& error) {
      std::fprintf(stderr, "isowave %s: internal error: %s\n", command.name, error.what());
      return 1;
    }
  }
  std::fprintf(stderr, "isowave: unknown command '%s' (see 'isowave --help')\n", name.c_str());
  return 2;
}
