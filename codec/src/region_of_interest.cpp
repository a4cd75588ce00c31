#include "isowave/codec/region_of_interest.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "isowave/core/error.h"

namespace isowave {

bool RegionOfInterest::contains(const Vec3& p) const {
  if (shape == Shape::Sphere) return squared_norm(p - centre) <= radius * radius;
  return p.x >= low.x && p.x <= high.x && p.y >= low.y && p.y <= high.y && p.z >= low.z && p.z <= high.z;
}

double RegionOfInterest::distance(const Vec3& p) const {
  if (shape == Shape::Sphere) return std::max(0.0, norm(p - centre) - radius);
  return norm(p - clamp_to_box(p, low, high));
}

bool RegionOfInterest::meets_box(const Vec3& lo, const Vec3& hi) const {
  if (shape == Shape::Sphere) {
    return squared_norm(clamp_to_box(centre, lo, hi) - centre) <= radius * radius;
  }
  return lo.x <= high.x && hi.x >= low.x && lo.y <= high.y && hi.y >= low.y && lo.z <= high.z && hi.z >= low.z;
}

RegionOfInterest parse_region(const std::string& text, bool sphere, const std::string& option) {
  const std::size_t expected = sphere ? 4 : 6;
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v))
      throw Error(ErrorKind::InvalidArgument, option + " expects " + std::to_string(expected) +
                                                  " comma-separated finite numbers, got '" + text + "'");
    values.push_back(v);
  }
  return make_region(values, sphere, option);
}

RegionOfInterest make_region(const std::vector<double>& values, bool sphere, const std::string& option) {
  const std::size_t expected = sphere ? 4 : 6;
  if (values.size() != expected)
    throw Error(ErrorKind::InvalidArgument,
                option + " expects " + std::to_string(expected) + " numbers, got " + std::to_string(values.size()));
  for (const double v : values)
    if (!std::isfinite(v)) throw Error(ErrorKind::InvalidArgument, option + " expects finite numbers");
  RegionOfInterest region;
  if (sphere) {
    region.shape = RegionOfInterest::Shape::Sphere;
    region.centre = {values[0], values[1], values[2]};
    region.radius = values[3];
    if (!(region.radius > 0)) throw Error(ErrorKind::InvalidArgument, option + ": the radius must be positive");
  } else {
    region.low = {std::min(values[0], values[3]), std::min(values[1], values[4]), std::min(values[2], values[5])};
    region.high = {std::max(values[0], values[3]), std::max(values[1], values[4]), std::max(values[2], values[5])};
  }
  return region;
}

}  // namespace isowave
