#pragma once
// Builds the SurfaceMap (isowave/simplify/surface_map.h) while a CollapseMesh
// is simplified (private to the simplify library). The mesh calls it around
// every collapse and flip; each call flattens the region the operation
// changes (the triangles at the edge's endpoints) into a convex planar chart
// in which the triangulations before and after both embed, and carries the
// input vertices mapped into the region from the old triangles to the new
// ones through their chart positions (MAPS, Lee et al. 1998, Sec. 3).
//
// The chart: the region's boundary polygon on the unit circle, arc lengths
// proportional to its 3D edge lengths; interior vertices at their
// mean-value combination of their neighbours (Floater 2003: positive weights
// and a convex boundary give an embedding). The new vertex: the midpoint of
// the two endpoints' chart positions, or the endpoint it collapses onto
// (sharp or boundary vertex). A boundary edge's collapse lays its removed
// endpoint on the chord between its neighbours, so that the region keeps
// its shape. A flip's quad lies on the circle: both diagonals embed.
//
// The history (SurfaceMapHistory): every operation's chart, the triangles it
// consumed and those it made, appended under a mutex (one short append per
// operation); per triangle slot its current version.
//
// Storage: per input vertex its triangle slot, barycentric (u, v) and the
// next vertex of its triangle's list; per triangle slot the first one. Flat
// arrays: millions of points, and one list per triangle keeps a relocation
// local. Thread-safe across lanes (CollapseMesh::kLanes) as long as the
// lanes' operations touch disjoint triangles, as collapse_inside() ensures.
#include <array>
#include <cstdint>
#include <mutex>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/simplify/collapse_mesh.h"
#include "isowave/simplify/surface_map.h"

namespace isowave::simplify {

class SurfaceMapTracker {
 public:
  // Every vertex of `mesh` (an unmodified table) maps to a corner of one of
  // its triangles. O(vertices).
  explicit SurfaceMapTracker(const CollapseMesh& mesh);

  // Called by CollapseMesh::collapse() before it changes anything, with the
  // edge and the new vertex's position, and after, with the survivor.
  void before_collapse(const CollapseMesh& mesh, std::uint32_t e, const Vec3& position, int lane);
  void after_collapse(const CollapseMesh& mesh, std::uint32_t survivor, int lane);
  // Called by CollapseMesh::flip() before and after.
  void before_flip(const CollapseMesh& mesh, std::uint32_t e, int lane);
  void after_flip(const CollapseMesh& mesh, std::uint32_t e, int lane);

  // The map onto the compacted mesh: `vertex_map` and the triangle order as
  // CollapseMesh::to_polygon_mesh() makes them, `input_of_vertex[k]` the
  // input index of table vertex k; each triangle its own face (edge removal
  // sets triangle_face later). O(vertices + triangles).
  // Moves the history into the result: call once.
  SurfaceMap finish(const CollapseMesh& mesh, const std::vector<std::uint32_t>& vertex_map,
                    const std::vector<std::uint32_t>& input_of_vertex);

 private:
  static constexpr std::uint32_t kNone = CollapseMesh::kNone;
  struct ChartVertex {
    std::uint32_t vertex;
    double x, y;
  };
  struct Carried {
    std::uint32_t point;
    double x, y;
  };
  // Scratch of one lane: the region's chart and the points taken out of it.
  struct Lane {
    std::vector<ChartVertex> chart;
    std::vector<std::uint32_t> triangles;  // the region's triangle slots before the operation
    std::vector<Carried> carried;
    std::array<double, 2> new_vertex{};    // chart position of the collapse's survivor
    std::vector<std::uint32_t> boundary_from, boundary_to;  // scratch: the region's boundary half-edges
    std::vector<std::uint32_t> polygon;                     // scratch: the region's boundary polygon
    std::vector<double> arcs;                               // scratch: its edge lengths
    std::vector<std::uint32_t> ring;                        // scratch: a vertex's neighbours
    std::vector<double> weights;                            // scratch: their weights
    std::vector<double> corner_xy;                          // scratch: chart corners of lane.triangles
    std::vector<std::uint32_t> consumed;                    // versions of lane.triangles before the operation
    std::vector<std::array<std::uint8_t, 3>> consumed_corners;  // their corners in lane.chart
    std::uint32_t survivor = kNone;                         // the collapse's survivor (kNone for a flip)
  };

  // The triangles at v (its fan) appended to `out`, without duplicates.
  static void append_fan(const CollapseMesh& mesh, std::uint32_t v, std::vector<std::uint32_t>& out);
  // lane.polygon: the region's boundary, counter-clockwise, from lane.triangles.
  static void boundary_polygon(const CollapseMesh& mesh, Lane& lane);
  // Appends lane.polygon to lane.chart on the unit circle, each edge's arc
  // proportional to lane.arcs (its length) plus kArcFloor of the mean;
  // lane.arcs then holds those shares.
  static void place_on_circle(Lane& lane);
  // The chart position of interior vertex v from its neighbours' (all in the
  // chart except `unplaced`, whose weight is returned): the mean-value
  // combination (3D angles), uniform where those weights are not finite and
  // positive. Returns the weight of `unplaced` (0 if not a neighbour).
  static double mean_value_position(const CollapseMesh& mesh, std::uint32_t v, std::uint32_t unplaced, Lane& lane,
                                    double& x, double& y);
  // The chart of a collapse of edge (vi, vj) whose region both endpoints lie
  // inside, and of one with one endpoint on its boundary.
  static void chart_inside(const CollapseMesh& mesh, std::uint32_t vi, std::uint32_t vj, const Vec3& position,
                           Lane& lane);
  static void chart_one_on_boundary(const CollapseMesh& mesh, std::uint32_t on, std::uint32_t inside, Lane& lane);
  // A boundary edge's: the endpoint with the larger fan lies on the chord.
  static void chart_boundary_edge(const CollapseMesh& mesh, std::uint32_t vi, std::uint32_t vj, Lane& lane);
  // Chart position of vertex v in lane.chart (precondition: present).
  static const ChartVertex& chart_of(const Lane& lane, std::uint32_t v);
  static void set_lengths(const CollapseMesh& mesh, Lane& lane);  // lane.arcs from lane.polygon
  // Takes the points of lane.triangles out of their lists into lane.carried
  // at their chart positions.
  void take_points(const CollapseMesh& mesh, Lane& lane);
  // Puts lane.carried into lane.triangles as they are now (the survivor at
  // lane.new_vertex): each into the triangle it lies in, or where it is
  // nearest to lying (rounding), its barycentric coordinates clamped.
  void place_points(const CollapseMesh& mesh, Lane& lane);

  // Index of vertex v in lane.chart (precondition: present, under 255 vertices).
  static std::uint8_t chart_index(const Lane& lane, std::uint32_t v);
  // Notes lane.triangles' versions and chart corners before the operation.
  void note_consumed(const CollapseMesh& mesh, Lane& lane) const;
  // Appends the operation to the history: its chart (the survivor's new
  // position as one more vertex), what it consumed, and the region's live
  // triangles as new versions.
  void record(const CollapseMesh& mesh, const Lane& lane);

  std::vector<std::uint32_t> point_triangle_;  // per table vertex (input point)
  std::vector<std::array<double, 2>> point_uv_;
  std::vector<std::uint32_t> next_point_;      // list link, kNone at the end
  std::vector<std::uint32_t> first_point_;     // per triangle slot
  std::array<Lane, CollapseMesh::kLanes> lanes_;
  std::vector<std::uint32_t> version_;  // per triangle slot
  SurfaceMapHistory history_;
  std::mutex history_mutex_;
};

}  // namespace isowave::simplify
