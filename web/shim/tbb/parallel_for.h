#pragma once
// The browser build's serial TBB (blocked_range.h).
#include "blocked_range.h"

namespace tbb {

template <class Range, class Body>
void parallel_for(const Range& range, const Body& body) {
  if (!range.empty()) body(range);
}
template <class Range, class Body, class Partitioner>
void parallel_for(const Range& range, const Body& body, const Partitioner&) {
  if (!range.empty()) body(range);
}
template <class Index, class Function>
void parallel_for(Index first, Index last, const Function& f) {
  for (Index i = first; i < last; ++i) f(i);
}

}  // namespace tbb
