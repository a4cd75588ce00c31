#pragma once
// Errors that come from a file or a user: typed exceptions the CLI turns into
// one line on stderr and a non-zero exit code. Programming errors use assert.
#include <stdexcept>
#include <string>

namespace isowave {

enum class ErrorKind {
  InvalidArgument,  // a parameter or option out of its documented range
  Io,               // a file cannot be opened, read, written or renamed
  Format,           // a file's content is malformed, truncated or inconsistent
  Topology,         // a mesh is not the 2-manifold the stage requires
  Unsupported,      // a valid input the code does not handle
  EmptyResult,      // a valid input that yields nothing to work on (an empty isosurface)
};

const char* to_string(ErrorKind kind);

class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  ErrorKind kind() const { return kind_; }

 private:
  ErrorKind kind_;
};

}  // namespace isowave
