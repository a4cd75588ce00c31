#pragma once
// The browser build's serial TBB (blocked_range.h).
#include <algorithm>

namespace tbb {

template <class Iterator>
void parallel_sort(Iterator first, Iterator last) {
  std::sort(first, last);
}
template <class Iterator, class Compare>
void parallel_sort(Iterator first, Iterator last, const Compare& compare) {
  std::sort(first, last, compare);
}

}  // namespace tbb
