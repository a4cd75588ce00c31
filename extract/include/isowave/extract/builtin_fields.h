#pragma once
// Generated scalar fields for tests and the demo, sampled on an N^3 grid with
// the surface of interest at value 0 (see builtin_field_names()).
//
// Every field is sampled at the integer points (i, j, k), 0 <= i, j, k < N,
// with unit spacing and origin 0, so world coordinates are voxel indices. The
// formulas use p = (i, j, k), the box centre c = (N-1)/2 * (1, 1, 1), the
// box size L = N - 1 and normalised coordinates u = p / L in [0, 1]^3.
// Values are positive on the "inside" (higher-valued) side of the surface,
// so extracted normals, which point toward lower values, point outward.
//
//   sphere          R - |p - c|,  R = 0.35 L  (closed, genus 0, area 4 pi R^2)
//   torus           r - sqrt((sqrt(x^2 + y^2) - R)^2 + z^2) with (x, y, z) = p - c,
//                   R = 0.25 L, r = 0.1 L  (closed, genus 1, area 4 pi^2 R r)
//   genus3          three such tori (R = 0.1 L, r = 0.045 L) in the z = 0 plane
//                   centred at x = -d, 0, +d, d = 2R + r, joined by a smooth
//                   maximum (polynomial smooth max, width 0.01 L): their tubes
//                   merge but their core circles stay apart, so the union is
//                   a closed surface of genus 3
//   marschner-lobb  the Marschner-Lobb test signal (Marschner and Lobb 1994)
//                   on [-1, 1]^3 minus its usual isovalue 1/2:
//                   (1 - sin(pi z / 2) + a (1 + cos(2 pi f cos(pi r / 2)))) / (2 (1 + a)) - 1/2,
//                   r = sqrt(x^2 + y^2), f = 6, a = 1/4. A rippled sheet near
//                   z = 0 that meets the four side faces of the box (as the
//                   standard signal does).
//   mixing          a procedural stand-in for a Rayleigh-Taylor mixing layer
//                   (heavy fluid on top, positive): with s = u_z - 1/2 - h(u_x, u_y),
//                   h = 0.05 fbm2(3 u_x, 3 u_y) the large-scale interface waves,
//                   value = s + 0.3 exp(-(s / 0.16)^2) fbm3(4 u) combined with a
//                   deterministic set of spherical heavy droplets below and light
//                   bubbles above the layer. fbm is 5 octaves of gradient noise
//                   (lacunarity 2, gain 1/2) from a fixed permutation, so the field
//                   is identical on every platform (the noise term is skipped
//                   where the envelope is below 1e-4, far from the surface).
//                   The layer meets the four side faces of the box (exercising
//                   boundaries) and stays away from the top and bottom faces; at
//                   N = 128 it has about 80 components and genus about 35.
//
// Sampling is parallel (TBB) and deterministic; cost O(N^3).
#include <string>
#include <vector>

#include "isowave/core/volume.h"

namespace isowave {

// "sphere", "torus", "genus3", "marschner-lobb", "mixing".
const std::vector<std::string>& builtin_field_names();

// Throws Error(InvalidArgument) for an unknown name or N outside 8..1024.
Volume make_builtin_field(const std::string& name, std::size_t n = 128);

}  // namespace isowave
