#pragma once
// The paper's "fast priority queue implemented using bucket sorting, where
// within each bucket of priorities the legal edge collapses are listed in
// first-in-first-out order" (Sec. 4.1).
//
// Items are dense indices 0..item_count-1 (edge ids). Each bucket is a doubly
// linked list threaded through per-item links (next, prev, bucket: 12 bytes
// per item, together so that touching an item costs one cache miss, and no
// allocation after construction, which matters for ~8 M edges). The links are
// a flat array of the queue's own, or live in the caller's per-item records
// (the collapse keeps them in its edge records, whose cache line a requeued
// edge's evaluation has just loaded; queues with disjoint items can share
// them). A two-level bitmap of non-empty
// buckets finds the highest one in O(bucket_count / 4096) word reads.
// push, remove, pop: O(1) plus that bitmap scan.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "isowave/core/huge_page_vector.h"

namespace isowave::simplify {

class BucketQueue {
 public:
  static constexpr std::uint32_t kNotQueued = ~std::uint32_t{0};
  struct Links {
    std::uint32_t next, prev, bucket;  // bucket = kNotQueued: not in a queue
  };

  // bucket_count >= 1; a higher bucket index means a higher priority.
  BucketQueue(std::size_t item_count, std::uint32_t bucket_count);
  // With the caller's links: item i's at (char*)links + i * stride, with
  // bucket == kNotQueued for every item not in this queue (precondition).
  // They must outlive the queue.
  BucketQueue(Links* links, std::size_t stride, std::size_t item_count, std::uint32_t bucket_count);
  BucketQueue(const BucketQueue&) = delete;
  BucketQueue& operator=(const BucketQueue&) = delete;

  std::uint32_t bucket_count() const { return static_cast<std::uint32_t>(head_.size()); }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool contains(std::uint32_t item) const { return link(item).bucket != kNotQueued; }
  // The item's bucket, or kNotQueued.
  std::uint32_t bucket_of(std::uint32_t item) const { return link(item).bucket; }

  // Appends item at the tail of bucket (first in, first out). Precondition:
  // !contains(item), bucket < bucket_count().
  void push(std::uint32_t item, std::uint32_t bucket);
  // Precondition: contains(item).
  void remove(std::uint32_t item);
  // Head of the highest non-empty bucket (the oldest item there). Precondition: !empty().
  std::uint32_t top() const;
  std::uint32_t pop();

 private:
  std::uint32_t highest_bucket() const;
  Links& link(std::uint32_t item) { return *reinterpret_cast<Links*>(links_ + item * stride_); }
  const Links& link(std::uint32_t item) const { return *reinterpret_cast<const Links*>(links_ + item * stride_); }

  HugePageVector<Links> own_links_;                  // per item, unless the caller keeps them
  unsigned char* links_;
  std::size_t stride_;
  std::vector<std::uint32_t> head_, tail_;           // per bucket
  std::vector<std::uint64_t> occupied_;              // bit per bucket
  std::vector<std::uint64_t> occupied_words_;        // bit per word of occupied_
  std::size_t size_ = 0;
};

}  // namespace isowave::simplify
