#pragma once
// Shows the progress the library stages report: on a terminal a live line per
// stage (label, stage, percent, elapsed, ETA), otherwise one line per finished
// stage, or nothing.
#include <chrono>
#include <mutex>
#include <string>

#include "isowave/core/progress.h"

namespace isowave::cli {

enum class ProgressMode { Quiet, Lines, LiveBar };

// LiveBar when stderr is a terminal and nothing asks for quiet or lines.
ProgressMode default_progress_mode(bool quiet);

class ConsoleProgress : public ProgressSink {
 public:
  ConsoleProgress(std::string label, ProgressMode mode) : label_(std::move(label)), mode_(mode) {}
  void begin_stage(std::string_view name) override;
  void update(double fraction) override;
  void end_stage() override;

 private:
  using Clock = std::chrono::steady_clock;
  void draw(double fraction, bool final_line);

  std::string label_;
  ProgressMode mode_;
  std::string stage_;
  Clock::time_point stage_start_{};
  Clock::time_point last_draw_{};
  std::mutex mutex_;
};

}  // namespace isowave::cli
