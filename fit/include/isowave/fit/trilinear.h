#pragma once
// Trilinear interpolation of a Volume's samples, and the gradient of that
// interpolant: the continuous field that the signed-distance seeds, the
// attraction line search and the final isosurface correction all evaluate
// (Bertram et al. 2000, Sec. 4.2: "trilinear or better").
//
// Positions are world coordinates (Volume::world); points outside the box are
// clamped onto it. Requires at least 2 samples along every axis (assert).
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstddef>

#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"

// The fitting loops call these hundreds of millions of times from inside
// lambdas, where GCC otherwise declines to inline them.
#if defined(__GNUC__) || defined(__clang__)
#define ISOWAVE_TRILINEAR_INLINE inline __attribute__((always_inline))
#else
#define ISOWAVE_TRILINEAR_INLINE inline
#endif

namespace isowave {

struct TrilinearSample {
  double value = 0;  // interpolated sample value (NaN if a corner is NaN)
  Vec3 gradient;     // derivative of the interpolant, value units per world unit
};

// The interpolant. The fitting loops sample one volume hundreds of millions
// of times, mostly along lines p + t d: strides, inverse spacings and clamp
// bounds are set up once and points may be given in grid coordinates
// (grid_point, grid_direction), so a sample on a line costs one multiply-add
// per axis and no division. Keeps a pointer to the volume's samples: the
// volume must outlive it and keep its size. O(1) per sample.
class TrilinearGrid {
 public:
  explicit TrilinearGrid(const Volume& volume) : TrilinearGrid(volume, volume.values.data()) {}
  // The volume's grid with other samples in the same layout (a copy of its
  // values elsewhere, e.g. on huge pages).
  TrilinearGrid(const Volume& volume, const float* values)
      : values_(values),
        stride_y_(volume.dims[0]),
        stride_z_(volume.dims[0] * volume.dims[1]),
        origin_(volume.origin),
        inverse_spacing_{1.0 / volume.spacing.x, 1.0 / volume.spacing.y, 1.0 / volume.spacing.z},
        last_{double(volume.dims[0] - 1), double(volume.dims[1] - 1), double(volume.dims[2] - 1)} {
    assert(volume.dims[0] >= 2 && volume.dims[1] >= 2 && volume.dims[2] >= 2);
  }

  // Grid coordinates (in cells from sample (0, 0, 0)) of a world position,
  // and of a world direction or offset.
  Vec3 grid_point(const Vec3& world) const {
    return {(world.x - origin_.x) * inverse_spacing_.x, (world.y - origin_.y) * inverse_spacing_.y,
            (world.z - origin_.z) * inverse_spacing_.z};
  }
  Vec3 grid_direction(const Vec3& direction) const {
    return {direction.x * inverse_spacing_.x, direction.y * inverse_spacing_.y, direction.z * inverse_spacing_.z};
  }

  // Interpolated value at grid coordinates g (clamped onto the box).
  ISOWAVE_TRILINEAR_INLINE double value_at(const Vec3& g) const {
    double u, v, w;
    const float* c = corner(g, u, v, w);
    const double c00 = c[0] + u * (c[1] - c[0]);
    const double c10 = c[stride_y_] + u * (c[stride_y_ + 1] - c[stride_y_]);
    const double c01 = c[stride_z_] + u * (c[stride_z_ + 1] - c[stride_z_]);
    const double c11 = c[stride_z_ + stride_y_] + u * (c[stride_z_ + stride_y_ + 1] - c[stride_z_ + stride_y_]);
    const double c0 = c00 + v * (c10 - c00);
    const double c1 = c01 + v * (c11 - c01);
    return c0 + w * (c1 - c0);
  }

  // Value and gradient (value units per world unit) at grid coordinates g;
  // on a cell face the gradient of the cell with the lower index.
  ISOWAVE_TRILINEAR_INLINE TrilinearSample sample_at(const Vec3& g) const {
    double u, v, w;
    const float* c = corner(g, u, v, w);
    const std::size_t sy = stride_y_, sz = stride_z_;
    const double v000 = c[0], v100 = c[1], v010 = c[sy], v110 = c[sy + 1];
    const double v001 = c[sz], v101 = c[sz + 1], v011 = c[sz + sy], v111 = c[sz + sy + 1];
    const double c00 = v000 + u * (v100 - v000), c10 = v010 + u * (v110 - v010);
    const double c01 = v001 + u * (v101 - v001), c11 = v011 + u * (v111 - v011);
    const double c0 = c00 + v * (c10 - c00), c1 = c01 + v * (c11 - c01);
    TrilinearSample s;
    s.value = c0 + w * (c1 - c0);
    const double dx00 = v100 - v000, dx10 = v110 - v010, dx01 = v101 - v001, dx11 = v111 - v011;
    const double dx0 = dx00 + v * (dx10 - dx00), dx1 = dx01 + v * (dx11 - dx01);
    s.gradient.x = (dx0 + w * (dx1 - dx0)) * inverse_spacing_.x;
    s.gradient.y = ((c10 - c00) + w * ((c11 - c01) - (c10 - c00))) * inverse_spacing_.y;
    s.gradient.z = (c1 - c0) * inverse_spacing_.z;
    return s;
  }

  double value(const Vec3& world) const { return value_at(grid_point(world)); }

  // Whether grid coordinates g lie in the box (within 1e-9 of a cell).
  bool inside(const Vec3& g) const {
    constexpr double slack = 1e-9;
    return g.x >= -slack && g.y >= -slack && g.z >= -slack && g.x <= last_.x + slack && g.y <= last_.y + slack &&
           g.z <= last_.z + slack;
  }
  TrilinearSample sample(const Vec3& world) const { return sample_at(grid_point(world)); }

  // Asks the cache for the samples around grid coordinates g (a hint; loops
  // over scattered points issue it a few points ahead).
  void prefetch_at(const Vec3& g) const {
#if defined(__GNUC__) || defined(__clang__)
    double u, v, w;
    const float* c = corner(g, u, v, w);
    __builtin_prefetch(c);
    __builtin_prefetch(c + stride_y_);
    __builtin_prefetch(c + stride_z_);
    __builtin_prefetch(c + stride_z_ + stride_y_);
#else
    (void)g;
#endif
  }

 private:
  // Lowest corner of the cell holding g (clamped onto the box) and the
  // fractions inside it; the top face belongs to the last cell.
  ISOWAVE_TRILINEAR_INLINE static std::size_t cell(double g, double last, double& t) {
    if (!(g > 0)) g = 0;  // also catches NaN
    if (g > last) g = last;
    const std::size_t c = static_cast<std::size_t>(std::min(g, last - 1.0));
    t = g - static_cast<double>(c);
    return c;
  }
  ISOWAVE_TRILINEAR_INLINE const float* corner(const Vec3& g, double& u, double& v, double& w) const {
    const std::size_t i = cell(g.x, last_.x, u), j = cell(g.y, last_.y, v), k = cell(g.z, last_.z, w);
    return values_ + i + stride_y_ * j + stride_z_ * k;
  }

  const float* values_;
  std::size_t stride_y_, stride_z_;
  Vec3 origin_, inverse_spacing_, last_;
};

// Lowest and highest world corner of the volume's box.
inline Vec3 volume_box_min(const Volume& volume) { return volume.origin; }
inline Vec3 volume_box_max(const Volume& volume) {
  return volume.world(static_cast<double>(volume.dims[0] - 1), static_cast<double>(volume.dims[1] - 1),
                      static_cast<double>(volume.dims[2] - 1));
}

}  // namespace isowave
