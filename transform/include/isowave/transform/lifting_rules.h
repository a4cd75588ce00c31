#pragma once
// The lifted bicubic subdivision-surface wavelet rules of Bertram et al. 2000,
// Sec. 3.3 (rules 3.8 and 3.10) and Sec. 3.4 (sharp edges and vertices), in one
// place and free of storage concerns, like OpenSubdiv's Sdc.
//
// A fine level holds three vertex types (Sec. 3.1): v (children of coarse
// vertices), e (children of edges) and f (children of faces). Each lifting
// step updates one type from averages of the others:
//
//   synthesis:  target <- self * target + f * avg_f + e * avg_e + v * avg_v
//   analysis:   target <- (target - f * avg_f - e * avg_e - v * avg_v) / self
//
// where avg_x is the averaging operator x̄_y of Sec. 3.1. Synthesis runs the six
// steps in order; analysis inverts them in reverse order, which is exactly the
// decomposition rules (3.10). Because analysis recomputes each average from
// values the step does not touch, and every `self` is a power of two, the pair
// is invertible up to one rounding per step.
#include <array>

namespace isowave::lifting {

enum class VertexType { V, E, F };

struct Rule {
  double self;
  double f;  // weight of the average of adjacent (or corresponding) f vertices
  double e;  // weight of the average of adjacent e vertices
  double v;  // weight of the average of adjacent (or corresponding) v vertices
};

struct Step {
  VertexType target;
  Rule smooth;
  // Sec. 3.4. For e targets: whether an e vertex on a sharp edge, or on an
  // edge with a sharp endpoint, skips the step (rules 1 and 5). For v targets:
  // the replacement rule for a v vertex with two incident sharp edges (its
  // avg_e is then taken over those two edges only); sharp v vertices (flagged,
  // or corners with three or more sharp edges) skip v steps altogether.
  bool skipped_on_sharp_edges;
  Rule crease;
};

// Reconstruction rules (3.8), in synthesis order.
inline constexpr std::array<Step, 6> kSynthesisSteps = {{
    // 1. e <- e - 3/4 f̄_e
    {VertexType::E, {1.0, -0.75, 0.0, 0.0}, true, {}},
    // 2. v <- v - 9/16 f̄_v - 3/2 ē_v ; crease: v <- v - 3/4 ē_v
    {VertexType::V, {1.0, -9.0 / 16.0, -1.5, 0.0}, false, {1.0, 0.0, -0.75, 0.0}},
    // 3. e <- e + v̄_e
    {VertexType::E, {1.0, 0.0, 0.0, 1.0}, false, {}},
    // 4. f <- f - v̄_f + 2 ē_f
    {VertexType::F, {1.0, 0.0, 2.0, -1.0}, false, {}},
    // 5. e <- 1/2 e + 1/2 f̄_e
    {VertexType::E, {0.5, 0.5, 0.0, 0.0}, true, {}},
    // 6. v <- 1/4 v - 1/4 f̄_v + ē_v ; crease: v <- 1/2 v + 1/2 ē_v
    {VertexType::V, {0.25, -0.25, 1.0, 0.0}, false, {0.5, 0.0, 0.5, 0.0}},
}};

}  // namespace isowave::lifting
