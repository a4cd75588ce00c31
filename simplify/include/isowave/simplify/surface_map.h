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

  std::size_t triangle_count() const { return triangles.size(); }
  std::size_t vertex_count() const { return vertex_triangle.size(); }
};

}  // namespace isowave::simplify
