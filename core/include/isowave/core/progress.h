#pragma once
// Progress reporting from library code, which never prints: a stage reports
// through this interface and the CLI decides how to show it.
#include <string_view>

namespace isowave {

class ProgressSink {
 public:
  virtual ~ProgressSink() = default;
  // A named stage starts (e.g. "analysis").
  virtual void begin_stage(std::string_view name) {}
  // Fraction of the current stage done, in [0, 1]; may be called from any thread.
  virtual void update(double fraction) {}
  virtual void end_stage() {}
};

// Reports nothing; the default for every stage.
inline ProgressSink& no_progress() {
  static ProgressSink sink;
  return sink;
}

}  // namespace isowave
