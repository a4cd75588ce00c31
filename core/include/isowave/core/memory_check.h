#pragma once
// A job's memory estimate against this machine's physical memory, checked
// before the job allocates: one clear line at once rather than minutes of
// swapping, the OOM killer or a bare std::bad_alloc.
#include <string>

namespace isowave {

// Refuses, with Error(InvalidArgument) naming `what` (e.g. "6 levels"), a
// job whose estimate (fine_vertices x bytes_per_vertex) exceeds this
// machine's physical memory. O(1).
void check_memory(double fine_vertices, double bytes_per_vertex, const std::string& what);

}  // namespace isowave
