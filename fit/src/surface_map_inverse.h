#pragma once
// The inverse of the simplifier's surface map (simplify/surface_map.h): from
// a point of a base triangle to the point of the input surface mapped there.
// Private to the parametrization-based fit (parametrized_fit.h).
//
// Input triangle t = (i, j, k) maps to the triangle of the images of its
// vertices, straight in the plane of the base triangles unfolded around them.
// A base triangle T's candidates are the input triangles with a vertex mapped
// into T, and those with vertices in two base triangles that share only a
// base vertex w, T between them around w (either way round a closed fan).
// Each candidate's vertices are unfolded into T's (u, v) frame: across an
// edge of T, or around a corner of T the shorter way (a boundary vertex's fan
// has one way), with the base triangles' 3D edge lengths; a candidate whose
// image is not positively oriented there (unfolded the wrong way round, or a
// map that folds) is dropped, since the map preserves orientation. A query
// point is located among them (barycentric test, a uniform grid when there
// are more than 16); where none contains it, the candidate whose smallest
// barycentric coordinate is the largest gives it, clamped (a fallback). Where
// no candidate can be unfolded into T, those of the triangles around T are
// tried; failing these too, the point of the base triangle itself is
// returned (also a fallback).
//
// Base triangles are processed in parallel (TBB), each with thread-local
// scratch, and every result depends only on its base triangle: identical for
// any thread count. Memory: about 12 bytes per input triangle, 4 per
// (base triangle, candidate) pair, 8 during their counting sort, 4 per query.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/simplify/surface_map.h"

namespace isowave {

// A point of a plane: a chart, or base triangles unfolded into one's plane.
struct Vec2 {
  double x = 0, y = 0;
};
inline Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2 operator*(double s, Vec2 a) { return {s * a.x, s * a.y}; }
inline double cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
using Corners = std::array<Vec2, 3>;

// The barycentric weights of q in triangle p (either orientation); false,
// and w untouched, if p is degenerate.
inline bool barycentric(const Corners& p, Vec2 q, std::array<double, 3>& w) {
  const double det = cross(p[1] - p[0], p[2] - p[0]);
  if (det == 0) return false;
  w[1] = cross(q - p[0], p[2] - p[0]) / det;
  w[2] = cross(p[1] - p[0], q - p[0]) / det;
  w[0] = 1 - w[1] - w[2];
  return true;
}

// A point of the parameter domain: a base triangle of the map and the
// barycentric weights of its corners 1 and 2.
struct MapPoint {
  std::uint32_t triangle = 0;
  double u = 0, v = 0;
};

// Compressed rows of indices: the values of key k are
// values[offsets[k] .. offsets[k+1]).
struct IndexRows {
  std::vector<std::size_t> offsets;
  std::vector<std::uint32_t> values;
  const std::uint32_t* begin(std::size_t k) const { return values.data() + offsets[k]; }
  const std::uint32_t* end(std::size_t k) const { return values.data() + offsets[k + 1]; }
  std::size_t size(std::size_t k) const { return offsets[k + 1] - offsets[k]; }
};

// Stable counting sort of values by key (every key < key_count): each row
// keeps the values' given order. Serial, O(keys + key_count).
IndexRows sort_into_rows(std::size_t key_count, const std::vector<std::uint32_t>& keys,
                         const std::vector<std::uint32_t>& values);

struct InverseMapResult {
  std::vector<Vec3> points;  // points[i] for queries[i]
  std::size_t fallback_points = 0;
};

// The surface points at `queries`. Preconditions (checked by the caller):
// the map's indices are in range of base_positions, the surface's vertices
// and the map's triangles; the surface's faces are valid; every query's
// triangle is a map triangle.
InverseMapResult inverse_map(const simplify::SurfaceMap& map, const std::vector<Vec3>& base_positions,
                             const PolygonMesh& surface, const std::vector<MapPoint>& queries);

}  // namespace isowave
