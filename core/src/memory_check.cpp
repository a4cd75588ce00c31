#include "isowave/core/memory_check.h"

#include <cstdio>
#include <unistd.h>

#include "isowave/core/error.h"

namespace isowave {

void check_memory(double fine_vertices, double bytes_per_vertex, const std::string& what) {
  const double needed = fine_vertices * bytes_per_vertex;
  const double physical = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGESIZE));
  if (physical > 0 && needed > physical) {
    char message[256];
    std::snprintf(message, sizeof message,
                  "%s would make %.0f fine vertices, about %.1f GB, more than this machine's %.1f GB", what.c_str(),
                  fine_vertices, needed / 1e9, physical / 1e9);
    throw Error(ErrorKind::InvalidArgument, message);
  }
}

}  // namespace isowave
