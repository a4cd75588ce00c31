#include "edge_removal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "isowave/simplify/bucket_queue.h"
#include "isowave/simplify/collapse_mesh.h"

namespace isowave::simplify {

namespace {

constexpr std::uint32_t kNone = CollapseMesh::kNone;
// Removal priorities lie in [-1, 3] (see simplify.h); buckets of 5e-5.
constexpr std::uint32_t kBucketCount = 1 << 16;
constexpr double kLowestPriority = -1, kHighestPriority = 3;

// The pass on the corner table of the triangles: a face is a set of at most
// three triangles joined by removed edges, named by its first triangle
// (`face_of`). Its side count and vector area (the sum of its triangles'
// cross products: Newell's normal of the polygon, times two) are kept per
// face, polygon valences per vertex, so that a priority costs O(1); the test
// that the two faces share only the edge runs when the edge is popped.
// Flat arrays rather than a polygon halfedge mesh: building one (OpenMesh)
// costs a noticeable share of the whole simplification.
class EdgeRemoval {
 public:
  EdgeRemoval(const CollapseMesh& mesh, const std::vector<std::uint8_t>& sharp, double min_normal_dot)
      : mesh_(mesh),
        sharp_(sharp),
        min_normal_dot_(min_normal_dot),
        triangle_count_(static_cast<std::uint32_t>(mesh.alive_triangles())),
        face_of_(triangle_count_),
        sides_(triangle_count_, 3),
        area_(triangle_count_),
        members_(triangle_count_),
        removed_(mesh.edge_slots(), 0),
        valence_(mesh.vertex_slots()),
        queue_(mesh.edge_slots(), kBucketCount) {
    for (std::uint32_t t = 0; t < triangle_count_; ++t) {
      face_of_[t] = t;
      members_[t] = {t, kNone, kNone};
      const Vec3& a = mesh.position(mesh.origin(3 * t));
      area_[t] = cross(mesh.position(mesh.origin(3 * t + 1)) - a, mesh.position(mesh.origin(3 * t + 2)) - a);
    }
    for (std::uint32_t v = 0; v < mesh.vertex_slots(); ++v) valence_[v] = mesh.valence(v);
  }

  std::size_t run() {
    for (std::uint32_t e = 0; e < mesh_.edge_slots(); ++e) update(e);
    std::size_t removed = 0;
    while (!queue_.empty()) {
      const std::uint32_t e = queue_.pop();
      // A later change around this edge queues it again.
      if (!merge_is_simple(e)) continue;
      remove(e);
      ++removed;
    }
    return removed;
  }

  // The faces as polygons, each walked along its sides from a kept edge.
  void write(PolygonMesh& polygons, std::vector<std::uint32_t>* triangle_face) const {
    if (triangle_face) triangle_face->assign(triangle_count_, kNone);
    polygons.face_offsets.assign(1, 0);
    polygons.face_vertices.clear();
    std::vector<std::uint32_t> corners;
    for (std::uint32_t t = 0; t < triangle_count_; ++t) {
      if (face_of_[t] != t) continue;
      std::uint32_t start = 3 * t;
      while (removed_[mesh_.edge_of(start)]) ++start;
      corners.clear();
      std::uint32_t h = start;
      do {
        corners.push_back(mesh_.origin(h));
        h = CollapseMesh::next(h);
        while (removed_[mesh_.edge_of(h)]) h = CollapseMesh::next(mesh_.opposite(h));
      } while (h != start);
      if (triangle_face)
        for (std::uint32_t member : members_[t])
          if (member != kNone) (*triangle_face)[member] = static_cast<std::uint32_t>(polygons.face_count());
      polygons.add_face(corners.data(), corners.size());
    }
  }

 private:
  static std::uint32_t triangle(std::uint32_t h) { return h / 3; }

  // Removal priority of edge e if it passes the O(1) rules.
  bool priority(std::uint32_t e, double& result) const {
    if (removed_[e]) return false;  // a removed edge is never queued again
    const std::uint32_t h = mesh_.edge_halfedge(e), o = mesh_.opposite(h);
    if (o == kNone) return false;
    const std::uint32_t vi = mesh_.origin(h), vj = mesh_.origin(o);
    if (!sharp_.empty() && (sharp_[vi] || sharp_[vj])) return false;
    if (valence_[vi] < 4 || valence_[vj] < 4) return false;
    const std::uint32_t f0 = face_of_[triangle(h)], f1 = face_of_[triangle(o)];
    const std::uint32_t merged = sides_[f0] + sides_[f1] - 2;
    if (merged > 5) return false;
    const double length = std::sqrt(dot(area_[f0], area_[f0]) * dot(area_[f1], area_[f1]));
    const double normal_dot = length > 0 ? dot(area_[f0], area_[f1]) / length : 0.0;
    if (!(normal_dot >= min_normal_dot_)) return false;
    result = normal_dot + (merged == 4 ? 1.0 : 0.0) + 0.25 * ((valence_[vi] > 4 ? 1 : 0) + (valence_[vj] > 4 ? 1 : 0));
    return true;
  }

  // Queues e at its current priority, keeping its place if the bucket is
  // the same, or takes it out of the queue.
  void update(std::uint32_t e) {
    double p = 0;
    if (!priority(e, p)) {
      if (queue_.contains(e)) queue_.remove(e);
      return;
    }
    const double share = (p - kLowestPriority) / (kHighestPriority - kLowestPriority);
    const auto bucket =
        static_cast<std::uint32_t>(std::clamp(share, 0.0, 1.0) * double(kBucketCount - 1));
    if (queue_.contains(e)) {
      if (queue_.bucket_of(e) == bucket) return;
      queue_.remove(e);
    }
    queue_.push(e, bucket);
  }

  // The corners of face f (its vertices, each once per triangle).
  int face_corners(std::uint32_t f, std::array<std::uint32_t, 9>& corners) const {
    int count = 0;
    for (std::uint32_t t : members_[f])
      if (t != kNone)
        for (std::uint32_t k = 0; k < 3; ++k) corners[count++] = mesh_.origin(3 * t + k);
    return count;
  }

  // The faces of e share only e and its endpoints: the merged face is a
  // simple polygon.
  bool merge_is_simple(std::uint32_t e) const {
    const std::uint32_t h = mesh_.edge_halfedge(e);
    std::array<std::uint32_t, 9> a, b;
    const int a_count = face_corners(face_of_[triangle(h)], a);
    const int b_count = face_corners(face_of_[triangle(mesh_.opposite(h))], b);
    std::sort(a.begin(), a.begin() + a_count);
    std::sort(b.begin(), b.begin() + b_count);
    const int a_unique = static_cast<int>(std::unique(a.begin(), a.begin() + a_count) - a.begin());
    const int b_unique = static_cast<int>(std::unique(b.begin(), b.begin() + b_count) - b.begin());
    std::array<std::uint32_t, 9> shared;
    const auto end = std::set_intersection(a.begin(), a.begin() + a_unique, b.begin(), b.begin() + b_unique,
                                           shared.begin());
    return end - shared.begin() == 2;
  }

  void remove(std::uint32_t e) {
    const std::uint32_t h = mesh_.edge_halfedge(e), o = mesh_.opposite(h);
    const std::uint32_t vi = mesh_.origin(h), vj = mesh_.origin(o);
    const std::uint32_t f0 = face_of_[triangle(h)], f1 = face_of_[triangle(o)];
    removed_[e] = 1;
    --valence_[vi];
    --valence_[vj];
    int slot = 0;
    while (members_[f0][slot] != kNone) ++slot;
    for (std::uint32_t t : members_[f1])
      if (t != kNone) {
        face_of_[t] = f0;
        members_[f0][slot++] = t;
      }
    sides_[f0] += sides_[f1] - 2;
    area_[f0] = area_[f0] + area_[f1];
    // The merged face's size and normal changed: its sides' priorities. The
    // endpoints' valences enter a priority only through the thresholds 4
    // (rule) and 5 (bonus): the edges at an endpoint now of valence 3 or 4.
    for (std::uint32_t t : members_[f0])
      if (t != kNone)
        for (std::uint32_t k = 0; k < 3; ++k)
          if (const std::uint32_t side = mesh_.edge_of(3 * t + k); !removed_[side]) update(side);
    for (std::uint32_t v : {vi, vj}) {
      if (valence_[v] > 4) continue;
      const std::uint32_t first = mesh_.vertex_halfedge(v);
      std::uint32_t c = first;
      do {
        update(mesh_.edge_of(c));
        update(mesh_.edge_of(CollapseMesh::prev(c)));
        c = mesh_.opposite(CollapseMesh::prev(c));
      } while (c != kNone && c != first);
    }
  }

  const CollapseMesh& mesh_;
  const std::vector<std::uint8_t>& sharp_;
  const double min_normal_dot_;
  const std::uint32_t triangle_count_;
  std::vector<std::uint32_t> face_of_;              // per triangle: its face
  std::vector<std::uint32_t> sides_;                // per face
  std::vector<Vec3> area_;                          // per face
  std::vector<std::array<std::uint32_t, 3>> members_;  // per face: its triangles
  std::vector<std::uint8_t> removed_;               // per edge
  std::vector<std::uint32_t> valence_;              // per vertex, in the polygon mesh
  BucketQueue queue_;
};

}  // namespace

std::size_t remove_edges(PolygonMesh& polygons, double min_normal_dot, std::vector<std::uint32_t>* triangle_face) {
  // The input is compact and its faces triangles: the table keeps their
  // order (triangle t holds corners 3t..3t+2) and vertex indices.
  const CollapseMesh mesh(polygons);
  EdgeRemoval removal(mesh, polygons.sharp, min_normal_dot);
  const std::size_t removed = removal.run();
  removal.write(polygons, triangle_face);
  return removed;
}

}  // namespace isowave::simplify
