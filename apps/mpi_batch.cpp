// The convert batch over MPI ranks: assignment, thread share, and the
// reports' way to rank 0 (serialized, MPI_Gather of sizes, MPI_Gatherv of
// bytes).
#include "mpi_batch.h"

#include <mpi.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cassert>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <numeric>
#include <string>
#include <thread>

namespace isowave::cli {
namespace {

// The reports of one rank as bytes: per report its job index, flags, byte
// counts and strings (length-prefixed), in host byte order (the ranks of
// one batch share an architecture).
void put(std::string& out, std::uint64_t value) { out.append(reinterpret_cast<const char*>(&value), sizeof value); }
void put(std::string& out, const std::string& text) {
  put(out, std::uint64_t{text.size()});
  out += text;
}

std::string serialize(const std::vector<std::size_t>& jobs, const std::vector<JobReport>& reports) {
  std::string out;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const JobReport& r = reports[i];
    put(out, std::uint64_t{jobs[i]});
    put(out, std::uint64_t{r.ok} | std::uint64_t{r.usage_error} << 1);
    put(out, std::uint64_t{r.volume_bytes});
    put(out, std::uint64_t{r.bytes_out});
    put(out, r.error);
    put(out, r.table_rows);
    put(out, r.json);
  }
  return out;
}

// Reads what serialize() wrote (from this batch's own ranks) into `reports`
// at each report's job index.
class Reader {
 public:
  Reader(const char* begin, const char* end) : at_(begin), end_(end) {}
  bool done() const { return at_ == end_; }
  std::uint64_t number() {
    assert(end_ - at_ >= 8);
    std::uint64_t value;
    std::memcpy(&value, at_, sizeof value);
    at_ += sizeof value;
    return value;
  }
  std::string text() {
    const std::uint64_t length = number();
    assert(std::uint64_t(end_ - at_) >= length);
    std::string value(at_, length);
    at_ += length;
    return value;
  }

 private:
  const char* at_;
  const char* end_;
};

void deserialize(const char* begin, const char* end, std::vector<JobReport>& reports, std::vector<bool>& seen) {
  for (Reader in(begin, end); !in.done();) {
    const std::uint64_t job = in.number();
    assert(job < reports.size() && !seen[job]);
    seen[job] = true;
    JobReport& r = reports[job];
    const std::uint64_t flags = in.number();
    r.ok = flags & 1;
    r.usage_error = flags & 2;
    r.volume_bytes = in.number();
    r.bytes_out = in.number();
    r.error = in.text();
    r.table_rows = in.text();
    r.json = in.text();
  }
}

// This rank's share of its node's hardware threads: all of them over the
// ranks on the node (MPI_COMM_TYPE_SHARED), at least 1.
int thread_share() {
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
  int local_ranks = 1;
  MPI_Comm_size(node, &local_ranks);
  MPI_Comm_free(&node);
  const int hardware = static_cast<int>(std::thread::hardware_concurrency());
  return std::max(1, hardware / std::max(1, local_ranks));
}

// Rank 0's `costs` on every rank: the assignment is computed from one copy.
std::vector<double> costs_of_root(std::vector<double> costs) {
  MPI_Bcast(costs.data(), static_cast<int>(costs.size()), MPI_DOUBLE, 0, MPI_COMM_WORLD);
  return costs;
}

// Every rank's `bytes` on rank 0, concatenated in rank order (empty
// elsewhere).
std::string gather_to_root(const MpiSession& mpi, const std::string& bytes) {
  assert(bytes.size() <= std::size_t(INT_MAX));
  const int size = static_cast<int>(bytes.size());
  std::vector<int> sizes(mpi.rank() == 0 ? std::size_t(mpi.ranks()) : 0);
  MPI_Gather(&size, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::vector<int> offsets(sizes.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < sizes.size(); ++r) {
    offsets[r] = static_cast<int>(total);
    total += std::size_t(sizes[r]);
    assert(total <= std::size_t(INT_MAX));
  }
  std::string all(total, '\0');
  MPI_Gatherv(bytes.data(), size, MPI_CHAR, all.data(), sizes.data(), offsets.data(), MPI_CHAR, 0, MPI_COMM_WORLD);
  return all;
}

}  // namespace

bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"})
    if (std::getenv(name)) return true;
  return false;
}

MpiSession::MpiSession() {
  MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks_);
}

MpiSession::~MpiSession() { MPI_Finalize(); }

int MpiSession::broadcast_from_root(int value) const {
  MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return value;
}

std::vector<std::vector<std::size_t>> assign_largest_first(const std::vector<double>& costs, int ranks) {
  assert(ranks >= 1);
  std::vector<std::size_t> order(costs.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return costs[a] > costs[b]; });
  std::vector<std::vector<std::size_t>> assigned(static_cast<std::size_t>(ranks));
  std::vector<double> load(static_cast<std::size_t>(ranks), 0.0);
  for (std::size_t job : order) {
    const std::size_t rank = static_cast<std::size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    assigned[rank].push_back(job);
    load[rank] += costs[job];
  }
  return assigned;
}

std::vector<JobReport> run_on_ranks(const MpiSession& mpi, const std::vector<double>& costs,
                                    const std::function<std::vector<JobReport>(const std::vector<std::size_t>&)>& run) {
  const std::vector<std::size_t> mine =
      assign_largest_first(costs_of_root(costs), mpi.ranks())[static_cast<std::size_t>(mpi.rank())];
  std::string bytes;
  {
    const tbb::global_control share(tbb::global_control::max_allowed_parallelism,
                                    static_cast<std::size_t>(thread_share()));
    try {
      const std::vector<JobReport> reports = run(mine);
      assert(reports.size() == mine.size());
      bytes = serialize(mine, reports);
    } catch (const std::exception& error) {
      // Not a job's failure (those are reports) but the rank's: the others
      // would wait for it forever.
      std::fprintf(stderr, "isowave convert: rank %d: %s\n", mpi.rank(), error.what());
      MPI_Abort(MPI_COMM_WORLD, 1);
    }
  }
  const std::string all = gather_to_root(mpi, bytes);
  std::vector<JobReport> reports(mpi.rank() == 0 ? costs.size() : 0);
  std::vector<bool> seen(reports.size(), false);
  deserialize(all.data(), all.data() + all.size(), reports, seen);
  assert(std::all_of(seen.begin(), seen.end(), [](bool s) { return s; }));
  return reports;
}

}  // namespace isowave::cli
