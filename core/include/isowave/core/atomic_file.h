#pragma once
// Writes a file so that readers never see it half-written: the data goes to an
// unnamed file in the target's directory (O_TMPFILE; a named temporary file
// where that is not available), which takes the target's name only on
// commit(). Destroying an uncommitted writer removes the temporary; a killed
// process leaves none behind (with a named temporary: none after SIGINT or
// SIGTERM, see remove_uncommitted_temporary_files()). A replaced file keeps
// its permissions; a symbolic link keeps pointing at the file it named.
#include <cstdint>
#include <cstdio>
#include <string>

namespace isowave {

class AtomicFileWriter {
 public:
  // Throws Error(Io) if the temporary file cannot be created. If `overwrite`
  // is false, commit() refuses to replace an existing file.
  explicit AtomicFileWriter(std::string path, bool overwrite = true);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  // Throws Error(Io) on a short write (disk full, ...).
  void write(const void* data, std::size_t bytes);
  void write(const std::string& text) { write(text.data(), text.size()); }
  // Flushes, closes and renames onto the target; throws Error(Io) on failure.
  void commit();

  const std::string& path() const { return path_; }

 private:
  std::string path_;    // as given, for messages
  std::string target_;  // the file written: path_, or the file a symbolic link there names
  std::string temporary_path_;  // empty while the file is unnamed
  std::FILE* file_ = nullptr;
  char* registered_path_ = nullptr;  // copy of temporary_path_ known to remove_uncommitted_temporary_files()
  void register_path(const std::string& temporary);
  void release_registration();
  void link_unnamed_file();
  void rename_into_place();
  bool overwrite_ = true;
  std::uint64_t written_ = 0;       // bytes written so far
  std::uint64_t written_back_ = 0;  // of which writeback to disk has been started
};

// Removes the temporary file of every writer that has not committed, so that
// a program interrupted by a signal leaves nothing half-written behind. Only
// async-signal-safe calls (unlink), for use in a signal handler.
void remove_uncommitted_temporary_files() noexcept;

}  // namespace isowave
