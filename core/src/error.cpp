#include "isowave/core/error.h"

namespace isowave {

const char* to_string(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::InvalidArgument: return "invalid argument";
    case ErrorKind::Io: return "i/o error";
    case ErrorKind::Format: return "format error";
    case ErrorKind::Topology: return "topology error";
    case ErrorKind::Unsupported: return "unsupported";
    case ErrorKind::EmptyResult: return "empty result";
  }
  return "error";
}

}  // namespace isowave
