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

namespace detail {

// Cell index along one axis and the fraction inside it, with clamping.
ISOWAVE_TRILINEAR_INLINE void locate(double world, double origin, double spacing, std::size_t samples, std::size_t& cell, double& t) {
  double g = (world - origin) / spacing;
  const double last = static_cast<double>(samples - 1);
  if (!(g > 0)) g = 0;  // also catches NaN
  if (g > last) g = last;
  std::size_t c = static_cast<std::size_t>(g);
  if (c > samples - 2) c = samples - 2;
  cell = c;
  t = g - static_cast<double>(c);
}

}  // namespace detail

// Interpolated value at p. O(1).
ISOWAVE_TRILINEAR_INLINE double trilinear_value(const Volume& volume, const Vec3& p) {
  assert(volume.dims[0] >= 2 && volume.dims[1] >= 2 && volume.dims[2] >= 2);
  std::size_t i, j, k;
  double u, v, w;
  detail::locate(p.x, volume.origin.x, volume.spacing.x, volume.dims[0], i, u);
  detail::locate(p.y, volume.origin.y, volume.spacing.y, volume.dims[1], j, v);
  detail::locate(p.z, volume.origin.z, volume.spacing.z, volume.dims[2], k, w);
  const std::size_t sx = 1, sy = volume.dims[0], sz = volume.dims[0] * volume.dims[1];
  const float* c = volume.values.data() + i + sy * j + sz * k;
  const double c00 = c[0] + u * (c[sx] - c[0]);
  const double c10 = c[sy] + u * (c[sy + sx] - c[sy]);
  const double c01 = c[sz] + u * (c[sz + sx] - c[sz]);
  const double c11 = c[sz + sy] + u * (c[sz + sy + sx] - c[sz + sy]);
  const double c0 = c00 + v * (c10 - c00);
  const double c1 = c01 + v * (c11 - c01);
  return c0 + w * (c1 - c0);
}

// Interpolated value and gradient at p. On a cell face the gradient of the
// cell with the lower index is returned (the interpolant is only C0 there).
ISOWAVE_TRILINEAR_INLINE TrilinearSample trilinear_sample(const Volume& volume, const Vec3& p) {
  assert(volume.dims[0] >= 2 && volume.dims[1] >= 2 && volume.dims[2] >= 2);
  std::size_t i, j, k;
  double u, v, w;
  detail::locate(p.x, volume.origin.x, volume.spacing.x, volume.dims[0], i, u);
  detail::locate(p.y, volume.origin.y, volume.spacing.y, volume.dims[1], j, v);
  detail::locate(p.z, volume.origin.z, volume.spacing.z, volume.dims[2], k, w);
  const std::size_t sx = 1, sy = volume.dims[0], sz = volume.dims[0] * volume.dims[1];
  const float* c = volume.values.data() + i + sy * j + sz * k;
  const double v000 = c[0], v100 = c[sx], v010 = c[sy], v110 = c[sy + sx];
  const double v001 = c[sz], v101 = c[sz + sx], v011 = c[sz + sy], v111 = c[sz + sy + sx];
  // Interpolate along x first, then y, then z; derivatives by the product rule.
  const double c00 = v000 + u * (v100 - v000), c10 = v010 + u * (v110 - v010);
  const double c01 = v001 + u * (v101 - v001), c11 = v011 + u * (v111 - v011);
  const double c0 = c00 + v * (c10 - c00), c1 = c01 + v * (c11 - c01);
  TrilinearSample s;
  s.value = c0 + w * (c1 - c0);
  const double dx00 = v100 - v000, dx10 = v110 - v010, dx01 = v101 - v001, dx11 = v111 - v011;
  const double dx0 = dx00 + v * (dx10 - dx00), dx1 = dx01 + v * (dx11 - dx01);
  s.gradient.x = (dx0 + w * (dx1 - dx0)) / volume.spacing.x;
  s.gradient.y = ((c10 - c00) + w * ((c11 - c01) - (c10 - c00))) / volume.spacing.y;
  s.gradient.z = (c1 - c0) / volume.spacing.z;
  return s;
}

// Lowest and highest world corner of the volume's box.
inline Vec3 volume_box_min(const Volume& volume) { return volume.origin; }
inline Vec3 volume_box_max(const Volume& volume) {
  return volume.world(static_cast<double>(volume.dims[0] - 1), static_cast<double>(volume.dims[1] - 1),
                      static_cast<double>(volume.dims[2] - 1));
}

}  // namespace isowave
