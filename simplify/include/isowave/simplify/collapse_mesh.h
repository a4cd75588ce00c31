#pragma once
// Triangle mesh for the edge-collapse phase of base-mesh construction (paper
// Sec. 4.1): legality and error of a collapse, the collapse itself, and an
// invariant check. Exposed for tests; simplify() is the normal entry point.
//
// Representation: a corner table. Triangle t owns corners 3t, 3t+1, 3t+2;
// corner c is also the half-edge from the vertex of corner c to the vertex of
// the next corner of its triangle. Per corner we keep the opposite half-edge
// (or kNone on the boundary) and its edge id; per edge one half-edge, the
// accumulated error E_acc and the latest delta E. Flat arrays of small
// records (vertex 40 bytes, corner 12, so a triangle is 36 contiguous bytes,
// edge 32) indexed by vertex, corner or edge id: no per-element allocation
// for millions of elements, next/prev/face are arithmetic on the corner
// index, and the fields one evaluation reads of an element share a cache
// line (the collapse loop works at random places, so each array an element
// is spread over costs a miss). evaluate() with a FanCache gathers each
// vertex fan once per collapse instead of once per stencil edge.
//
// Deleted triangles, edges and vertices are only marked; to_polygon_mesh()
// compacts. Every operation is local: evaluate() and collapse() cost
// O(valence of the two endpoints).
//
// Files: collapse_table.cpp (construction), legality.cpp (the rules,
// evaluate), valence_flips.cpp (flips), collapse_mesh.cpp (collapse,
// stencil, validation, output).
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/simplify/bucket_queue.h"

namespace isowave::simplify {

// Why an edge may not collapse (first failing rule, in evaluation order).
enum class Legality : std::uint8_t {
  Legal,
  DeadEdge,
  BothEndpointsSharp,        // never collapse an edge with two sharp endpoints
  InteriorEdgeOnBoundary,    // an interior edge joining two boundary vertices
  BoundaryLoopMinimum,       // a boundary loop keeps at least 3 vertices
  NewVertexValence,          // N_i + N_j - 4 (boundary edge: - 3) outside 3..8 (2..8 on the boundary)
  OppositeVertexValence,     // a or b would drop below 3 (2 on the boundary)
  LinkCondition,             // Hoppe / Dey et al.: common neighbours must be exactly a, b
  NormalFlip,                // a ring triangle's normal turns beyond the threshold
  DegenerateTriangle,        // a ring triangle would get zero area
  AreaBudget,                // the new vertex would hold more surface than CollapseRules::max_vertex_area
};
const char* to_string(Legality legality);
constexpr int kLegalityCount = 11;

struct CollapseRules {
  int max_valence = 8;  // paper: valences 3..8 (2..8 on the boundary)
  // An edge flip (see CollapseMesh::flip) needs every pair of the old and new
  // triangles' unit normals to have a dot product >= this, so that it only
  // re-triangulates a nearly flat quad; in [-1, 1].
  double flip_min_normal_dot = 0.7;
  // A collapse is rejected when a surviving triangle's unit normal n_new has
  // dot(n_old, n_new) < min_normal_dot (Hoppe's face-flip test); 0 allows
  // turns up to 90 degrees.
  double min_normal_dot = 0.0;
  // See SimplifyOptions::boundary_curve_error.
  bool boundary_curve_error = true;
  // Not in the paper (0 reproduces it): each vertex holds a share of the
  // input's area (a third of each input triangle at its corners; a collapse
  // adds the removed vertex's to the survivor's), and a collapse whose new
  // vertex would hold more than this (squared length units) is illegal.
  double max_vertex_area = 0;
};

class CollapseMesh;
class SurfaceMapTracker;

// The fans of the vertices evaluate() has looked at: for each, its corners in
// counter-clockwise order, its ring of neighbours with their positions, and the
// cross product (w_t - v) x (w_{t+1} - v) of each current triangle (the "old"
// normal of the face-flip test). Evaluating the ~30 edges of one stencil
// would otherwise walk each fan (a chain of dependent loads) and recompute
// those cross products about five times. Valid while the mesh's version()
// does not change; evaluate() refills it as needed. Small (a few hundred
// fans at most, then it starts over), not thread-safe: one per thread.
class FanCache {
 public:
  // `lane`: see CollapseMesh::kLanes; the cache follows that lane's changes.
  explicit FanCache(int lane = 0);

 private:
  friend class CollapseMesh;
  struct Fan {
    std::uint32_t vertex;
    std::uint32_t begin;    // first entry in entries_
    std::uint32_t corners;  // corner count; the fan has corners + 1 entries
    std::uint64_t neighbours;  // bit (w % 64) set for each neighbour w: most link tests need no search
  };
  // Entry t of a fan around v: ring vertex t (the target of corner t; the
  // last entry closes the fan and has no triangle) and corner t's triangle
  // (v, ring t, ring t+1) with its cross product (ring t - v) x (ring t+1 - v).
  // One cache line; plain doubles so that the buffer is not zeroed.
  struct Entry {
    double x, y, z;
    double cross_x, cross_y, cross_z, cross_squared;
    std::uint32_t vertex, triangle;
  };
  static constexpr std::uint32_t kSlots = 512, kMaxFans = 256;
  static constexpr std::uint32_t kEntries = 1984;  // 124 KiB: below malloc's mmap threshold
  void clear(const CollapseMesh* mesh, std::uint64_t version);

  const CollapseMesh* mesh_ = nullptr;
  int lane_ = 0;
  std::uint64_t version_ = 0;
  std::uint32_t stamp_ = 0;
  // Open-addressing table vertex -> fan, valid where slot_stamp_ == stamp_.
  std::vector<std::uint32_t> slot_vertex_, slot_fan_, slot_stamp_;
  std::unique_ptr<Entry[]> entries_;
  std::uint32_t used_entries_ = 0;
  std::vector<Fan> fans_;
};

struct Evaluation {
  Legality legality = Legality::DeadEdge;
  bool geometry_computed = false;  // delta_error and position are valid
  double delta_error = 0;          // (4.2)
  Vec3 position;                   // the new vertex
};

class CollapseMesh {
 public:
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  // Lanes let threads collapse disjoint regions at once (see collapse_loops.cpp):
  // each has its own version, stamps and counts, so one lane never touches a
  // cache line the other writes. Lane l's collapses must stay inside its
  // region: collapse_inside() must hold for the edge.
  static constexpr int kLanes = 2;

  // Precondition: `mesh` is a triangle mesh with valid indices. Throws
  // Error(Topology) if it is not a consistently oriented 2-manifold without
  // unreferenced vertices (the checks of require_manifold(), done while the
  // table is built; call that for a message naming the problem).
  explicit CollapseMesh(const PolygonMesh& mesh, CollapseRules rules = {});
  // The same with the vertices renumbered: vertex k of the table is mesh
  // vertex vertex_order[k] (a permutation), and the triangles are ordered by
  // their smallest new vertex index, ties in input order. Built in parallel.
  CollapseMesh(const PolygonMesh& mesh, const std::vector<std::uint32_t>& vertex_order, CollapseRules rules = {});

  std::uint32_t vertex_slots() const { return static_cast<std::uint32_t>(vertices_.size()); }
  std::uint32_t edge_slots() const { return static_cast<std::uint32_t>(edges_.size()); }
  std::uint32_t triangle_slots() const { return static_cast<std::uint32_t>(corners_.size() / 3); }
  std::size_t alive_vertices() const;
  std::size_t alive_triangles() const;

  bool vertex_alive(std::uint32_t v) const { return vertices_[v].halfedge != kNone; }
  // An outgoing half-edge of v, the boundary one if v is on the boundary:
  // h, opposite(prev(h)), ... walks v's corners until kNone or h again.
  std::uint32_t vertex_halfedge(std::uint32_t v) const { return vertices_[v].halfedge; }
  bool edge_alive(std::uint32_t e) const { return edges_[e].halfedge != kNone; }
  std::uint32_t edge_halfedge(std::uint32_t e) const { return edges_[e].halfedge; }
  std::uint32_t origin(std::uint32_t h) const { return corners_[h].vertex; }
  std::uint32_t target(std::uint32_t h) const { return corners_[next(h)].vertex; }
  std::uint32_t opposite(std::uint32_t h) const { return corners_[h].opposite; }
  std::uint32_t edge_of(std::uint32_t h) const { return corners_[h].edge; }
  static std::uint32_t next(std::uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; }
  static std::uint32_t prev(std::uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; }
  const Vec3& position(std::uint32_t v) const { return vertices_[v].position; }
  std::uint32_t valence(std::uint32_t v) const { return vertices_[v].valence; }
  bool is_sharp(std::uint32_t v) const { return (vertices_[v].flags & kSharp) != 0; }
  bool is_boundary(std::uint32_t v) const { return (vertices_[v].flags & kBoundary) != 0; }
  // Appends the vertices joined to v by an edge (some twice). O(valence).
  void append_neighbours(std::uint32_t v, std::vector<std::uint32_t>& neighbours) const;
  // Finds the edge between two vertices, or kNone. O(valence).
  std::uint32_t find_edge(std::uint32_t a, std::uint32_t b) const;

  float accumulated_error(std::uint32_t e) const { return edges_[e].accumulated_error; }
  float latest_delta_error(std::uint32_t e) const { return edges_[e].latest_delta; }
  void set_latest_delta_error(std::uint32_t e, double delta) { edges_[e].latest_delta = static_cast<float>(delta); }
  // E (4.3) as of the latest evaluation: E_acc + the latest delta E (0 if none).
  double error(std::uint32_t e) const {
    return double(edges_[e].accumulated_error) + double(edges_[e].latest_delta);
  }
  // Counts a lane's collapses and flips; a FanCache of that lane filled at
  // another version is stale.
  std::uint64_t version(int lane = 0) const { return lanes_[lane].version; }

  // Legality and, if the topological rules pass, the new position and delta
  // E of collapsing edge e. Thread-safe (reads only; one cache per thread).
  // O(valence). The cache makes evaluations that share endpoints (the Fig. 8
  // stencil, or edges in id order) gather each vertex fan once; results are
  // bit-identical with or without it.
  Evaluation evaluate(std::uint32_t e, FanCache& cache) const;
  Evaluation evaluate(std::uint32_t e) const;
  // The same with the new vertex allowed a valence up to `max_valence`
  // instead of the rules' (a and b are still checked): the priority an edge
  // would have once flips have lowered its endpoints' valences.
  Evaluation evaluate(std::uint32_t e, FanCache& cache, int max_valence) const;
  // The rules evaluate() checks first, which read only the endpoints' and
  // opposite vertices' records (sharp, boundary, loop size, valences): Legal
  // when they pass. They change only when a collapse or flip touches those
  // vertices, and so the edge's Fig. 8 stencil. O(1).
  Legality vertex_rules(std::uint32_t e, int max_valence) const;

  // Edge flips (not in the paper; they let the collapse go on where the
  // valence rule alone stalls it, see simplify.h). Edge e = (v_i, v_j) between
  // triangles (v_i, v_j, a) and (v_j, v_i, b) becomes (a, b). Legal when e is
  // interior, neither endpoint is sharp and a, b are not both sharp, (a, b) is
  // not already an edge, v_i and v_j keep valence >= 3 (2 on the boundary),
  // a and b stay <= max_valence, and the quad is nearly flat
  // (rules.flip_min_normal_dot). O(valence).
  bool can_flip(std::uint32_t e) const;
  // Precondition: can_flip(e), or e was flipped last (flipping it again
  // restores the old diagonal). Keeps the edge id and its E_acc. `lane` as
  // for collapse().
  void flip(std::uint32_t e, int lane = 0);
  // Flips edges at v (never one to a vertex in `keep`) until its valence
  // has dropped by `count` or no legal flip is left; appends the flipped edge
  // ids to `flipped` (undo: flip them again in reverse order) and returns how
  // many it flipped. Prefers flips whose raised vertices have low valence.
  int lower_valence(std::uint32_t v, int count, const std::uint32_t* keep, int keep_count,
                    std::vector<std::uint32_t>& flipped, int lane = 0);
  // About the most lower_valence(v, ..., keep, keep_count) can achieve: the
  // edges at v that can_flip() might accept now (interior, to a non-sharp
  // vertex outside `keep`, both opposite vertices below the valence limit),
  // capped by the valence v may lose. Not a strict bound: a flip changes the
  // opposite vertices of the edges next to it. Reads only. O(valence).
  int flip_capacity(std::uint32_t v, const std::uint32_t* keep, int keep_count) const;
  // The four vertices around edge e: v_i, v_j, a, b (b = kNone on the boundary).
  std::array<std::uint32_t, 4> edge_vertices(std::uint32_t e) const;

  // Collapses edge e (precondition: evaluate(e) was Legal and nothing changed
  // since) with the new vertex at `position`, and applies the paper's error
  // propagation: E_acc of every edge around the new vertex becomes
  // max(E_acc, E of the five destroyed edges), E taken from error(). Returns
  // the surviving vertex; `removed_edges` receives the three edge ids deleted
  // (kNone for a boundary edge's missing ones) and `opposite_vertices` a and b
  // (b = kNone on the boundary).
  std::uint32_t collapse(std::uint32_t e, const Vec3& position, std::uint32_t removed_edges[3],
                         std::uint32_t opposite_vertices[2], int lane = 0);

  // A region id per vertex (0 after construction), kept in the vertex record
  // that evaluations load anyway.
  void set_region(std::uint32_t v, std::uint8_t id) { vertices_[v].region = id; }
  std::uint8_t region(std::uint32_t v) const { return vertices_[v].region; }
  // True when e is interior and e's endpoints and all their neighbours are in
  // region `id`: then collapsing e writes only records of that region's
  // vertices, their triangles and edges. O(valence).
  bool collapse_inside(std::uint32_t e, std::uint8_t id) const;

  // Per-edge links for BucketQueue's caller-kept constructor, in the edge
  // records: requeueing a stencil edge then touches the cache line its
  // evaluation loaded. All "not queued" after construction, and again once
  // every queue using them is empty; queues sharing them must hold disjoint
  // edges.
  BucketQueue::Links* queue_links() { return &edges_.data()->queue; }
  static constexpr std::size_t queue_link_stride() { return sizeof(EdgeRecord); }

  // Appends to `edges` (no duplicates) the update stencil of Fig. 8 around
  // the vertices `centres`: every edge of every triangle incident to one of
  // them, i.e. the edges adjacent to the new vertex and to a and b plus the
  // ring of edges between their outer endpoints. Uses the lane's stamps: one
  // thread per lane.
  void gather_stencil(const std::uint32_t* centres, int count, std::vector<std::uint32_t>& edges, int lane = 0);

  // Cache hints, no effect on results. The collapse loop waits on memory
  // (see the top of this file); fetching what it will read soon overlaps
  // those waits. For edges evaluated in a known order (a batch), three
  // steps at decreasing distance ahead, each reading only what the one
  // before fetched: the edge record, its corners, its vertices (and the
  // opposite triangle).
  void prefetch_edge_record(std::uint32_t e) const { __builtin_prefetch(&edges_[e]); }
  void prefetch_edge_corners(std::uint32_t e) const {
    const std::uint32_t h = edges_[e].halfedge;
    if (h == kNone) return;
    __builtin_prefetch(&corners_[h]);
    __builtin_prefetch(&corners_[h] + 2);  // a triangle may straddle two cache lines
  }
  void prefetch_edge_vertices(std::uint32_t e) const {
    const std::uint32_t h = edges_[e].halfedge;
    if (h == kNone) return;
    __builtin_prefetch(&vertices_[corners_[h].vertex]);
    __builtin_prefetch(&vertices_[corners_[next(h)].vertex]);
    __builtin_prefetch(&vertices_[corners_[prev(h)].vertex]);
    if (const std::uint32_t o = corners_[h].opposite; o != kNone) __builtin_prefetch(&corners_[o]);
  }

  // From now on, collapse() and flip() report to `tracker` (nullptr: none),
  // which carries the surface map along (surface_map_tracker.h). Not owned.
  void set_surface_map_tracker(SurfaceMapTracker* tracker) { map_tracker_ = tracker; }

  // Checks every invariant of the corner table (opposite symmetry, edge ids,
  // valences, boundary flags and loop sizes, manifold fans, vertex
  // half-edges); returns "" or the first problem found. O(n).
  std::string validate() const;

  // Compacted polygon mesh of the alive triangles (sharp flags included when
  // the input had any). `vertex_map`, if given, receives for each vertex slot
  // its index in the result or kNone.
  PolygonMesh to_polygon_mesh(std::vector<std::uint32_t>* vertex_map = nullptr) const;

  // Per-component counts of the current mesh, for the report's lower bound.
  struct ComponentCounts {
    std::size_t vertices = 0, edges = 0, faces = 0, boundary_loops = 0;
    long long genus() const {
      return (2 - (static_cast<long long>(vertices) - static_cast<long long>(edges) + static_cast<long long>(faces)) -
              static_cast<long long>(boundary_loops)) / 2;
    }
  };
  std::vector<ComponentCounts> components() const;

 private:
  static constexpr std::uint8_t kSharp = 1, kBoundary = 2, kHadSharpInput = 4;

  // Calls visit(corner) for each corner at vertex v, counter-clockwise,
  // starting at the boundary half-edge for a boundary vertex.
  template <typename Visit>
  void for_each_corner(std::uint32_t v, Visit&& visit) const;
  // Index in cache.fans_ of v's fan, gathering it if needed.
  std::uint32_t fan(std::uint32_t v, FanCache& cache) const;
  // Given a fan's ring vertex ids (entries 0..count), its positions and old
  // cross products.
  void fill_fan_geometry(std::uint32_t v, FanCache::Entry* entries, std::uint32_t count) const;
  // Both constructors; vertex_order may be null (input order). The steps, in
  // order (collapse_table.cpp); each throws Error(Topology) on what it finds.
  void build(const PolygonMesh& mesh, const std::uint32_t* vertex_order);
  void build_vertices(const PolygonMesh& mesh, const std::uint32_t* vertex_order);
  void build_corners(const PolygonMesh& mesh, const std::uint32_t* vertex_order,
                     const std::vector<std::uint32_t>& new_index);
  void share_area();    // vertex_area_ from the triangles (CollapseRules::max_vertex_area)
  void pair_corners();  // opposites, vertex half-edges, valences, boundary flags
  void number_edges();
  void find_boundary_loops();
  // Link condition on two gathered fans (evaluate()): the number of
  // neighbours v_i and v_j share.
  static int common_neighbours(const FanCache::Fan& fan_i, const FanCache::Entry* ring_i, bool boundary_i,
                               const FanCache::Fan& fan_j, const FanCache::Entry* ring_j, bool boundary_j);
  // How far moving endpoint `from` (fan `ring` of `corners` triangles, other
  // endpoint `other`) to `p` moves the boundary curve within the surface:
  // |(p - from) . m|, m the unit in-surface normal of the endpoint's other
  // boundary edge (SimplifyOptions::boundary_curve_error).
  static double boundary_curve_move(const FanCache::Entry* ring, std::uint32_t corners, std::uint32_t other,
                                    const Vec3& from, const Vec3& p);
  // Makes vertices_[v].halfedge a live outgoing half-edge, the boundary one if v
  // is on the boundary, starting from the live outgoing half-edge `start`.
  void reset_vertex_halfedge(std::uint32_t v, std::uint32_t start);

  CollapseRules rules_;
  bool input_had_sharp_ = false;
  SurfaceMapTracker* map_tracker_ = nullptr;
  // Records rather than one array per field: collapses happen at random
  // places, so each element costs a cache miss per array it is spread over.
  // The fields one evaluation reads of a vertex, corner or edge sit together.
  struct VertexRecord {
    Vec3 position;
    std::uint32_t halfedge;       // kNone = deleted vertex
    std::uint32_t valence;
    std::uint32_t boundary_loop;  // kNone if interior
    std::uint8_t flags;
    std::uint8_t region;
  };
  HugePageVector<VertexRecord> vertices_;
  std::vector<float> vertex_area_;  // with CollapseRules::max_vertex_area > 0: the area each vertex holds
  std::vector<std::uint32_t> loop_size_;  // vertices per boundary loop
  struct CornerRecord {
    std::uint32_t vertex;    // kNone = deleted triangle
    std::uint32_t opposite;  // kNone on the boundary
    std::uint32_t edge;
  };
  HugePageVector<CornerRecord> corners_;  // triangle t: corners 3t..3t+2, 36 contiguous bytes
  struct EdgeRecord {
    std::uint32_t halfedge;  // kNone = deleted edge
    float accumulated_error;
    float latest_delta;
    std::uint32_t stamp;  // gather_stencil()'s "already listed"
    BucketQueue::Links queue;
    std::uint32_t unused;  // 32 bytes: two records per cache line
  };
  HugePageVector<EdgeRecord> edges_;
  // Per lane, on its own cache line: stamps are lane + kLanes * count, so no
  // two lanes ever use the same value.
  struct alignas(64) Lane {
    std::uint64_t version = 0;
    std::uint32_t stamp = 0;
    std::size_t removed_vertices = 0, removed_triangles = 0;
  };
  std::array<Lane, kLanes> lanes_{};
  std::size_t initial_vertices_ = 0, initial_triangles_ = 0;
};

}  // namespace isowave::simplify
