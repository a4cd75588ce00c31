#pragma once
// The transform's loops over flat index ranges.
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace isowave::detail {

// Runs body(begin, end) over [0, n) split across threads in chunks of at
// least `grain` items (enough to amortize scheduling); small ranges inline.
template <class Body>
void parallel_range(std::uint32_t n, std::uint32_t grain, const Body& body) {
  if (n <= grain) {
    body(0u, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::uint32_t>& r) { body(r.begin(), r.end()); });
}

}  // namespace isowave::detail
