#pragma once
// The browser build's serial TBB (blocked_range.h): one thread, one copy.
#include <functional>
#include <optional>

namespace tbb {

template <class T>
class enumerable_thread_specific {
 public:
  template <class Make>
  explicit enumerable_thread_specific(Make make) : make_(make) {}
  T& local() {
    if (!value_) value_.emplace(make_());
    return *value_;
  }

 private:
  std::function<T()> make_;
  std::optional<T> value_;
};

}  // namespace tbb
