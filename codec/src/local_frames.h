#pragma once
// Private: the local frames of the .isw 2.0 coefficients (issue #34; MPEG
// V-DMC's choice): at every entry of the coarse-to-fine array, the unit
// normal of the base mesh subdivided to the finest level with zero details,
// S^L(base), at that entry's fine vertex (entry i is fine vertex i). The
// decoder rebuilds them from the base control points it decoded before any
// coefficient, so every prefix of the stream sees the same frames. A frame is
// (n, t, b): t the unit vector of n x a, a the world axis least aligned with
// n, and b = n x t; a zero normal (a degenerate patch) takes the world axes.
// Encoder and decoder must get bit-identical frames: every sum has a fixed
// order (threads split the vertices, never a sum), and the codec target
// compiles without floating contraction.
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"

namespace isowave::detail {

struct Frame {
  Vec3 n, t, b;
};

// The frame of a unit (or zero) normal.
Frame frame_of(const Vec3& normal);

// Per fine vertex: the area-weighted unit normal of S^L(base_points) (zero
// where the faces around it have no area; docs/FORMAT.md, "Local frames"):
// the vector areas of the level-(L-1) faces, as fans of their e vertices
// around their f vertex, summed at the f vertex, at the e vertices of the
// faces' edges and at their corners. L = 0 gives the base mesh's own.
// Cost: one synthesis and three parallel passes, O(fine vertices).
std::vector<Vec3> frame_normals(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_points);

// World vector -> (n, t, b) components, and back.
inline Vec3 to_frame(const Frame& f, const Vec3& v) { return {dot(v, f.n), dot(v, f.t), dot(v, f.b)}; }
inline Vec3 from_frame(const Frame& f, const Vec3& c) { return f.n * c[0] + f.t * c[1] + f.b * c[2]; }

}  // namespace isowave::detail
