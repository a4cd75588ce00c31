#pragma once
// The browser build's TBB (web/README.md): the library's loops run serially
// in the one thread a page's WebAssembly has by default. Only what the
// decoder uses, with TBB's semantics for one thread.
#include <cstddef>

namespace tbb {

template <class Value>
class blocked_range {
 public:
  blocked_range(Value begin, Value end, std::size_t grain = 1) : begin_(begin), end_(end), grain_(grain) {}
  Value begin() const { return begin_; }
  Value end() const { return end_; }
  std::size_t size() const { return static_cast<std::size_t>(end_ - begin_); }
  std::size_t grainsize() const { return grain_; }
  bool empty() const { return !(begin_ < end_); }

 private:
  Value begin_, end_;
  std::size_t grain_;
};

class simple_partitioner {};
class auto_partitioner {};
class static_partitioner {};

}  // namespace tbb
