#pragma once
// The browser build's serial TBB (blocked_range.h): a task runs when it is
// given, so wait() has nothing left to do.
namespace tbb {

class task_group {
 public:
  template <class Function>
  void run(const Function& f) {
    f();
  }
  void wait() {}
};

}  // namespace tbb
