// The assignment of a batch's jobs to MPI ranks (apps/mpi_batch.h): every job
// once, each rank's jobs largest first, and the largest rank's cost within
// Graham's bound for the LPT rule against the optimum found by brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "mpi_batch.h"

namespace {

using isowave::cli::assign_largest_first;

double cost_of(const std::vector<std::size_t>& jobs, const std::vector<double>& costs) {
  double total = 0;
  for (std::size_t j : jobs) total += costs[j];
  return total;
}

// The least largest rank cost over every assignment (ranks^jobs of them).
double optimal_makespan(const std::vector<double>& costs, int ranks) {
  std::vector<int> rank_of(costs.size(), 0);
  double best = HUGE_VAL;
  while (true) {
    std::vector<double> load(static_cast<std::size_t>(ranks), 0.0);
    for (std::size_t j = 0; j < costs.size(); ++j) load[static_cast<std::size_t>(rank_of[j])] += costs[j];
    best = std::min(best, *std::max_element(load.begin(), load.end()));
    std::size_t k = 0;
    while (k < rank_of.size() && ++rank_of[k] == ranks) rank_of[k++] = 0;
    if (k == rank_of.size()) return best;
  }
}

TEST(MpiBatch, EveryJobOnceLargestFirstWithinGrahamsBound) {
  std::mt19937 random(36);
  for (int trial = 0; trial < 200; ++trial) {
    const int ranks = 2 + trial % 3;
    const std::size_t jobs = 1 + static_cast<std::size_t>(random() % 8);
    std::vector<double> costs(jobs);
    for (double& c : costs) c = random() % 4 == 0 ? 0.0 : double(1 + random() % 1000);
    const auto assigned = assign_largest_first(costs, ranks);
    ASSERT_EQ(assigned.size(), static_cast<std::size_t>(ranks));
    std::vector<int> seen(jobs, 0);
    double makespan = 0;
    for (const auto& mine : assigned) {
      for (std::size_t i = 0; i < mine.size(); ++i) {
        ++seen[mine[i]];
        if (i > 0) {
          EXPECT_GE(costs[mine[i - 1]], costs[mine[i]]);
        }
      }
      makespan = std::max(makespan, cost_of(mine, costs));
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(jobs));
    // Graham (1969): LPT's makespan is at most (4/3 - 1/(3m)) times the optimum.
    EXPECT_LE(makespan, (4.0 / 3.0 - 1.0 / (3.0 * ranks)) * optimal_makespan(costs, ranks) + 1e-9);
    EXPECT_EQ(assigned, assign_largest_first(costs, ranks));  // the same on every rank
  }
}

TEST(MpiBatch, MoreRanksThanJobsLeavesRanksIdle) {
  const auto assigned = assign_largest_first({5.0, 7.0}, 4);
  EXPECT_EQ(assigned, (std::vector<std::vector<std::size_t>>{{1}, {0}, {}, {}}));
}

}  // namespace
