// The collapse loops of base-mesh construction (paper Sec. 4.1): the
// priority queue of all legal edges, the serial loop in the paper's order,
// the two-thread phases (SimplifyOptions::parallel) and the flip rounds
// (SimplifyOptions::valence_flips).
#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "isowave/core/huge_page_vector.h"
#include "isowave/simplify/bucket_queue.h"
#include "isowave/simplify/collapse_error.h"
#include "simplify_steps.h"

namespace isowave::simplify {

namespace {

// The flip round lowers the endpoints' valences by at most this many flips.
constexpr int kMaxFlipsPerCollapse = 4;
constexpr double kParallelShare = 0.9;  // see collapse_in_parallel
constexpr std::uint8_t kBand = 255;     // region of the vertices no thread collapses

// Which rules a collapse loop applies: the paper's alone, or with an edge
// blocked only by its new vertex's valence first flipping edges at its
// endpoints (SimplifyOptions::valence_flips).
enum class CollapseRound { PaperRules, ValenceFlips };

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

static_assert(std::tuple_size_v<decltype(SimplifyReport::rejected_at_pop)> == kLegalityCount,
              "SimplifyReport::rejected_at_pop holds one count per Legality");

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
// Fig. 8 stencil. In the flip round (CollapseRound::ValenceFlips) an edge blocked
// only by its new vertex's valence first flips edges at its endpoints.
// Confined to a region (the two-thread phases), the loop collapses only
// edges inside it (CollapseMesh::collapse_inside, checked before any flip:
// then the flips, whose quads lie around the endpoints, stay inside too) and
// drops every other edge from its queue, for the serial loop that follows.
class CollapseLoop {
 public:
  static constexpr int kAnyRegion = -1;

  CollapseLoop(CollapseMesh& mesh, BucketQueue& queue, const SimplifyOptions& options, CollapseRound round, int lane,
               int region)
      : mesh_(mesh),
        queue_(queue),
        options_(options),
        with_flips_(round == CollapseRound::ValenceFlips),
        lane_(lane),
        region_(region),
        cache_(lane),
        // The flip round stays eager: with stale priorities it makes many
        // more failed flip attempts for no gain in time.
        lazy_(options.lazy_stencil && !with_flips_) {
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
    // them before flipping. Not exact (a flip can free a neighbouring edge),
    // so now and then it skips an attempt that would have worked.
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
    // at once even when lazy (waiting until popped left the fitted surfaces
    // with more folded faces).
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
// rules first, later the flip round (CollapseRound::ValenceFlips). The vertices (in Morton
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
                          std::size_t target, const SimplifyOptions& options, CollapseRound round,
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
    // short of cheap edges is forced into expensive ones.
    const std::size_t quota = static_cast<std::size_t>(kParallelShare * double(planned) *
                                                       double(region_vertices[lane].load()) /
                                                       double(std::max<std::size_t>(alive, 1)));
    // The two queues hold disjoint edges: they share the links in the edge
    // records, which an emptied queue leaves as it found them.
    BucketQueue queue(mesh.queue_links(), CollapseMesh::queue_link_stride(), mesh.edge_slots(), bucket_count);
    for (std::uint32_t k = 0; k < edge_count; ++k)
      if (edge_region[k] == lane) queue.push(edges[k], initial_buckets[k]);
    CollapseLoop loop(mesh, queue, options, round, lane, lane);
    loop.run(batch_span, [&] { return loop.counters.collapses < quota; }, [] {});
    counters[lane] = loop.counters;
    emptied[lane] = queue.empty() && loop.counters.collapses < quota;
    while (!queue.empty()) queue.pop();  // for the serial queue
  };
  tbb::parallel_invoke([&] { run_lane(0); }, [&] { run_lane(1); });
  for (const LoopCounters& lane : counters) {
    lane.add_to(report);
    report.parallel_collapses += lane.collapses;
    if (round == CollapseRound::ValenceFlips) report.parallel_flip_round_collapses += lane.collapses;
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

// The queue and the loops of one simplify() run over one corner table.
class CollapsePhases {
 public:
  CollapsePhases(CollapseMesh& mesh, const SimplifyOptions& options, SimplifyReport& report, ProgressSink& progress)
      : mesh_(mesh),
        options_(options),
        report_(report),
        progress_(progress),
        edges_(mesh.edge_slots()),
        queue_(mesh.queue_links(), CollapseMesh::queue_link_stride(), mesh.edge_slots(), options.bucket_count) {}

  // Priorities of the listed edges that `selected` admits, evaluated in
  // parallel (evaluate() only reads): bucket k for edges[k]. Callers queue
  // them in edge order so that the FIFO order is deterministic.
  template <typename Selected>
  std::vector<std::uint32_t> evaluate_edges(int max_valence, const Selected& selected) const {
    const std::uint32_t bucket_count = options_.bucket_count;
    std::vector<std::uint32_t> buckets;
    reserve_fresh_on_huge_pages(buckets, edges_.size());
    buckets.resize(edges_.size(), BucketQueue::kNotQueued);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, edges_.size(), 8192),
                      [&](const tbb::blocked_range<std::uint32_t>& range) {
                        FanCache cache;
                        for (std::uint32_t k = range.begin(); k != range.end(); ++k) {
                          const std::uint32_t e = edges_[k];
                          if (!mesh_.edge_alive(e) || !selected(e)) continue;
                          const Evaluation evaluation = mesh_.evaluate(e, cache, max_valence);
                          if (evaluation.legality != Legality::Legal) continue;
                          mesh_.set_latest_delta_error(e, evaluation.delta_error);
                          buckets[k] = priority_bucket(mesh_.error(e), bucket_count);
                        }
                      });
    return buckets;
  }
  std::vector<std::uint32_t> evaluate_every_edge(int max_valence) const {
    return evaluate_edges(max_valence, [](std::uint32_t) { return true; });
  }

  template <typename Selected>
  void queue_edges(int max_valence, const Selected& selected) {
    const std::vector<std::uint32_t> buckets = evaluate_edges(max_valence, selected);
    for (std::uint32_t k = 0; k < edges_.size(); ++k)
      if (buckets[k] != BucketQueue::kNotQueued) queue_.push(edges_[k], buckets[k]);
  }
  void queue_every_edge(int max_valence) {
    queue_edges(max_valence, [](std::uint32_t) { return true; });
  }

  // The paper's rules in its order (batched, the base mesh comes out farther
  // from the input); the flip round in batches
  // (SimplifyOptions::batch_error_factor).
  void run_serial_loop(CollapseRound round) {
    const std::size_t target = report_.target_vertices;
    const std::size_t planned = report_.input_vertices - target;
    CollapseLoop loop(mesh_, queue_, options_, round, 0, CollapseLoop::kAnyRegion);
    std::size_t collapses = report_.collapses;
    loop.run(
        round == CollapseRound::ValenceFlips ? priority_bucket_span(options_.batch_error_factor, options_.bucket_count)
                                             : 0,
        [&] { return mesh_.alive_vertices() > target; },
        [&] {
          ++collapses;
          if (options_.validate_every_collapse) {
            const std::string problem = mesh_.validate();
            if (!problem.empty())
              throw std::logic_error("simplify: invariant broken after collapse " + std::to_string(collapses) + ": " +
                                     problem);
          }
          if ((collapses & 0xFFFF) == 0) progress_.update(double(collapses) / double(planned));
        });
    loop.counters.add_to(report_);
  }

  // Whether both threads emptied their queues (see collapse_in_parallel).
  bool collapse_on_two_threads(std::vector<std::uint32_t> buckets, CollapseRound round) {
    const bool emptied =
        collapse_in_parallel(mesh_, edges_, buckets, report_.target_vertices, options_, round, report_);
    if (options_.validate_every_collapse && !mesh_.validate().empty())
      throw std::logic_error("simplify: invariant broken by the parallel collapses: " + mesh_.validate());
    return emptied;
  }

  // After a two-thread phase: when both loops emptied their queues, the
  // serial loop takes only the edges they had to leave, else every edge.
  void queue_after_two_threads(int max_valence, bool emptied) {
    if (emptied)
      queue_edges(max_valence, [&](std::uint32_t e) { return left_by_two_threads(mesh_, e); });
    else
      queue_every_edge(max_valence);
  }

  // Drops the dead edges from the list once the first two-thread phase has
  // deleted most of them.
  void keep_alive_edges() { edges_.keep_alive(mesh_); }

 private:
  CollapseMesh& mesh_;
  const SimplifyOptions& options_;
  SimplifyReport& report_;
  ProgressSink& progress_;
  EdgeList edges_;
  BucketQueue queue_;
};

// Why collapsing stopped, for the report.
std::string stop_reason(bool collapse_wanted, const CollapseMesh& mesh, const SimplifyReport& report) {
  if (!collapse_wanted) return "target at or above the input vertex count: no collapse";
  if (report.target_reached) return "target reached";
  return "no legal collapse remains (" + std::to_string(mesh.alive_vertices()) + " vertices; the rules allow at best " +
         std::to_string(report.lower_bound_vertices) + ")";
}

}  // namespace

void collapse_to_target(CollapseMesh& mesh, const SimplifyOptions& options, SimplifyReport& report,
                        ProgressSink& progress, Clock::time_point& clock) {
  const std::size_t input_vertices = report.input_vertices;
  report.target_vertices = std::min(options.target_vertices, input_vertices);
  const bool collapse_wanted = options.target_vertices < input_vertices;
  const bool in_parallel = collapse_wanted && options.parallel && input_vertices >= options.parallel_min_vertices;
  CollapsePhases phases(mesh, options, report, progress);
  progress.begin_stage("simplify: queue");
  std::vector<std::uint32_t> initial_buckets;
  if (in_parallel) initial_buckets = phases.evaluate_every_edge(options.max_valence);
  else if (collapse_wanted) phases.queue_every_edge(options.max_valence);
  progress.end_stage();
  report.seconds_queue = seconds_since(clock);

  // First the paper's rules alone; when they stall, rounds in which an edge
  // blocked only by the valence of its new vertex may first flip edges at
  // its endpoints. Each on two threads first, when in_parallel, then serially.
  progress.begin_stage("simplify: collapse");
  const std::size_t target = report.target_vertices;
  const int relaxed_valence = options.max_valence + kMaxFlipsPerCollapse;
  if (in_parallel) {
    const bool emptied = phases.collapse_on_two_threads(std::move(initial_buckets), CollapseRound::PaperRules);
    phases.keep_alive_edges();
    phases.queue_after_two_threads(options.max_valence, emptied);
    report.seconds_parallel = seconds_since_start(clock);
  }
  if (options.serial_phase_begins) options.serial_phase_begins();
  if (collapse_wanted) {
    phases.run_serial_loop(CollapseRound::PaperRules);
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
      phases.queue_after_two_threads(
          relaxed_valence, in_parallel && phases.collapse_on_two_threads(phases.evaluate_every_edge(relaxed_valence),
                                                                         CollapseRound::ValenceFlips));
      phases.run_serial_loop(CollapseRound::ValenceFlips);
      gained = before - mesh.alive_vertices() > before / 100;
    }
    report.seconds_flip_rounds += seconds_since_start(clock);
  }
  report.vertices_after_collapse = mesh.alive_vertices();
  report.triangles_after_collapse = mesh.alive_triangles();
  report.target_reached = mesh.alive_vertices() <= target;
  report.stop_reason = stop_reason(collapse_wanted, mesh, report);
  progress.end_stage();
  report.seconds_collapse = seconds_since(clock);
}

}  // namespace isowave::simplify
