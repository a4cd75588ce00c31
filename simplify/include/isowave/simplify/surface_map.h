#pragma once
// A bijective map from the input surface onto the base mesh, built while the
// base mesh is simplified, as MAPS does (Lee, Sweldens, Schroeder, Cowsar,
// Dobkin, SIGGRAPH 1998): every collapse and flip flattens the region it
// changes into a convex planar chart, and each input vertex already mapped
// into that region is carried into the new triangles by its chart position.
// The map is the parameter domain of the parametrization-based fit
// (fit/parametrized_fit.h): a point of the base mesh's triangles is a point
// of the input surface.
//
// Representation: flat arrays (millions of input vertices, read in parallel
// by the fit). The base mesh's triangles are those of the collapse, before
// edge removal merged them into polygons; each belongs to one base face.
#include <array>
#include <cstdint>
#include <vector>

namespace isowave::simplify {

// The map's history: every triangle the simplification made, and every
// operation's chart, so that a point of a base triangle can be carried back,
// operation by operation, to the input triangle it comes from (the exact
// inverse of the piecewise-linear map the charts compose; fit's
// parametrized_fit). Triangle "versions": [0, input_corners.size()) are the
// input's triangles; each later one was made by exactly one operation.
// Operation r (a collapse or a flip, in the order they were applied to the
// region, any order across disjoint regions):
// - its chart vertices: chart[chart_begin[r] .. chart_begin[r + 1]), planar
//   positions (the tracker's convex chart, 16 bytes a vertex);
// - the triangles it consumed: consumed[consumed_begin[r] .. [r + 1]), with
//   their corners as indices into the operation's chart vertices;
// - the triangles it made: versions made_begin[r] .. made_begin[r + 1] - 1,
//   their corners made_corners[version - input triangles], likewise.
// Both triangle sets tile the same convex polygon of the chart, so each
// operation is a bijection. Memory: about 300 bytes per collapse.
struct SurfaceMapHistory {
  std::vector<std::array<std::uint32_t, 3>> input_corners;  // input vertex indices per input triangle
  std::vector<std::uint32_t> base_version;                  // per base triangle (SurfaceMap::triangles)
  std::vector<std::uint32_t> chart_begin, consumed_begin, made_begin;  // per operation, plus one
  std::vector<std::array<double, 2>> chart;
  std::vector<std::uint32_t> consumed;
  std::vector<std::array<std::uint8_t, 3>> consumed_corners, made_corners;

  std::size_t operation_count() const { return made_begin.empty() ? 0 : made_begin.size() - 1; }
  bool empty() const { return base_version.empty(); }
};

struct SurfaceMap {
  // The base triangles: vertex indices of the base mesh (SimplifyResult::base),
  // oriented as the base faces. Every base face of n sides is the union of
  // n - 2 of them, joined along its diagonals (edges the edge removal deleted).
  std::vector<std::array<std::uint32_t, 3>> triangles;
  // Per base triangle: the base face it belongs to.
  std::vector<std::uint32_t> triangle_face;
  // Per input vertex (the simplifier's input numbering): the base triangle it
  // maps into, and its barycentric coordinates there, (u, v) the weights of
  // corners 1 and 2 (corner 0 weighs 1 - u - v); all three in [0, 1].
  std::vector<std::uint32_t> vertex_triangle;
  std::vector<std::array<double, 2>> vertex_uv;
  SurfaceMapHistory history;

  std::size_t triangle_count() const { return triangles.size(); }
  std::size_t vertex_count() const { return vertex_triangle.size(); }
};

}  // namespace isowave::simplify
