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
  // Ends a live line left open by a stage that threw, so that the error
  // message starts on a line of its own.
  ~ConsoleProgress();
  ConsoleProgress(const ConsoleProgress&) = delete;
  ConsoleProgress& operator=(const ConsoleProgress&) = delete;
  void begin_stage(std::string_view name) override;
  void update(double fraction) override;
  void end_stage() override;

 private:
  using Clock = std::chrono::steady_clock;
  void draw(double fraction, bool final_line);

  std::string label_;
  ProgressMode mode_;
  std::string stage_;
  bool line_open_ = false;  // a live line without its newline yet
  Clock::time_point stage_start_{};
  Clock::time_point last_draw_{};
  std::mutex mutex_;
};

}  // namespace isowave::cli
