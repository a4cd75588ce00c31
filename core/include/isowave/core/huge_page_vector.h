#pragma once
// std::vector whose large buffers live on transparent huge pages (2 MiB).
//
// Why: the edge-collapse loop, the shrink-wrap and the distance field touch
// arrays of hundreds of megabytes at random places. With 4 KiB pages nearly
// every such access also misses the TLB and walks the page table; with THP in
// "madvise" mode, asking for huge pages removes most of those walks. Buffers
// under 4 MiB use the ordinary heap. Where the kernel has no huge pages to
// give, madvise is a hint and the buffer works as before.
#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#include <sys/mman.h>

namespace isowave {

template <typename T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr std::size_t kHugePage = std::size_t{2} << 20;
  static constexpr std::size_t kThreshold = std::size_t{4} << 20;

  HugePageAllocator() noexcept = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  T* allocate(std::size_t count) {
    if (count > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = count * sizeof(T);
    if (bytes < kThreshold) return static_cast<T*>(::operator new(bytes));
    const std::size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
    void* memory = std::aligned_alloc(kHugePage, rounded);
    if (memory == nullptr) throw std::bad_alloc();
    madvise(memory, rounded, MADV_HUGEPAGE);  // a hint: failure leaves ordinary pages
    return static_cast<T*>(memory);
  }
  void deallocate(T* pointer, std::size_t count) noexcept {
    if (count * sizeof(T) < kThreshold) ::operator delete(pointer);
    else std::free(pointer);
  }
  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
  template <typename U>
  bool operator!=(const HugePageAllocator<U>&) const noexcept { return false; }
};

template <typename T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

// For large std::vector buffers whose type an interface fixes (decoded
// coefficients, refinement arrays): asks for huge pages on the whole 2 MiB
// pages inside [data, data + bytes). A hint that helps only before the pages
// are first touched.
void advise_huge_pages_in(const void* data, std::size_t bytes);
// Faults in the pages of [data, data + bytes) on all threads (the kernel
// zeroes each page on its first touch, which for hundreds of megabytes filled
// by one thread takes a large part of a second). A hint: kernels before 5.14
// leave the pages to be touched later as usual.
void fault_in_pages(const void* data, std::size_t bytes);

// For programs (the CLI, the benchmarks), called once at the start of main();
// library code never calls it. Makes glibc's malloc take large blocks from
// its heap instead of fresh mmap()s and keep freed memory instead of giving
// it back, so that a stage reuses the pages an earlier stage faulted in: the
// kernel zeroes every fresh page on first touch, which costs about a second
// per GB on slow virtual machines. The peak resident size stays about the
// same (the freed blocks are what the next stage allocates); the process
// keeps it until release_freed_memory() or exit.
void keep_freed_memory_for_reuse();
// Gives the memory kept for reuse back to the kernel (malloc_trim): between
// the inputs of a batch, so that one input's leftovers do not stay resident,
// fragmented, under the next (a small input after a large one would otherwise
// keep the large one's peak), and before a benchmark measures a dataset's
// peak.
void release_freed_memory();

// Makes room for `count` elements in `values`, keeping its contents, in a
// buffer on huge pages that are already faulted in, unless it has that room
// already; then resize() or assign() fills it without page faults. For
// vectors whose type an interface fixes (the allocator is std::allocator).
template <typename T, typename Allocator>
void reserve_on_huge_pages(std::vector<T, Allocator>& values, std::size_t count) {
  if (values.capacity() >= count) return;
  if (values.empty()) std::vector<T, Allocator>().swap(values);  // free the old buffer before the new one
  std::vector<T, Allocator> fresh;
  fresh.reserve(count);
  advise_huge_pages_in(fresh.data(), count * sizeof(T));
  fault_in_pages(fresh.data(), count * sizeof(T));
  fresh.assign(values.begin(), values.end());
  values.swap(fresh);
}

// The same for an emptied `values`.
template <typename T, typename Allocator>
void reserve_fresh_on_huge_pages(std::vector<T, Allocator>& values, std::size_t count) {
  values.clear();
  reserve_on_huge_pages(values, count);
}

}  // namespace isowave
