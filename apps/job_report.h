#pragma once
// What one job of a convert batch (one input at one isovalue) reports in the
// summary, as data that can travel between processes (apps/mpi_batch.h):
// plain fields and the job's summary already rendered as text.
#include <cstddef>
#include <string>

namespace isowave::cli {

struct JobReport {
  bool ok = false;
  bool usage_error = false;      // failed with ErrorKind::InvalidArgument (what exit code 2 means)
  std::string error;             // why it failed (empty when ok)
  std::size_t volume_bytes = 0;  // the input's samples as it stores them (0 when it was not loaded)
  std::size_t bytes_out = 0;     // the .isw file written (0 when it failed)
  std::string table_rows;        // its lines of the summary table, newline-terminated
  std::string json;              // its object in the --json results array
};

}  // namespace isowave::cli
