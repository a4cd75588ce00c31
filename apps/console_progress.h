#pragma once
// Shows the progress the library stages report for one run (one input of a
// batch): on a terminal a live line per stage (label, stage, percent,
// elapsed, ETA); otherwise one line per run, the stages and their seconds as
// they finish; or nothing. finish() ends the run with its outcome.
#include <chrono>
#include <mutex>
#include <string>

#include "isowave/core/progress.h"

namespace isowave::cli {

enum class ProgressMode {
  Quiet,
  // One line per run: "LABEL: load 0.02 s, contour 0.10 s, ...; OUTCOME".
  // Written as the stages finish, so that a log shows where a run is.
  Line,
  // The same line, written at once by finish(): for runs side by side.
  BufferedLine,
  LiveBar,
};

// LiveBar when stderr is a terminal, else Line; Quiet when asked.
ProgressMode default_progress_mode(bool quiet);

class ConsoleProgress : public ProgressSink {
 public:
  ConsoleProgress(std::string label, ProgressMode mode) : label_(std::move(label)), mode_(mode) {}
  // Ends a line left open by a stage that threw, so that what follows
  // starts on a line of its own.
  ~ConsoleProgress();
  ConsoleProgress(const ConsoleProgress&) = delete;
  ConsoleProgress& operator=(const ConsoleProgress&) = delete;
  void begin_stage(std::string_view name) override;
  void update(double fraction) override;
  void end_stage() override;
  // Ends the run's line with `outcome` (one line, no newline); on a terminal
  // "LABEL: OUTCOME" on a line of its own. Nothing when quiet.
  void finish(const std::string& outcome);
  // Adds `text` to the run's report: within its line in the line modes
  // ("LABEL: load 0.60 s, TEXT, contour ..."), a line of its own on a
  // terminal; nothing when quiet.
  void note(const std::string& text);
  // `line` on a line of its own on stderr in every mode (a warning); an open
  // line is ended first.
  void message(const std::string& line);

 private:
  using Clock = std::chrono::steady_clock;
  void draw(double fraction, bool final_line);

  std::string label_;
  ProgressMode mode_;
  std::string stage_;
  std::string line_;        // BufferedLine: the line so far
  bool line_open_ = false;  // a line without its newline yet
  Clock::time_point stage_start_{};
  Clock::time_point last_draw_{};
  std::mutex mutex_;
};

}  // namespace isowave::cli
