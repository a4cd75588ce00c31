#pragma once
// A region of interest in world units (the volume's coordinates): a box or a
// ball (issue #48). Its own header so that the decoder's options can name one
// without the region reconstruction's (region.h).
#include <cstdint>
#include <string>
#include <vector>

#include "isowave/core/vec3.h"

namespace isowave {

struct RegionOfInterest {
  enum class Shape : std::uint8_t { Box, Sphere };
  Shape shape = Shape::Box;
  Vec3 low, high;     // Box: corners, low <= high componentwise
  Vec3 centre;        // Sphere
  double radius = 0;  // Sphere: > 0
  // The magnifying glass's width (Gross, Staadt and Gatti), world units,
  // >= 0: outside the region a coefficient's importance is weighted by
  // exp(-d^2 / (2 falloff^2)), d its entry's distance from the region; 0
  // leaves importance as it is.
  double falloff = 0;
  bool contains(const Vec3& p) const;
  // Distance from p to the region (0 inside).
  double distance(const Vec3& p) const;
  // Whether the region and the closed box [lo, hi] share a point.
  bool meets_box(const Vec3& lo, const Vec3& hi) const;
};

// Parses "x0,y0,z0,x1,y1,z1" (a box, the corners in any order) or
// "cx,cy,cz,r" (sphere = true; r > 0). Throws Error(InvalidArgument) naming
// `option` for anything else, including non-finite numbers.
RegionOfInterest parse_region(const std::string& text, bool sphere, const std::string& option);
// The same from the numbers themselves (6 for a box, 4 for a sphere).
RegionOfInterest make_region(const std::vector<double>& values, bool sphere, const std::string& option);

}  // namespace isowave
