#include "isowave/simplify/simplify.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "edge_removal.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/simplify/bucket_queue.h"
#include "isowave/simplify/collapse_error.h"
#include "isowave/simplify/collapse_mesh.h"
#include "isowave/core/binned_surface_distance.h"

namespace isowave::simplify {

namespace {

// The flip round lowers the endpoints' valences by at most this many flips.
constexpr int kMaxFlipsPerCollapse = 4;
constexpr double kHuge = 1e300;
constexpr double kParallelShare = 0.9;  // see collapse_in_parallel
constexpr std::uint8_t kBand = 255;     // region of the vertices no thread collapses

using Clock = std::chrono::steady_clock;

double seconds_since_start(const Clock::time_point& start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double seconds_since(Clock::time_point& start) {
  const Clock::time_point now = Clock::now();
  const double seconds = std::chrono::duration<double>(now - start).count();
  start = now;
  return seconds;
}

void check_options(const SimplifyOptions& options) {
  const auto fail = [](const std::string& what) { throw Error(ErrorKind::InvalidArgument, "simplify: " + what); };
  if (!(options.edge_removal_min_normal_dot >= -1 && options.edge_removal_min_normal_dot <= 1))
    fail("edge-removal normal threshold must be in [-1, 1]");
  if (!(options.collapse_min_normal_dot >= -1 && options.collapse_min_normal_dot < 1))
    fail("collapse normal threshold must be in [-1, 1)");
  if (!(options.flip_min_normal_dot >= -1 && options.flip_min_normal_dot <= 1))
    fail("flip normal threshold must be in [-1, 1]");
  if (options.max_valence < 3 || options.max_valence > 32) fail("maximum valence must be in 3..32");
  if (options.bucket_count < 1) fail("bucket count must be at least 1");
  if (options.max_flip_rounds < 0) fail("flip rounds must not be negative");
  if (!(options.batch_error_factor >= 1 && options.batch_error_factor <= 1e20))
    fail("batch error factor must be in [1, 1e20]");
}

// Fewest vertices the rules allow for one component (see SimplifyReport).
std::size_t component_lower_bound(const CollapseMesh::ComponentCounts& counts) {
  const long long g = counts.genus();
  const long long b = static_cast<long long>(counts.boundary_loops);
  long long bound = 0;
  if (b == 0) bound = std::max(4LL, 6 * g - 6);
  else bound = std::max(3 * b, (6 * g - 6 + 3 * b + 1) / 2);
  return static_cast<std::size_t>(std::max(bound, 3LL));
}

// Interleaves the low 21 bits of x, y, z (Morton / Z-order code).
std::uint64_t morton_code(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  const auto spread = [](std::uint64_t v) {
    v &= 0x1FFFFF;
    v = (v | v << 32) & 0x1F00000000FFFFull;
    v = (v | v << 16) & 0x1F0000FF0000FFull;
    v = (v | v << 8) & 0x100F00F00F00F00Full;
    v = (v | v << 4) & 0x10C30C30C30C30C3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

// Vertex order for the corner table: Morton order of the positions (the
// table then puts triangles in order of their first vertex). The collapse
// loop jumps between random places of a mesh of hundreds of megabytes; in
// scan order (marching cubes) a vertex's fan lies in three far-apart
// stretches of memory, in Morton order mostly in one, so each fan walk costs
// fewer cache misses.
std::vector<std::uint32_t> spatial_order(const PolygonMesh& mesh) {
  const std::size_t n = mesh.vertex_count();
  double low[3] = {kHuge, kHuge, kHuge}, high[3] = {-kHuge, -kHuge, -kHuge};
  for (const Vec3& p : mesh.positions)
    for (int axis = 0; axis < 3; ++axis) {
      low[axis] = std::min(low[axis], p[axis]);
      high[axis] = std::max(high[axis], p[axis]);
    }
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 65536), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t v = range.begin(); v != range.end(); ++v) {
      std::uint32_t cell[3];
      for (int axis = 0; axis < 3; ++axis) {
        const double extent = high[axis] - low[axis];
        const double t = extent > 0 ? (mesh.positions[v][axis] - low[axis]) / extent : 0.0;
        cell[axis] = static_cast<std::uint32_t>(t * double(0x1FFFFF));
      }
      keyed[v] = {morton_code(cell[0], cell[1], cell[2]), static_cast<std::uint32_t>(v)};
    }
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = keyed[k].second;
  return order;
}

// The corner table of the input in spatial order. Its manifold checks only
// say that something is wrong; require_manifold() then names the problem.
CollapseMesh build_table(const PolygonMesh& input, const CollapseRules& rules, const std::string& source) {
  try {
    return CollapseMesh(input, spatial_order(input), rules);
  } catch (const Error& error) {
    if (error.kind() == ErrorKind::Topology) require_manifold(input, source);
    throw Error(error.kind(), source + ": " + error.what());
  }
}

// After re-evaluating stencil edge s: a legal edge goes to the bucket of its
// new priority (keeping its FIFO place if the bucket is the same), an
// illegal one leaves the queue.
void requeue(BucketQueue& queue, CollapseMesh& mesh, std::uint32_t s, const Evaluation& update,
             std::uint32_t bucket_count) {
  if (update.legality != Legality::Legal) {
    if (queue.contains(s)) queue.remove(s);
    return;
  }
  mesh.set_latest_delta_error(s, update.delta_error);
  const std::uint32_t bucket = priority_bucket(mesh.error(s), bucket_count);
  if (queue.contains(s)) {
    if (queue.bucket_of(s) == bucket) return;
    queue.remove(s);
  }
  queue.push(s, bucket);
}

// Hands edges to a collapse loop (SimplifyOptions::batch_error_factor). With
// a span of 0 buckets, one at a time in priority order, as the paper does.
// Otherwise in batches: every queued edge within `span` buckets of the top
// one, in edge order (the corner table numbers edges in the order of their
// triangles, which follow the Morton order of the vertices: consecutive
// edges are neighbours that share cache lines). A batch edge that a collapse
// deleted is skipped; one that went back into the queue meanwhile is taken
// out again. O(log batch) per edge.
class EdgePops {
 public:
  EdgePops(BucketQueue& queue, std::uint32_t span) : queue_(queue), span_(span) {}

  // The next edge, out of the queue, and the bucket its re-evaluated priority
  // must reach for it to collapse now (else it goes back); false when the
  // queue and the batch are empty.
  bool next(const CollapseMesh& mesh, std::uint32_t& e, std::uint32_t& least_bucket) {
    if (span_ == 0) {
      if (queue_.empty()) return false;
      e = queue_.top();
      least_bucket = queue_.bucket_of(e);
      queue_.remove(e);
      return true;
    }
    for (;;) {
      while (next_ < batch_.size()) {
        if (next_ + 8 < batch_.size()) mesh.prefetch_edge_record(batch_[next_ + 8]);
        if (next_ + 4 < batch_.size()) mesh.prefetch_edge_corners(batch_[next_ + 4]);
        if (next_ + 2 < batch_.size()) mesh.prefetch_edge_vertices(batch_[next_ + 2]);
        e = batch_[next_++];
        if (!mesh.edge_alive(e)) continue;
        if (queue_.contains(e)) queue_.remove(e);
        least_bucket = threshold_;
        return true;
      }
      if (queue_.empty()) return false;
      batch_.clear();
      next_ = 0;
      const std::uint32_t top = queue_.bucket_of(queue_.top());
      threshold_ = top > span_ ? top - span_ : 0;
      while (!queue_.empty() && queue_.bucket_of(queue_.top()) >= threshold_) {
        batch_.push_back(queue_.top());
        queue_.remove(batch_.back());
      }
      std::sort(batch_.begin(), batch_.end());
    }
  }

 private:
  BucketQueue& queue_;
  const std::uint32_t span_;
  std::vector<std::uint32_t> batch_;
  std::size_t next_ = 0;
  std::uint32_t threshold_ = 0;
};

// What a collapse loop did, added to the report once it ends.
struct LoopCounters {
  std::size_t collapses = 0, collapses_after_flips = 0, flips = 0, flips_undone = 0, flip_attempts_failed = 0;
  std::array<std::size_t, kLegalityCount> rejected{};

  void add_to(SimplifyReport& report) const {
    report.collapses += collapses;
    report.collapses_after_flips += collapses_after_flips;
    report.flips += flips;
    report.flips_undone += flips_undone;
    report.flip_attempts_failed += flip_attempts_failed;
    for (int k = 0; k < kLegalityCount; ++k) report.rejected_at_pop[k] += rejected[k];
  }
};

// One thread's collapse loop (paper Sec. 4.1): pop the best edge, evaluate
// it again, collapse it if it is still legal and still as good, update the
// Fig. 8 stencil. Optionally (with_flips, the flip round) an edge blocked
// only by its new vertex's valence first flips edges at its endpoints.
// Confined to a region (the two-thread phases), the loop collapses only
// edges inside it (CollapseMesh::collapse_inside, checked before any flip:
// then the flips, whose quads lie around the endpoints, stay inside too) and
// drops every other edge from its queue, for the serial loop that follows.
class CollapseLoop {
 public:
  static constexpr int kAnyRegion = -1;

  CollapseLoop(CollapseMesh& mesh, BucketQueue& queue, const SimplifyOptions& options, bool with_flips, int lane,
               int region)
      : mesh_(mesh),
        queue_(queue),
        options_(options),
        with_flips_(with_flips),
        lane_(lane),
        region_(region),
        cache_(lane),
        // The flip round stays eager: with stale priorities it made 65% more
        // failed flip attempts (miranda) for no gain in time.
        lazy_(options.lazy_stencil && !with_flips) {
    stencil_.reserve(128);
  }

  // Collapses until keep_going() is false or the queue is empty; calls
  // after_collapse() after each collapse. Batched by `batch_span` buckets
  // (EdgePops).
  template <typename KeepGoing, typename AfterCollapse>
  void run(std::uint32_t batch_span, const KeepGoing& keep_going, const AfterCollapse& after_collapse) {
    const std::uint32_t bucket_count = options_.bucket_count;
    EdgePops pops(queue_, batch_span);
    std::uint32_t e, least_bucket;
    while (keep_going() && pops.next(mesh_, e, least_bucket)) {
      Evaluation evaluation = mesh_.evaluate(e, cache_);
      flipped_.clear();
      if (with_flips_ && evaluation.legality == Legality::NewVertexValence) {
        if (!collapses_here(e)) continue;
        evaluation = flip_for(e);
        if (evaluation.legality != Legality::Legal) continue;
      }
      if (evaluation.legality != Legality::Legal) {
        ++counters.rejected[static_cast<int>(evaluation.legality)];
        continue;
      }
      if (flipped_.empty() && !collapses_here(e)) continue;
      mesh_.set_latest_delta_error(e, evaluation.delta_error);
      const std::uint32_t bucket = priority_bucket(mesh_.error(e), bucket_count);
      if (bucket < least_bucket) {  // its neighbourhood changed outside the stencil
        undo_flips();
        queue_.push(e, bucket);
        continue;
      }
      // The flipped edges' quads join the stencil centres.
      centres_.clear();
      for (std::uint32_t f : flipped_)
        for (std::uint32_t w : mesh_.edge_vertices(f)) centres_.push_back(w);
      counters.flips += flipped_.size();
      if (!flipped_.empty()) ++counters.collapses_after_flips;
      std::uint32_t removed[3], opposite_vertices[2];
      const std::uint32_t v = mesh_.collapse(e, evaluation.position, removed, opposite_vertices, lane_);
      ++counters.collapses;
      for (std::uint32_t dead : removed)
        if (dead != CollapseMesh::kNone && queue_.contains(dead)) queue_.remove(dead);
      centres_.insert(centres_.end(), {v, opposite_vertices[0], opposite_vertices[1]});
      stencil_.clear();
      mesh_.gather_stencil(centres_.data(), static_cast<int>(centres_.size()), stencil_, lane_);
      for (std::uint32_t s : stencil_) mesh_.prefetch_edge_vertices(s);
      for (std::uint32_t s : stencil_) update_stencil_edge(s, v);
      after_collapse();
    }
  }

  LoopCounters counters;

 private:
  bool confined() const { return region_ != kAnyRegion; }
  // Whether this loop may collapse e (with flips around its endpoints).
  bool collapses_here(std::uint32_t e) const {
    return !confined() || mesh_.collapse_inside(e, static_cast<std::uint8_t>(region_));
  }

  // Evaluation of a stencil edge: in the flip round, an edge blocked by the
  // new vertex's valence gets the priority it would have after flips.
  Evaluation evaluate_for_queue(std::uint32_t e) {
    Evaluation evaluation = mesh_.evaluate(e, cache_);
    if (with_flips_ && evaluation.legality == Legality::NewVertexValence)
      evaluation = mesh_.evaluate(e, cache_, options_.max_valence + kMaxFlipsPerCollapse);
    return evaluation;
  }

  // Lowers the endpoints' valences until the new vertex fits, then evaluates
  // e again; undoes the flips and counts a failed attempt if it is still
  // not legal.
  Evaluation flip_for(std::uint32_t e) {
    const auto [vi, vj, a, b] = mesh_.edge_vertices(e);
    const std::uint32_t keep[4] = {vi, vj, a, b};
    int excess = int(mesh_.valence(vi)) + int(mesh_.valence(vj)) - (b == CollapseMesh::kNone ? 3 : 4) -
                 options_.max_valence;
    // Most attempts cannot flip enough: a bound on the flips available skips
    // them before flipping (flip round on miranda 2.0 -> 1.65 s). Not exact
    // (a flip can free a neighbouring edge), so now and then it skips an
    // attempt that would have worked: 51 of 14,016 collapses.
    if (mesh_.flip_capacity(vi, keep, 4) + mesh_.flip_capacity(vj, keep, 4) < excess) {
      ++counters.flip_attempts_failed;
      return Evaluation{};
    }
    for (std::uint32_t endpoint : {vi, vj})
      if (excess > 0) excess -= mesh_.lower_valence(endpoint, excess, keep, 4, flipped_, lane_);
    const Evaluation evaluation = excess > 0 ? Evaluation{} : mesh_.evaluate(e, cache_);
    if (evaluation.legality != Legality::Legal) {
      ++counters.flip_attempts_failed;
      undo_flips();
    }
    return evaluation;
  }

  void undo_flips() {
    for (std::size_t k = flipped_.size(); k-- > 0;) mesh_.flip(flipped_[k], lane_);
    counters.flips_undone += flipped_.size();
    flipped_.clear();
  }

  // The update of stencil edge s after a collapse made vertex v. Outside the
  // region: out of this loop's queue. Eager (the paper): evaluate and
  // requeue. Lazy (SimplifyOptions::lazy_stencil): only an edge at v is
  // evaluated; another keeps its place in the queue, or, if it is not
  // queued, comes back at its last priority when the vertex rules admit it;
  // it is evaluated when popped.
  void update_stencil_edge(std::uint32_t s, std::uint32_t v) {
    const std::uint32_t bucket_count = options_.bucket_count;
    const std::uint32_t h = mesh_.edge_halfedge(s), origin = mesh_.origin(h), target = mesh_.target(h);
    if (confined() && (mesh_.region(origin) != region_ || mesh_.region(target) != region_)) {
      if (queue_.contains(s)) queue_.remove(s);
      return;
    }
    // An edge at v: its E_acc rose and its ring changed, so it is evaluated
    // at once even when lazy. Waiting until popped (at the bound E_acc + 1e-8
    // on its E) saved 0.45 s of the miranda two-thread phase but left the
    // mixing field's fit with 0.44% of its faces folded instead of 0.33%
    // (bases of 2,200-2,600 vertices), its surface max 0.9-1.7 cells instead
    // of 0.65, and miranda's Table 1 rows 0.1-0.5% of a cell higher.
    if (!lazy_ || origin == v || target == v)
      requeue(queue_, mesh_, s, evaluate_for_queue(s), bucket_count);
    else if (!queue_.contains(s) && mesh_.vertex_rules(s, options_.max_valence) == Legality::Legal)
      queue_.push(s, priority_bucket(mesh_.error(s), bucket_count));
  }


  CollapseMesh& mesh_;
  BucketQueue& queue_;
  const SimplifyOptions& options_;
  const bool with_flips_;
  const int lane_, region_;
  FanCache cache_;
  const bool lazy_;
  std::vector<std::uint32_t> stencil_, flipped_, centres_;
};

// The edges a pass looks at, in id order: every slot at first; once the
// first two-thread phase has deleted most edges, the ones then alive (later
// deletions are skipped: no collapse or flip makes a new edge id), so that
// later passes do not scan a few million dead slots each.
class EdgeList {
 public:
  explicit EdgeList(std::uint32_t slots) : slots_(slots) {}
  std::uint32_t size() const { return listed_ ? static_cast<std::uint32_t>(ids_.size()) : slots_; }
  std::uint32_t operator[](std::uint32_t k) const { return listed_ ? ids_[k] : k; }
  void keep_alive(const CollapseMesh& mesh) {
    std::vector<std::uint32_t> alive;
    for (std::uint32_t k = 0; k < size(); ++k)
      if (mesh.edge_alive((*this)[k])) alive.push_back((*this)[k]);
    ids_.swap(alive);
    listed_ = true;
  }

 private:
  std::uint32_t slots_;
  bool listed_ = false;
  std::vector<std::uint32_t> ids_;
};

// Two-thread phases of the collapse (SimplifyOptions::parallel): the paper's
// rules first, later the flip round (with_flips). The vertices (in Morton
// order, so each half is a compact part of space) are split in two halves;
// the vertices within two edges of an edge joining the halves form a band
// that nobody collapses. Each half runs a CollapseLoop on its own queue, in
// its own CollapseMesh lane, confined to its half, so the two threads never
// write what the other reads: collapses and flips never join band vertices,
// so the band keeps the halves two edges apart throughout. Boundary edges,
// and edges that reach the band, wait for the serial loop that follows.
// Each half's sequence depends only on its own half and the unchanging band,
// so the result does not depend on thread timing. `initial_buckets[k]`: the
// priority bucket of edges[k] (kNotQueued if not legal). Returns whether
// both loops emptied their queues (rather than stopping at their quota).
bool collapse_in_parallel(CollapseMesh& mesh, const EdgeList& edges, const std::vector<std::uint32_t>& initial_buckets,
                          std::size_t target, const SimplifyOptions& options, bool with_flips,
                          SimplifyReport& report) {
  using Range = tbb::blocked_range<std::uint32_t>;
  const std::uint32_t vertex_slots = mesh.vertex_slots();
  const auto endpoints = [&](std::uint32_t e) {
    const std::uint32_t h = mesh.edge_halfedge(e);
    return std::pair<std::uint32_t, std::uint32_t>{mesh.origin(h), mesh.target(h)};
  };
  const std::uint32_t half = vertex_slots / 2;
  // The band: breadth-first from the cut vertices (the endpoints of the edges
  // joining the halves), two rings out.
  tbb::enumerable_thread_specific<std::vector<std::uint32_t>> cut_parts;
  const std::uint32_t edge_count = edges.size();
  tbb::parallel_for(Range(0, edge_count, 1 << 16), [&](const Range& range) {
    std::vector<std::uint32_t>& part = cut_parts.local();
    for (std::uint32_t k = range.begin(); k != range.end(); ++k) {
      const std::uint32_t e = edges[k];
      if (!mesh.edge_alive(e)) continue;
      const auto [u, w] = endpoints(e);
      if ((u < half) != (w < half)) part.insert(part.end(), {u, w});
    }
  });
  std::vector<std::uint8_t> distance(vertex_slots, kBand);  // edges to the nearest cut vertex, up to 2
  std::vector<std::uint32_t> frontier, next_frontier, neighbours;
  for (const std::vector<std::uint32_t>& part : cut_parts)
    for (std::uint32_t v : part)
      if (distance[v] != 0) {
        distance[v] = 0;
        frontier.push_back(v);
      }
  for (std::uint8_t ring = 1; ring <= 2; ++ring) {
    next_frontier.clear();
    for (std::uint32_t v : frontier) {
      neighbours.clear();
      mesh.append_neighbours(v, neighbours);
      for (std::uint32_t w : neighbours)
        if (distance[w] > ring) {
          distance[w] = ring;
          next_frontier.push_back(w);
        }
    }
    frontier.swap(next_frontier);
  }
  std::array<std::atomic<std::size_t>, CollapseMesh::kLanes> region_vertices{};
  tbb::parallel_for(Range(0, vertex_slots, 1 << 16), [&](const Range& range) {
    std::size_t counts[CollapseMesh::kLanes] = {0, 0};
    for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
      const std::uint8_t region = distance[v] <= 2 ? kBand : (v < half ? 0 : 1);
      mesh.set_region(v, region);
      if (region != kBand && mesh.vertex_alive(v)) ++counts[region];
    }
    for (int lane = 0; lane < CollapseMesh::kLanes; ++lane) region_vertices[lane] += counts[lane];
  });
  // Each half's initial edges, chosen before the threads start: once one
  // collapses, the other must not look at its edges.
  std::vector<std::uint8_t> edge_region(edge_count, kBand);
  tbb::parallel_for(Range(0, edge_count, 1 << 16), [&](const Range& range) {
    for (std::uint32_t k = range.begin(); k != range.end(); ++k) {
      if (initial_buckets[k] == BucketQueue::kNotQueued) continue;
      const auto [u, w] = endpoints(edges[k]);
      if (mesh.region(u) == mesh.region(w)) edge_region[k] = mesh.region(u);
    }
  });
  const std::size_t alive = mesh.alive_vertices();
  const std::size_t planned = alive > target ? alive - target : 0;

  const std::uint32_t bucket_count = options.bucket_count;
  const std::uint32_t batch_span = priority_bucket_span(options.batch_error_factor, bucket_count);
  std::array<LoopCounters, CollapseMesh::kLanes> counters;
  std::array<bool, CollapseMesh::kLanes> emptied{};
  const auto run_lane = [&](int lane) {
    // 90% of its share of the planned collapses, so that where it stops does
    // not depend on the other thread, and the last, costliest collapses go to
    // the serial loop in global priority order: with the whole share, a half
    // short of cheap edges was forced into expensive ones (engine CT at 1.7%:
    // base-mesh RMSE 103% of a cell; 43% with 90%, as serially).
    const std::size_t quota = static_cast<std::size_t>(kParallelShare * double(planned) *
                                                       double(region_vertices[lane].load()) /
                                                       double(std::max<std::size_t>(alive, 1)));
    // The two queues hold disjoint edges: they share the links in the edge
    // records, which an emptied queue leaves as it found them.
    BucketQueue queue(mesh.queue_links(), CollapseMesh::queue_link_stride(), mesh.edge_slots(), bucket_count);
    for (std::uint32_t k = 0; k < edge_count; ++k)
      if (edge_region[k] == lane) queue.push(edges[k], initial_buckets[k]);
    CollapseLoop loop(mesh, queue, options, with_flips, lane, lane);
    loop.run(batch_span, [&] { return loop.counters.collapses < quota; }, [] {});
    counters[lane] = loop.counters;
    emptied[lane] = queue.empty() && loop.counters.collapses < quota;
    while (!queue.empty()) queue.pop();  // for the serial queue
  };
  tbb::parallel_invoke([&] { run_lane(0); }, [&] { run_lane(1); });
  for (const LoopCounters& lane : counters) {
    lane.add_to(report);
    report.parallel_collapses += lane.collapses;
    if (with_flips) report.parallel_flip_round_collapses += lane.collapses;
  }
  return emptied[0] && emptied[1];
}

// After collapse_in_parallel: whether its loops had to leave edge e to the
// serial loop (an edge inside a half is, when its loop emptied its queue,
// either collapsed or as illegal as a serial loop would find it).
bool left_by_two_threads(const CollapseMesh& mesh, std::uint32_t e) {
  const std::uint8_t region = mesh.region(mesh.origin(mesh.edge_halfedge(e)));
  return region == kBand || !mesh.collapse_inside(e, region);
}

// Face-size and valence histograms of the output.
void fill_histograms(const PolygonMesh& mesh, int max_valence, SimplifyReport& report) {
  report.face_size_histogram.clear();
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::size_t size = mesh.face_size(f);
    if (report.face_size_histogram.size() <= size) report.face_size_histogram.resize(size + 1, 0);
    ++report.face_size_histogram[size];
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(mesh.face_vertices.size());
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* face = mesh.face_begin(f);
    const std::uint32_t size = mesh.face_size(f);
    for (std::uint32_t k = 0; k < size; ++k) {
      const std::uint32_t u = face[k], w = face[(k + 1) % size];
      edges.emplace_back(std::min(u, w), std::max(u, w));
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::uint32_t> valence(mesh.vertex_count(), 0);
  std::vector<std::uint8_t> boundary(mesh.vertex_count(), 0);
  std::size_t unique_edges = 0;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    ++unique_edges;
    ++valence[edges[i].first];
    ++valence[edges[i].second];
    if (j - i == 1) boundary[edges[i].first] = boundary[edges[i].second] = 1;
    i = j;
  }
  report.output_edges = unique_edges;
  report.valence_histogram.clear();
  report.vertices_outside_valence_range = 0;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    if (report.valence_histogram.size() <= valence[v]) report.valence_histogram.resize(valence[v] + 1, 0);
    ++report.valence_histogram[valence[v]];
    const std::uint32_t low = boundary[v] ? 2 : 3;
    if (valence[v] < low || valence[v] > static_cast<std::uint32_t>(max_valence)) ++report.vertices_outside_valence_range;
  }
}

}  // namespace

SimplifyResult simplify(const PolygonMesh& input, const SimplifyOptions& options, ProgressSink& progress) {
  check_options(options);
  SimplifyResult result;
  SimplifyReport& report = result.report;
  Clock::time_point clock = Clock::now();

  // Input checks (Error for anything wrong with the data).
  const std::string source = "simplify input";
  validate_indices(input, source);
  for (std::size_t f = 0; f < input.face_count(); ++f)
    if (input.face_size(f) != 3)
      throw Error(ErrorKind::Unsupported, source + ": face " + std::to_string(f) + " has " +
                                              std::to_string(input.face_size(f)) +
                                              " sides; base-mesh construction needs a triangle mesh");
  if (input.vertex_count() >= (std::size_t{1} << 31) || input.face_vertices.size() >= (std::size_t{1} << 31))
    throw Error(ErrorKind::Unsupported, source + ": more than 2^31 vertices or corners");
  report.input_vertices = input.vertex_count();
  report.input_faces = input.face_count();
  report.seconds_check = seconds_since(clock);

  // Corner table and input topology.
  progress.begin_stage("simplify: build");
  CollapseRules rules;
  rules.max_valence = options.max_valence;
  rules.min_normal_dot = options.collapse_min_normal_dot;
  rules.boundary_curve_error = options.boundary_curve_error;
  rules.flip_min_normal_dot = options.flip_min_normal_dot;
  CollapseMesh mesh = build_table(input, rules, source);
  if (options.valence_flips) {
    // Input vertices above the valence limit (marching cubes makes a few of
    // valence 9..12) would stay so: no collapse may touch them.
    std::vector<std::uint32_t> flipped;
    for (std::uint32_t v = 0; v < mesh.vertex_slots(); ++v) {
      const int excess = mesh.vertex_alive(v) ? int(mesh.valence(v)) - options.max_valence : 0;
      if (excess > 0) mesh.lower_valence(v, excess, nullptr, 0, flipped);
    }
    report.input_valence_flips = flipped.size();
    if (options.validate_every_collapse && !mesh.validate().empty())
      throw std::logic_error("simplify: invariant broken by the input flips: " + mesh.validate());
  }
  for (const CollapseMesh::ComponentCounts& counts : mesh.components()) {
    ++report.input_components;
    report.input_boundary_loops += counts.boundary_loops;
    report.input_genus += counts.genus();
    report.lower_bound_vertices += component_lower_bound(counts);
  }
  progress.end_stage();
  report.seconds_build = seconds_since(clock);

  // Priorities of the listed edges, evaluated in parallel (evaluate() only
  // reads): bucket k for edges[k]. Callers queue them in edge order so that
  // the FIFO order is deterministic.
  const std::uint32_t bucket_count = options.bucket_count;
  EdgeList edges(mesh.edge_slots());
  const auto every_edge = [](std::uint32_t) { return true; };
  const auto evaluate_edges = [&](int max_valence, const auto& selected) {
    std::vector<std::uint32_t> buckets;
    reserve_fresh_on_huge_pages(buckets, edges.size());
    buckets.resize(edges.size(), BucketQueue::kNotQueued);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, edges.size(), 8192),
                      [&](const tbb::blocked_range<std::uint32_t>& range) {
                        FanCache cache;
                        for (std::uint32_t k = range.begin(); k != range.end(); ++k) {
                          const std::uint32_t e = edges[k];
                          if (!mesh.edge_alive(e) || !selected(e)) continue;
                          const Evaluation evaluation = mesh.evaluate(e, cache, max_valence);
                          if (evaluation.legality != Legality::Legal) continue;
                          mesh.set_latest_delta_error(e, evaluation.delta_error);
                          buckets[k] = priority_bucket(mesh.error(e), bucket_count);
                        }
                      });
    return buckets;
  };
  BucketQueue queue(mesh.queue_links(), CollapseMesh::queue_link_stride(), mesh.edge_slots(), bucket_count);
  const auto queue_edges = [&](int max_valence, const auto& selected) {
    const std::vector<std::uint32_t> buckets = evaluate_edges(max_valence, selected);
    for (std::uint32_t k = 0; k < edges.size(); ++k)
      if (buckets[k] != BucketQueue::kNotQueued) queue.push(edges[k], buckets[k]);
  };
  report.target_vertices = std::min(options.target_vertices, input.vertex_count());
  const bool collapse_wanted = options.target_vertices < input.vertex_count();
  const bool in_parallel = collapse_wanted && options.parallel && input.vertex_count() >= options.parallel_min_vertices;
  progress.begin_stage("simplify: queue");
  std::vector<std::uint32_t> initial_buckets;
  if (in_parallel) initial_buckets = evaluate_edges(options.max_valence, every_edge);
  else if (collapse_wanted) queue_edges(options.max_valence, every_edge);
  progress.end_stage();
  report.seconds_queue = seconds_since(clock);

  // Collapse loop. First the paper's rules alone; when they stall, a second
  // round in which an edge blocked only by the valence of its new vertex may
  // first flip edges at its endpoints (see SimplifyOptions::valence_flips).
  // Each on two threads first, when in_parallel, then serially.
  progress.begin_stage("simplify: collapse");
  const std::size_t target = report.target_vertices;
  const std::size_t planned = input.vertex_count() - target;
  const int relaxed_valence = options.max_valence + kMaxFlipsPerCollapse;
  // The paper's rules in its order (batched, the miranda base mesh came out
  // 5% farther from the input); the flip round in batches (SimplifyOptions::
  // batch_error_factor).
  const auto run_serial_loop = [&](bool with_flips) {
    CollapseLoop loop(mesh, queue, options, with_flips, 0, CollapseLoop::kAnyRegion);
    std::size_t collapses = report.collapses;
    loop.run(
        with_flips ? priority_bucket_span(options.batch_error_factor, bucket_count) : 0,
        [&] { return mesh.alive_vertices() > target; },
        [&] {
          ++collapses;
          if (options.validate_every_collapse) {
            const std::string problem = mesh.validate();
            if (!problem.empty())
              throw std::logic_error("simplify: invariant broken after collapse " + std::to_string(collapses) + ": " +
                                     problem);
          }
          if ((collapses & 0xFFFF) == 0) progress.update(double(collapses) / double(planned));
        });
    loop.counters.add_to(report);
  };
  const auto collapse_on_two_threads = [&](std::vector<std::uint32_t> buckets, bool with_flips) {
    const bool emptied =
        collapse_in_parallel(mesh, edges, buckets, report.target_vertices, options, with_flips, report);
    if (options.validate_every_collapse && !mesh.validate().empty())
      throw std::logic_error("simplify: invariant broken by the parallel collapses: " + mesh.validate());
    return emptied;
  };
  // After a two-thread phase: when both loops emptied their queues, the
  // serial loop takes only the edges they had to leave, else every edge.
  const auto queue_after_two_threads = [&](int max_valence, bool emptied) {
    if (emptied)
      queue_edges(max_valence, [&](std::uint32_t e) { return left_by_two_threads(mesh, e); });
    else
      queue_edges(max_valence, every_edge);
  };
  if (in_parallel) {
    const bool emptied = collapse_on_two_threads(std::move(initial_buckets), false);
    edges.keep_alive(mesh);
    queue_after_two_threads(options.max_valence, emptied);
    report.seconds_parallel = seconds_since_start(clock);
  }
  if (options.serial_phase_begins) options.serial_phase_begins();
  if (collapse_wanted) {
    run_serial_loop(false);
    report.vertices_after_paper_collapse = mesh.alive_vertices();
    report.seconds_flip_rounds = -seconds_since_start(clock);
    // Flip rounds: queue every edge the relaxed valence rule admits, in edge
    // order; an edge whose flips failed waits for the next round unless a
    // later collapse re-evaluates it. Stop when a round gains under 1%.
    bool gained = true;
    while (options.valence_flips && gained && report.flip_rounds < std::size_t(options.max_flip_rounds) &&
           mesh.alive_vertices() > target) {
      const std::size_t before = mesh.alive_vertices();
      ++report.flip_rounds;
      queue_after_two_threads(relaxed_valence,
                              in_parallel && collapse_on_two_threads(evaluate_edges(relaxed_valence, every_edge), true));
      run_serial_loop(true);
      gained = before - mesh.alive_vertices() > before / 100;
    }
    report.seconds_flip_rounds += seconds_since_start(clock);
  }
  report.vertices_after_collapse = mesh.alive_vertices();
  report.triangles_after_collapse = mesh.alive_triangles();
  report.target_reached = mesh.alive_vertices() <= target;
  if (!collapse_wanted)
    report.stop_reason = "target at or above the input vertex count: no collapse";
  else if (report.target_reached)
    report.stop_reason = "target reached";
  else
    report.stop_reason = "no legal collapse remains (" + std::to_string(mesh.alive_vertices()) +
                         " vertices; the rules allow at best " + std::to_string(report.lower_bound_vertices) + ")";
  progress.end_stage();
  report.seconds_collapse = seconds_since(clock);

  // Edge removal.
  result.base = mesh.to_polygon_mesh();
  {
    // Free the corner table before the polygon phase.
    CollapseMesh released = std::move(mesh);
  }
  if (options.edge_removal) {
    progress.begin_stage("simplify: edge removal");
    report.edges_removed = remove_edges(result.base, options.edge_removal_min_normal_dot);
    progress.end_stage();
  }
  report.seconds_edge_removal = seconds_since(clock);

  report.output_vertices = result.base.vertex_count();
  report.output_faces = result.base.face_count();
  fill_histograms(result.base, options.max_valence, report);
  report.seconds_output = seconds_since(clock);

  if (options.compute_distance) {
    progress.begin_stage("simplify: distance");
    const std::vector<double> distances = BinnedSurfaceDistance(result.base).distances(input.positions);
    double sum = 0;
    for (double d : distances) {
      sum += d * d;
      report.distance_max = std::max(report.distance_max, d);
    }
    report.distance_computed = true;
    report.distance_rms = distances.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(distances.size()));
    progress.end_stage();
    report.seconds_distance = seconds_since(clock);
  }
  return result;
}

std::string format_report(const SimplifyReport& r) {
  std::string out;
  char line[512];
  const auto add = [&](const char* format, auto... values) {
    std::snprintf(line, sizeof line, format, values...);
    out += line;
  };
  add("input: %zu vertices, %zu triangles, %zu components, genus %lld, %zu boundary loops\n", r.input_vertices,
      r.input_faces, r.input_components, r.input_genus, r.input_boundary_loops);
  add("target: %zu vertices (lower bound from topology and valence <= 8: %zu)\n", r.target_vertices,
      r.lower_bound_vertices);
  if (r.input_valence_flips) add("input: %zu flips to bring valences down to the limit\n", r.input_valence_flips);
  add("collapse: %zu collapses -> %zu vertices, %zu triangles; %s\n", r.collapses, r.vertices_after_collapse,
      r.triangles_after_collapse, r.stop_reason.c_str());
  if (r.parallel_collapses)
    add("parallel: %zu collapses on two threads inside two halves of the mesh (%zu of them in the flip rounds), "
        "the rest serial; %.3f s before the first serial loop\n",
        r.parallel_collapses, r.parallel_flip_round_collapses, r.seconds_parallel);
  if (r.collapses_after_flips)
    add("valence flips: the paper's rules stalled at %zu vertices; %zu rounds, %zu more collapses after %zu flips "
        "(%zu flips undone in %zu failed attempts)\n",
        r.vertices_after_paper_collapse, r.flip_rounds, r.collapses_after_flips, r.flips, r.flips_undone,
        r.flip_attempts_failed);
  std::string rejected;
  for (int k = 1; k < kLegalityCount; ++k)
    if (r.rejected_at_pop[k]) rejected += std::string(rejected.empty() ? "" : ", ") + to_string(Legality(k)) + " " +
                                          std::to_string(r.rejected_at_pop[k]);
  if (!rejected.empty()) add("rejected when popped: %s\n", rejected.c_str());
  add("edge removal: %zu edges removed\n", r.edges_removed);
  add("base mesh: %zu vertices, %zu edges, %zu faces\n", r.output_vertices, r.output_edges, r.output_faces);
  std::string sizes;
  for (std::size_t s = 0; s < r.face_size_histogram.size(); ++s)
    if (r.face_size_histogram[s]) sizes += " " + std::to_string(s) + ":" + std::to_string(r.face_size_histogram[s]);
  add("face sizes:%s\n", sizes.c_str());
  std::string valences;
  for (std::size_t k = 0; k < r.valence_histogram.size(); ++k)
    if (r.valence_histogram[k]) valences += " " + std::to_string(k) + ":" + std::to_string(r.valence_histogram[k]);
  add("valences:%s (%zu outside 3..8 / 2..8 on the boundary)\n", valences.c_str(), r.vertices_outside_valence_range);
  if (r.distance_computed)
    add("distance input vertices -> base surface: max %.6g, rms %.6g\n", r.distance_max, r.distance_rms);
  add("time: check %.3f s, build %.3f s, queue %.3f s, collapse %.3f s (%.3f s of it in flip rounds), edge removal %.3f s, output %.3f s, "
      "distance %.3f s, total %.3f s\n",
      r.seconds_check, r.seconds_build, r.seconds_queue, r.seconds_collapse, r.seconds_flip_rounds, r.seconds_edge_removal, r.seconds_output,
      r.seconds_distance, r.seconds_total());
  return out;
}

}  // namespace isowave::simplify
