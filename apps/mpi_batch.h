#pragma once
// A convert batch spread over the ranks of an MPI launch (mpirun -n R
// isowave convert ...): every rank plans the same jobs, runs its share, and
// rank 0 gathers the reports and prints the one summary. Compiled only when
// CMake finds MPI (ISOWAVE_MPI); docs/CLI.md "Batches on a cluster".
#include <cstddef>
#include <functional>
#include <vector>

#include "job_report.h"

namespace isowave::cli {

// True when an MPI launcher started this process (OpenMPI's, PMIx's or
// PMI's environment variables are set); a plain run never initializes MPI.
bool launched_by_mpi();

// MPI_Init on construction, MPI_Finalize on destruction: one per process,
// around the convert command only.
class MpiSession {
 public:
  MpiSession();
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int ranks() const { return ranks_; }
  // Rank 0's `value` on every rank (collective).
  int broadcast_from_root(int value) const;

 private:
  int rank_ = 0, ranks_ = 1;
};

// Assigns jobs with estimated `costs` (any unit, >= 0) to `ranks` ranks,
// largest first, each to the rank with the least cost assigned so far (the
// LPT rule; ties go to the earlier job and the lower rank, so every rank
// computes the same). Returns each rank's job indices in the order it runs
// them (largest first). Cost O(J log J + J R).
std::vector<std::vector<std::size_t>> assign_largest_first(const std::vector<double>& costs, int ranks);

// Runs a batch of costs.size() jobs over the ranks (collective): rank 0's
// costs are assigned by assign_largest_first(); on each rank TBB's threads
// are capped at its share of the node's hardware threads (hardware threads
// / ranks on the node, at least 1) while `run` runs this rank's jobs and
// returns their reports in the order given. Returns on rank 0 every job's
// report in job order, elsewhere nothing. `run` must report each job it is
// given (a failed job is a report); an exception from it aborts every rank
// (MPI_Abort) after printing it.
std::vector<JobReport> run_on_ranks(const MpiSession& mpi, const std::vector<double>& costs,
                                    const std::function<std::vector<JobReport>(const std::vector<std::size_t>&)>& run);

}  // namespace isowave::cli
