#pragma once
// A camera in ParaView's and three.js's terms (issue #48, item 2): what a
// view-dependent decode refines for, and the frustum a decode may read only
// the groups of. Its own header so that the decoder's options can name one
// without the view refinement's (view.h).
#include <string>

#include "isowave/core/vec3.h"

namespace isowave {

struct Camera {
  Vec3 position, target, up;  // world units; target != position, up not along the view
  double fov_degrees = 0;     // vertical field of view, in (0, 180)
  int width = 0, height = 0;  // viewport, pixels, > 0

  // Pixels per world unit at distance `depth` (> 0) along the view:
  // (height / 2) / tan(fov / 2) / depth.
  double pixels_per_unit(double depth) const;
  // Whether the box [lo, hi] lies wholly outside the view frustum (behind
  // the camera, or beyond a side plane).
  bool box_outside(const Vec3& lo, const Vec3& hi) const;
};

// A camera from the JSON object
// {"position":[x,y,z],"target":[x,y,z],"up":[x,y,z],"fov":DEGREES,"viewport":[WIDTH,HEIGHT]}
// (keys in any order, each once; nothing else). Throws Error(Format)
// headed by `name` for other text, Error(InvalidArgument) for a camera
// that is not one (see Camera).
Camera parse_camera(const std::string& json, const std::string& name);
// parse_camera() of a file's text (Error(Io) if it cannot be read).
Camera read_camera(const std::string& path);
// Error(InvalidArgument) unless `camera` is one (see Camera).
void check_camera(const Camera& camera);

}  // namespace isowave
