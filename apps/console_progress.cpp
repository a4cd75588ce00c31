#include "console_progress.h"

#include <cstdio>
#include <unistd.h>

namespace isowave::cli {

ProgressMode default_progress_mode(bool quiet) {
  if (quiet) return ProgressMode::Quiet;
  return isatty(fileno(stderr)) ? ProgressMode::LiveBar : ProgressMode::Line;
}

ConsoleProgress::~ConsoleProgress() {
  if (line_open_) std::fputc('\n', stderr);
}

void ConsoleProgress::begin_stage(std::string_view name) {
  std::lock_guard<std::mutex> lock(mutex_);
  stage_ = std::string(name);
  stage_start_ = Clock::now();
  last_draw_ = {};
  if (mode_ == ProgressMode::LiveBar) draw(0.0, false);
}

void ConsoleProgress::update(double fraction) {
  if (mode_ != ProgressMode::LiveBar) return;
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // another thread is drawing
  if (Clock::now() - last_draw_ < std::chrono::milliseconds(100)) return;
  draw(fraction, false);
}

void ConsoleProgress::end_stage() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (mode_ == ProgressMode::Quiet) return;
  draw(1.0, true);
}

void ConsoleProgress::finish(const std::string& outcome) {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (mode_) {
    case ProgressMode::Quiet:
      return;
    case ProgressMode::Line:
      std::fprintf(stderr, "%s%s\n", line_open_ ? "; " : (label_ + ": ").c_str(), outcome.c_str());
      break;
    case ProgressMode::BufferedLine:
      std::fprintf(stderr, "%s: %s%s%s\n", label_.c_str(), line_.c_str(), line_.empty() ? "" : "; ", outcome.c_str());
      break;
    case ProgressMode::LiveBar:
      std::fprintf(stderr, "%s%s: %s\n", line_open_ ? "\n" : "", label_.c_str(), outcome.c_str());
      break;
  }
  line_open_ = false;
  std::fflush(stderr);
}

void ConsoleProgress::note(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (mode_) {
    case ProgressMode::Quiet:
      return;
    case ProgressMode::Line:
      std::fprintf(stderr, "%s%s", line_open_ ? ", " : (label_ + ": ").c_str(), text.c_str());
      line_open_ = true;
      break;
    case ProgressMode::BufferedLine:
      line_ += (line_.empty() ? "" : ", ") + text;
      return;
    case ProgressMode::LiveBar:
      std::fprintf(stderr, "\r\033[K%s: %s\n", label_.c_str(), text.c_str());
      line_open_ = false;
      break;
  }
  std::fflush(stderr);
}

void ConsoleProgress::message(const std::string& line) {
  std::lock_guard<std::mutex> lock(mutex_);
  const char* start = mode_ == ProgressMode::LiveBar ? "\r\033[K" : (line_open_ ? "\n" : "");
  std::fprintf(stderr, "%s%s\n", start, line.c_str());
  line_open_ = false;
  std::fflush(stderr);
}

void ConsoleProgress::draw(double fraction, bool final_line) {
  last_draw_ = Clock::now();
  const double elapsed = std::chrono::duration<double>(last_draw_ - stage_start_).count();
  char stage[128];
  std::snprintf(stage, sizeof stage, "%s %.2f s", stage_.c_str(), elapsed);
  if (mode_ == ProgressMode::BufferedLine) {
    line_ += (line_.empty() ? "" : ", ") + std::string(stage);
    return;
  }
  if (mode_ == ProgressMode::Line) {
    std::fprintf(stderr, "%s%s", line_open_ ? ", " : (label_ + ": ").c_str(), stage);
    line_open_ = true;
    std::fflush(stderr);
    return;
  }
  const int width = 24;
  const int filled = static_cast<int>(fraction * width + 0.5);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(width, '.');
  char eta[32] = "";
  if (!final_line && fraction > 0.02)
    std::snprintf(eta, sizeof eta, "  ETA %.0f s", elapsed * (1.0 - fraction) / fraction);
  std::fprintf(stderr, "\r\033[K%s  %-24s [%s] %3.0f%%  %.1f s%s%s", label_.c_str(), stage_.c_str(), bar.c_str(),
               100.0 * fraction, elapsed, eta, final_line ? "\n" : "");
  line_open_ = !final_line;
  std::fflush(stderr);
}

}  // namespace isowave::cli
