#include "isowave/core/atomic_file.h"

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <utility>

#include "isowave/core/error.h"

namespace isowave {
namespace {

// Temporary paths of uncommitted writers, readable from a signal handler.
constexpr std::size_t kMaxPending = 256;
std::array<std::atomic<char*>, kMaxPending> pending_temporaries{};

void register_temporary(char* path) {
  for (auto& slot : pending_temporaries) {
    char* expected = nullptr;
    if (slot.compare_exchange_strong(expected, path)) return;
  }
}

void unregister_temporary(const char* path) {
  for (auto& slot : pending_temporaries) {
    char* expected = const_cast<char*>(path);
    if (slot.compare_exchange_strong(expected, nullptr)) return;
  }
}

}  // namespace

void remove_uncommitted_temporary_files() noexcept {
  for (auto& slot : pending_temporaries)
    if (char* path = slot.load()) unlink(path);
}

AtomicFileWriter::AtomicFileWriter(std::string path, bool overwrite)
    : path_(std::move(path)), target_(path_), overwrite_(overwrite) {
  if (path_.empty()) throw Error(ErrorKind::InvalidArgument, "empty output path");
  // A symbolic link keeps pointing where it did: the file it names is replaced.
  struct stat link {};
  if (lstat(path_.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
    std::error_code error;
    const std::filesystem::path resolved = std::filesystem::weakly_canonical(path_, error);
    if (!error) target_ = resolved.string();
  }
  // An unnamed file in the target's directory (O_TMPFILE) leaves nothing
  // behind even when the process is killed (SIGKILL, power loss); commit()
  // gives it its name through /proc/self/fd. Where the file system or a
  // missing /proc does not allow that, a named temporary file.
  int fd = -1;
  if (access("/proc/self/fd", X_OK) == 0) {
    const std::size_t slash = target_.rfind('/');
    const std::string directory = slash == std::string::npos ? "." : slash == 0 ? "/" : target_.substr(0, slash);
    fd = open(directory.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
  }
  if (fd < 0) {
    std::string pattern = target_ + ".tmp-XXXXXX";
    fd = mkstemp(pattern.data());
    if (fd < 0) throw Error(ErrorKind::Io, path_ + ": cannot create a temporary file: " + std::strerror(errno));
    temporary_path_ = pattern;
    register_path(temporary_path_);
    // mkstemp creates the file 0600; give it the permissions a plain create would.
    const mode_t mask = umask(0);
    umask(mask);
    fchmod(fd, 0666 & ~mask);
  }
  file_ = fdopen(fd, "wb");
  if (!file_) {
    ::close(fd);
    if (!temporary_path_.empty()) std::remove(temporary_path_.c_str());
    throw Error(ErrorKind::Io, path_ + ": cannot open a temporary file: " + std::strerror(errno));
  }
  static thread_local char buffer[1 << 16];
  std::setvbuf(file_, buffer, _IOFBF, sizeof buffer);
}

AtomicFileWriter::~AtomicFileWriter() {
  if (file_) std::fclose(file_);
  if (!temporary_path_.empty()) std::remove(temporary_path_.c_str());
  release_registration();
}

void AtomicFileWriter::register_path(const std::string& temporary) {
  registered_path_ = strdup(temporary.c_str());
  if (registered_path_) register_temporary(registered_path_);
}

void AtomicFileWriter::release_registration() {
  if (!registered_path_) return;
  unregister_temporary(registered_path_);
  std::free(registered_path_);
  registered_path_ = nullptr;
}

void AtomicFileWriter::write(const void* data, std::size_t bytes) {
  if (!file_) throw Error(ErrorKind::Io, path_ + ": write after commit");
  if (bytes && std::fwrite(data, 1, bytes, file_) != bytes)
    throw Error(ErrorKind::Io, path_ + ": write failed: " + std::strerror(errno));
  written_ += bytes;
  // Start writing large files to disk while the rest is produced, so that
  // commit()'s fsync waits only for the tail. A failed flush drops stdio's
  // buffer, so it must fail the write rather than leave a gap in the file.
  constexpr std::uint64_t kWritebackBytes = std::uint64_t{16} << 20;
  if (written_ - written_back_ >= kWritebackBytes) {
    if (std::fflush(file_) != 0) throw Error(ErrorKind::Io, path_ + ": write failed: " + std::strerror(errno));
    sync_file_range(fileno(file_), static_cast<off64_t>(written_back_), static_cast<off64_t>(written_ - written_back_),
                    SYNC_FILE_RANGE_WRITE);
    written_back_ = written_;
  }
}

void AtomicFileWriter::commit() {
  if (!file_) throw Error(ErrorKind::Io, path_ + ": committed twice");
  // ferror: any earlier failure of stdio on this stream (its data is lost).
  const bool flushed = std::fflush(file_) == 0 && !std::ferror(file_) && fsync(fileno(file_)) == 0;
  const int error = errno;
  // A replaced file keeps its permissions.
  struct stat existing {};
  if (flushed && overwrite_ && stat(target_.c_str(), &existing) == 0) fchmod(fileno(file_), existing.st_mode & 07777);
  if (temporary_path_.empty() && flushed) {
    link_unnamed_file();  // while the file is open: closing an unnamed one deletes it
  } else if (!flushed || std::fclose(std::exchange(file_, nullptr)) != 0) {
    throw Error(ErrorKind::Io, path_ + ": write failed: " + std::strerror(flushed ? errno : error));
  } else {
    if (!overwrite_ && access(target_.c_str(), F_OK) == 0)
      throw Error(ErrorKind::Io, path_ + ": already exists (not overwritten)");
    rename_into_place();
  }
}

void AtomicFileWriter::link_unnamed_file() {
  const std::string self = "/proc/self/fd/" + std::to_string(fileno(file_));
  if (!overwrite_) {
    // linkat() never replaces a file: no window between a check and the link.
    if (linkat(AT_FDCWD, self.c_str(), AT_FDCWD, target_.c_str(), AT_SYMLINK_FOLLOW) != 0) {
      const int error = errno;
      throw Error(ErrorKind::Io, path_ + (error == EEXIST ? ": already exists (not overwritten)"
                                                          : ": cannot give the file its name: " +
                                                                std::string(std::strerror(error))));
    }
  } else {
    // A name of its own first, then rename() over the old file.
    for (int attempt = 0;; ++attempt) {
      temporary_path_ = target_ + ".tmp-" + std::to_string(getpid()) + "-" + std::to_string(attempt);
      register_path(temporary_path_);
      if (linkat(AT_FDCWD, self.c_str(), AT_FDCWD, temporary_path_.c_str(), AT_SYMLINK_FOLLOW) == 0) break;
      const int error = errno;
      release_registration();
      temporary_path_.clear();
      if (error != EEXIST || attempt == 100)
        throw Error(ErrorKind::Io, path_ + ": cannot give the file its name: " + std::strerror(error));
    }
  }
  if (std::fclose(std::exchange(file_, nullptr)) != 0)
    throw Error(ErrorKind::Io, path_ + ": write failed: " + std::strerror(errno));
  if (!temporary_path_.empty()) rename_into_place();
}

void AtomicFileWriter::rename_into_place() {
  if (std::rename(temporary_path_.c_str(), target_.c_str()) != 0)
    throw Error(ErrorKind::Io, path_ + ": cannot rename the temporary file into place: " + std::strerror(errno));
  temporary_path_.clear();
  release_registration();
}

}  // namespace isowave
