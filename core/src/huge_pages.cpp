#include <algorithm>
#include <cstdint>
#include <limits>

#include <malloc.h>

#include <sys/mman.h>
#include <tbb/parallel_for.h>

#include "isowave/core/huge_page_vector.h"

namespace isowave {

void advise_huge_pages_in(const void* data, std::size_t bytes) {
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

void fault_in_pages(const void* data, std::size_t bytes) {
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

// glibc's malloc tuning; other C libraries (the browser build's) keep their own.
#ifdef __GLIBC__
void keep_freed_memory_for_reuse() {
  mallopt(M_MMAP_MAX, 0);  // every block from the heap, reusable after free
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());  // freed memory stays for reuse
}

void release_freed_memory() { malloc_trim(0); }
#else
void keep_freed_memory_for_reuse() {}
void release_freed_memory() {}
#endif

}  // namespace isowave
