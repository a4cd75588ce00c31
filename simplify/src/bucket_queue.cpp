#include "isowave/simplify/bucket_queue.h"

#include <cassert>

namespace isowave::simplify {

namespace {
constexpr std::uint32_t kNil = ~std::uint32_t{0};
int highest_bit(std::uint64_t word) { return 63 - __builtin_clzll(word); }
}  // namespace

BucketQueue::BucketQueue(std::size_t item_count, std::uint32_t bucket_count)
    : links_(item_count, Links{kNil, kNil, kNotQueued}),
      head_(bucket_count, kNil),
      tail_(bucket_count, kNil),
      occupied_((bucket_count + 63) / 64, 0),
      occupied_words_((occupied_.size() + 63) / 64, 0) {
  assert(bucket_count >= 1);
}

void BucketQueue::push(std::uint32_t item, std::uint32_t bucket) {
  assert(!contains(item) && bucket < bucket_count());
  links_[item].bucket = bucket;
  links_[item].next = kNil;
  links_[item].prev = tail_[bucket];
  if (tail_[bucket] == kNil) {
    head_[bucket] = item;
    occupied_[bucket / 64] |= std::uint64_t{1} << (bucket % 64);
    occupied_words_[bucket / 4096] |= std::uint64_t{1} << ((bucket / 64) % 64);
  } else {
    links_[tail_[bucket]].next = item;
  }
  tail_[bucket] = item;
  ++size_;
}

void BucketQueue::remove(std::uint32_t item) {
  assert(contains(item));
  const std::uint32_t bucket = links_[item].bucket;
  const std::uint32_t before = links_[item].prev, after = links_[item].next;
  if (before == kNil) head_[bucket] = after; else links_[before].next = after;
  if (after == kNil) tail_[bucket] = before; else links_[after].prev = before;
  if (head_[bucket] == kNil) {
    std::uint64_t& word = occupied_[bucket / 64];
    word &= ~(std::uint64_t{1} << (bucket % 64));
    if (word == 0) occupied_words_[bucket / 4096] &= ~(std::uint64_t{1} << ((bucket / 64) % 64));
  }
  links_[item].bucket = kNotQueued;
  --size_;
}

std::uint32_t BucketQueue::highest_bucket() const {
  for (std::size_t w = occupied_words_.size(); w-- > 0;) {
    if (occupied_words_[w] == 0) continue;
    const std::size_t word = w * 64 + static_cast<std::size_t>(highest_bit(occupied_words_[w]));
    return static_cast<std::uint32_t>(word * 64 + static_cast<std::size_t>(highest_bit(occupied_[word])));
  }
  assert(false && "top() of an empty BucketQueue");
  return kNil;
}

std::uint32_t BucketQueue::top() const {
  assert(!empty());
  return head_[highest_bucket()];
}

std::uint32_t BucketQueue::pop() {
  const std::uint32_t item = top();
  remove(item);
  return item;
}

}  // namespace isowave::simplify
