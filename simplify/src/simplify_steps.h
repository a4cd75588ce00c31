#pragma once
// The steps of simplify() (simplify.cpp), each in its own file: the corner
// table build (collapse_table.cpp), the collapse loops (collapse_loops.cpp)
// and the report (simplify_report.cpp). Private to the simplify library.
#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/progress.h"
#include "isowave/simplify/collapse_mesh.h"
#include "isowave/simplify/simplify.h"

namespace isowave::simplify {

using Clock = std::chrono::steady_clock;

inline double seconds_since_start(const Clock::time_point& start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Seconds since `start`, which moves to now.
inline double seconds_since(Clock::time_point& start) {
  const Clock::time_point now = Clock::now();
  const double seconds = std::chrono::duration<double>(now - start).count();
  start = now;
  return seconds;
}

// The corner table of the input in spatial (Morton) order. Throws what the
// CollapseMesh constructor throws, prefixed with `source`; for Error(Topology)
// the message of require_manifold(), which names the problem. `vertex_order`,
// if given, receives the input index of each table vertex.
CollapseMesh build_table(const PolygonMesh& input, const CollapseRules& rules, const std::string& source,
                         std::vector<std::uint32_t>* vertex_order = nullptr);

// The priority queue and the collapse phases (Sec. 4.1, and the valence
// flips): fills the report's target, collapse counts, stop reason and the
// queue and collapse times (`clock` as for seconds_since).
void collapse_to_target(CollapseMesh& mesh, const SimplifyOptions& options, SimplifyReport& report,
                        ProgressSink& progress, Clock::time_point& clock);

// Components, boundary loops, genus and the lower bound of the table as built.
void count_input_topology(const CollapseMesh& mesh, SimplifyReport& report);
// Output edge count, face-size and valence histograms.
void fill_histograms(const PolygonMesh& mesh, int max_valence, SimplifyReport& report);

}  // namespace isowave::simplify
