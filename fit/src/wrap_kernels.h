#pragma once
// Small inline helpers shared by the shrink-wrap's rooms (level mesh, steps,
// correction, fold repair, droplets, driver): parallel loops whose results do
// not depend on the thread count, the volume's box, face normals and the
// fold test. Private to fit/.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/orientation.h"
#include "isowave/fit/trilinear.h"
#include "isowave/fit/wrap_level_mesh.h"

namespace isowave::wrap {

constexpr std::uint32_t kNone = WrapLevelMesh::kNone;

template <class Body>
void for_vertices(std::size_t n, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v) body(v);
  });
}

// Runs body(begin, end, partial) over fixed blocks of items in parallel and
// returns the blocks' partial results in order: summing them in that order
// gives statistics that do not depend on the thread count, without a
// per-item array.
constexpr std::size_t kBlock = 4096;
// How many items ahead the gathering loops prefetch.
constexpr std::size_t kPrefetchDistance = 8;
template <class Partial, class Body>
std::vector<Partial> for_blocks(std::size_t n, const Body& body) {
  std::vector<Partial> partials((n + kBlock - 1) / kBlock);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, partials.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) body(b * kBlock, std::min(n, (b + 1) * kBlock), partials[b]);
  });
  return partials;
}

struct Box {
  Vec3 low, high;
  explicit Box(const Volume& volume) : low(volume_box_min(volume)), high(volume_box_max(volume)) {}
  Vec3 clamp(const Vec3& p) const {
    return {std::clamp(p.x, low.x, high.x), std::clamp(p.y, low.y, high.y), std::clamp(p.z, low.z, high.z)};
  }
  double plane(int face) const { return (face & 1) ? high[face >> 1] : low[face >> 1]; }
  // The range of t for which p + t d stays in the box (p inside).
  void clip(const Vec3& p, const Vec3& d, double& t_low, double& t_high) const {
    t_low = -1e300;
    t_high = 1e300;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0) continue;
      double t0 = (low[a] - p[a]) / d[a], t1 = (high[a] - p[a]) / d[a];
      if (t0 > t1) std::swap(t0, t1);
      t_low = std::max(t_low, std::min(t0, 0.0));
      t_high = std::min(t_high, std::max(t1, 0.0));
    }
  }
};

// Keeps the vertex on its box face and inside the box.
inline Vec3 place(const WrapLevelMesh& mesh, const Box& box, std::size_t v, Vec3 p) {
  const int face = mesh.box_face[v];
  if (face >= 0) p[face >> 1] = box.plane(face);
  return box.clamp(p);
}

// A polygon's Newell vector: twice its area vector.
inline Vec3 newell_vector(const std::uint32_t* face, std::uint32_t size, const std::vector<Vec3>& p) {
  Vec3 n;
  for (std::uint32_t k = 0; k < size; ++k) {
    const Vec3& a = p[face[k]];
    const Vec3& b = p[face[k + 1 == size ? 0 : k + 1]];
    n += cross(a, b);
  }
  return n;
}

// Unit normal of a polygon by Newell's method (zero if degenerate).
inline Vec3 face_normal(const std::uint32_t* face, std::uint32_t size, const std::vector<Vec3>& p) {
  return normalized(newell_vector(face, size, p));
}

// The direction a vertex may move in: box-held vertices only within their face.
inline Vec3 allowed_direction(const WrapLevelMesh& mesh, std::size_t v, Vec3 d) {
  const int face = mesh.box_face[v];
  if (face >= 0) d[face >> 1] = 0.0;
  return normalized(d);
}

// Unit face normals in single precision: the vertex loops gather them at
// scattered places, and half the bytes per normal is worth more there than
// digits beyond the 7th in a search direction.
struct FaceNormal {
  float x, y, z;
};
using FaceNormals = HugePageVector<FaceNormal>;

// The sign dot(face normal, field gradient) has on an unfolded face: -1 when
// normals point toward lower values, +1 toward higher ones.
inline double unfolded_sign(Orientation orientation) {
  return orientation == Orientation::TowardHigher ? 1.0 : -1.0;
}

// Face f's Newell normal (twice its area vector) and the field gradient at
// its centroid, its corners at position(vertex).
template <class Position>
inline void face_normal_and_gradient(const WrapLevelMesh& mesh, const TrilinearGrid& field, std::size_t f,
                                     const Position& position, Vec3& newell, Vec3& gradient) {
  const std::uint32_t begin = mesh.face_offsets[f], size = mesh.face_offsets[f + 1] - begin;
  const std::uint32_t* corners = mesh.face_vertices.data() + begin;
  Vec3 centroid;
  newell = Vec3{};
  for (std::uint32_t k = 0; k < size; ++k) {
    const Vec3 a = position(corners[k]);
    newell += cross(a, position(corners[k + 1 == size ? 0 : k + 1]));
    centroid += a;
  }
  centroid *= 1.0 / double(size);
  gradient = field.sample(centroid).gradient;
}

// 1 if face f's normal disagrees with the field gradient at its centroid
// (expected_sign: unfolded_sign() of the faces' orientation),
// its corners at position(vertex).
template <class Position>
inline std::uint8_t face_folded_at(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                                   std::size_t f, const Position& position) {
  Vec3 newell, gradient;
  face_normal_and_gradient(mesh, field, f, position, newell, gradient);
  return !(expected_sign * dot(newell, gradient) > 0);
}

inline std::uint8_t face_folded(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                                const std::vector<Vec3>& positions, std::size_t f) {
  return face_folded_at(mesh, field, expected_sign, f, [&](std::uint32_t v) -> const Vec3& { return positions[v]; });
}

// How many of vertex v's faces are folded (face_folded_at) with v at `at`
// and the other corners where `positions` has them.
inline int folded_faces_around(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                               const std::vector<Vec3>& positions, std::uint32_t v, const Vec3& at) {
  const auto position = [&](std::uint32_t u) -> const Vec3& { return u == v ? at : positions[u]; };
  int count = 0;
  for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
    count += face_folded_at(mesh, field, expected_sign, mesh.vertex_faces[k], position);
  return count;
}

// The centroid's samples are near those of the first corner.
inline void prefetch_face(const WrapLevelMesh& mesh, const TrilinearGrid& field, const std::vector<Vec3>& positions,
                          std::size_t f) {
  field.prefetch_at(field.grid_point(positions[mesh.face_vertices[mesh.face_offsets[f]]]));
}

}  // namespace isowave::wrap
