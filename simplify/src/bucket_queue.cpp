#include "isowave/simplify/bucket_queue.h"

#include <cassert>

namespace isowave::simplify {

namespace {
constexpr std::uint32_t kNil = ~std::uint32_t{0};
int highest_bit(std::uint64_t word) { return 63 - __builtin_clzll(word); }
}  // namespace

BucketQueue::BucketQueue(std::size_t item_count, std::uint32_t bucket_count)
    : own_links_(item_count, Links{kNil, kNil, kNotQueued}),
      links_(reinterpret_cast<unsigned char*>(own_links_.data())),
      stride_(sizeof(Links)),
      head_(bucket_count, kNil),
      tail_(bucket_count, kNil),
      occupied_((bucket_count + 63) / 64, 0),
      occupied_words_((occupied_.size() + 63) / 64, 0) {
  assert(bucket_count >= 1);
}

BucketQueue::BucketQueue(Links* links, std::size_t stride, std::size_t item_count, std::uint32_t bucket_count)
    : links_(reinterpret_cast<unsigned char*>(links)),
      stride_(stride),
      head_(bucket_count, kNil),
      tail_(bucket_count, kNil),
      occupied_((bucket_count + 63) / 64, 0),
      occupied_words_((occupied_.size() + 63) / 64, 0) {
  assert(bucket_count >= 1 && stride >= sizeof(Links) && (item_count == 0 || links != nullptr));
  (void)item_count;
}

void BucketQueue::push(std::uint32_t item, std::uint32_t bucket) {
  assert(!contains(item) && bucket < bucket_count());
  Links& item_links = link(item);
  item_links.bucket = bucket;
  item_links.next = kNil;
  item_links.prev = tail_[bucket];
  if (tail_[bucket] == kNil) {
    head_[bucket] = item;
    occupied_[bucket / 64] |= std::uint64_t{1} << (bucket % 64);
    occupied_words_[bucket / 4096] |= std::uint64_t{1} << ((bucket / 64) % 64);
  } else {
    link(tail_[bucket]).next = item;
  }
  tail_[bucket] = item;
  ++size_;
}

void BucketQueue::remove(std::uint32_t item) {
  assert(contains(item));
  Links& item_links = link(item);
  const std::uint32_t bucket = item_links.bucket;
  const std::uint32_t before = item_links.prev, after = item_links.next;
  if (before == kNil) head_[bucket] = after; else link(before).next = after;
  if (after == kNil) tail_[bucket] = before; else link(after).prev = before;
  if (head_[bucket] == kNil) {
    std::uint64_t& word = occupied_[bucket / 64];
    word &= ~(std::uint64_t{1} << (bucket % 64));
    if (word == 0) occupied_words_[bucket / 4096] &= ~(std::uint64_t{1} << ((bucket / 64) % 64));
  }
  item_links.bucket = kNotQueued;
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
