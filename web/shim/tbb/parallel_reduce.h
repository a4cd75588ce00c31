#pragma once
// The browser build's serial TBB (blocked_range.h).
#include "blocked_range.h"

namespace tbb {

template <class Range, class Value, class RealBody, class Reduction>
Value parallel_reduce(const Range& range, const Value& identity, const RealBody& body, const Reduction&) {
  return range.empty() ? identity : body(range, identity);
}

}  // namespace tbb
