#pragma once
// Transparent huge pages for the large std::vector buffers the fit hands out
// (the distance field's samples, the fitted positions), whose type the
// interfaces fix; internal arrays use HugePageVector instead. The fitting
// loops sample a 64 MB grid and walk per-vertex arrays of hundreds of
// megabytes at scattered places, where 4 KiB pages miss the TLB on nearly
// every access (see core/huge_page_vector.h).
#include <cstddef>
#include <cstdint>
#include <algorithm>
#include <vector>

#include <sys/mman.h>
#include <tbb/parallel_for.h>

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

// Faults in the pages of [data, data + bytes) on all threads: the kernel
// zeroes each page on its first touch, and for a fresh buffer of hundreds of
// megabytes filled by one thread (std::vector::resize) that zeroing alone
// takes a large part of a second. A hint like advise_huge_pages (kernels
// before 5.14 ignore it and the pages are touched later as usual).
inline void populate_pages(const void* data, std::size_t bytes) {
#ifdef MADV_POPULATE_WRITE
  constexpr std::uintptr_t kPage = 4096, kChunk = std::uintptr_t{8} << 20;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + kPage - 1) & ~(kPage - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kPage - 1);
  if (end <= begin) return;
  const std::size_t chunks = (end - begin + kChunk - 1) / kChunk;
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    const std::uintptr_t from = begin + c * kChunk, to = std::min(end, from + kChunk);
    madvise(reinterpret_cast<void*>(from), to - from, MADV_POPULATE_WRITE);
  });
#else
  (void)data;
  (void)bytes;
#endif
}

// Makes room for `count` elements in `values` (keeping its contents) in a
// buffer on huge pages whose pages are already faulted in.
template <class T, class Allocator>
void reserve_on_huge_pages(std::vector<T, Allocator>& values, std::size_t count) {
  if (values.capacity() >= count) return;
  std::vector<T, Allocator> fresh;
  fresh.reserve(count);
  advise_huge_pages(fresh.data(), count * sizeof(T));
  populate_pages(fresh.data(), count * sizeof(T));
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
