#pragma once
// Transparent huge pages for the large std::vector buffers the fit hands out
// (the distance field's samples, the fitted positions), whose type the
// interfaces fix; internal arrays use HugePageVector instead. The fitting
// loops sample a 64 MB grid and walk per-vertex arrays of hundreds of
// megabytes at scattered places, where 4 KiB pages miss the TLB on nearly
// every access (see core/huge_page_vector.h).
#include <cstddef>
#include <cstdint>
#include <vector>

#include <sys/mman.h>

namespace isowave::detail {

// Asks for huge pages on the whole 2 MiB pages inside [data, data + bytes).
// A hint: it only helps before the pages are first touched, and where the
// kernel has none to give nothing changes.
inline void advise_huge_pages(const void* data, std::size_t bytes) {
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

// `values` with `count` copies of `value`, in a buffer advised before it is
// filled (a fresh allocation when the current one is too small).
template <class T>
void assign_on_huge_pages(std::vector<T>& values, std::size_t count, const T& value) {
  if (values.capacity() < count) {
    std::vector<T>().swap(values);
    values.reserve(count);
    advise_huge_pages(values.data(), count * sizeof(T));
  }
  values.assign(count, value);
}

}  // namespace isowave::detail
