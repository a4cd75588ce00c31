#pragma once
// Transparent huge pages for the large std::vector buffers the fit hands out
// (the distance field's samples, the fitted positions), whose type the
// interfaces fix; internal arrays use HugePageVector instead. The fitting
// loops sample a 64 MB grid and walk per-vertex arrays of hundreds of
// megabytes at scattered places, where 4 KiB pages miss the TLB on nearly
// every access (see core/huge_page_vector.h).
#include <cstddef>
#include <vector>

#include "isowave/core/huge_page_vector.h"

namespace isowave::detail {

// Makes room for `count` elements in `values` (keeping its contents) in a
// buffer on huge pages whose pages are already faulted in.
template <class T, class Allocator>
void reserve_on_huge_pages(std::vector<T, Allocator>& values, std::size_t count) {
  if (values.capacity() >= count) return;
  std::vector<T, Allocator> fresh;
  fresh.reserve(count);
  advise_huge_pages_in(fresh.data(), count * sizeof(T));
  fault_in_pages(fresh.data(), count * sizeof(T));
  fresh.assign(values.begin(), values.end());
  values.swap(fresh);
}

// `values` with `count` copies of `value`, on huge pages.
template <class T>
void assign_on_huge_pages(std::vector<T>& values, std::size_t count, const T& value) {
  if (values.capacity() < count) {
    std::vector<T>().swap(values);
    reserve_on_huge_pages(values, count);
  }
  values.assign(count, value);
}

}  // namespace isowave::detail
