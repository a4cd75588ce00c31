// Generated scalar fields (formulas in builtin_fields.h).
#include "isowave/extract/builtin_fields.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>

#include "isowave/core/error.h"

namespace isowave {
namespace {

constexpr double kPi = 3.14159265358979323846;

// splitmix64: a fixed, platform-independent pseudo-random sequence (the
// standard library's distributions are implementation-defined).
struct SplitMix {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
};

// Perlin's improved gradient noise (2002) with our own fixed permutation.
class GradientNoise {
 public:
  explicit GradientNoise(std::uint64_t seed) {
    std::array<int, 256> p;
    for (int i = 0; i < 256; ++i) p[i] = i;
    SplitMix rng{seed};
    for (int i = 255; i > 0; --i) std::swap(p[i], p[static_cast<int>(rng.next() % static_cast<std::uint64_t>(i + 1))]);
    for (int i = 0; i < 512; ++i) perm_[i] = p[i & 255];
  }

  // In about [-1, 1]; zero at integer points.
  double operator()(double x, double y, double z) const {
    const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const int X = static_cast<int>(fx) & 255, Y = static_cast<int>(fy) & 255, Z = static_cast<int>(fz) & 255;
    x -= fx;
    y -= fy;
    z -= fz;
    const double u = fade(x), v = fade(y), w = fade(z);
    const int A = perm_[X] + Y, AA = perm_[A] + Z, AB = perm_[A + 1] + Z;
    const int B = perm_[X + 1] + Y, BA = perm_[B] + Z, BB = perm_[B + 1] + Z;
    return lerp(w,
                lerp(v, lerp(u, grad(perm_[AA], x, y, z), grad(perm_[BA], x - 1, y, z)),
                     lerp(u, grad(perm_[AB], x, y - 1, z), grad(perm_[BB], x - 1, y - 1, z))),
                lerp(v, lerp(u, grad(perm_[AA + 1], x, y, z - 1), grad(perm_[BA + 1], x - 1, y, z - 1)),
                     lerp(u, grad(perm_[AB + 1], x, y - 1, z - 1), grad(perm_[BB + 1], x - 1, y - 1, z - 1))));
  }

  // Fractal sum of 5 octaves, lacunarity 2, gain 1/2; each octave shifted so
  // that the zeros at integer points do not line up.
  double fbm(double x, double y, double z) const {
    double sum = 0, amplitude = 1, frequency = 1;
    for (int octave = 0; octave < 5; ++octave) {
      const double shift = 17.31 * octave;
      sum += amplitude * (*this)(x * frequency + shift, y * frequency + 0.5 * shift, z * frequency + 0.25 * shift);
      amplitude *= 0.5;
      frequency *= 2;
    }
    return sum;
  }

 private:
  static double fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }
  static double lerp(double t, double a, double b) { return a + t * (b - a); }
  static double grad(int hash, double x, double y, double z) {
    const int h = hash & 15;
    const double u = h < 8 ? x : y;
    const double v = h < 4 ? y : (h == 12 || h == 14 ? x : z);
    return ((h & 1) == 0 ? u : -u) + ((h & 2) == 0 ? v : -v);
  }
  std::array<int, 512> perm_;
};

// Polynomial smooth maximum (width k): equals max(a, b) when |a - b| >= k.
double smooth_max(double a, double b, double k) {
  const double h = std::max(k - std::abs(a - b), 0.0) / k;
  return std::max(a, b) + h * h * k * 0.25;
}

double torus_value(double x, double y, double z, double major, double minor) {
  const double ring = std::sqrt(x * x + y * y) - major;
  return minor - std::sqrt(ring * ring + z * z);
}

// Fills every sample with value(i, j, k), parallel over z.
Volume sample(std::size_t n, const std::function<void(std::size_t k, float* slice)>& fill_slice) {
  Volume volume;
  volume.dims = {n, n, n};
  volume.values.resize(n * n * n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t k = range.begin(); k != range.end(); ++k) fill_slice(k, volume.values.data() + k * n * n);
  });
  return volume;
}

template <typename Function>
Volume sample_points(std::size_t n, Function value) {
  return sample(n, [&](std::size_t k, float* slice) {
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t i = 0; i < n; ++i)
        slice[i + n * j] =
            static_cast<float>(value(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
  });
}

Volume make_sphere(std::size_t n) {
  const double size = static_cast<double>(n - 1), c = 0.5 * size, radius = 0.35 * size;
  return sample_points(n, [=](double x, double y, double z) {
    return radius - std::sqrt((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c));
  });
}

Volume make_torus(std::size_t n) {
  const double size = static_cast<double>(n - 1), c = 0.5 * size;
  return sample_points(
      n, [=](double x, double y, double z) { return torus_value(x - c, y - c, z - c, 0.25 * size, 0.1 * size); });
}

Volume make_genus3(std::size_t n) {
  const double size = static_cast<double>(n - 1), c = 0.5 * size;
  const double major = 0.1 * size, minor = 0.045 * size, spacing = 2 * major + minor, width = 0.01 * size;
  return sample_points(n, [=](double x, double y, double z) {
    x -= c;
    y -= c;
    z -= c;
    const double left = torus_value(x + spacing, y, z, major, minor);
    const double middle = torus_value(x, y, z, major, minor);
    const double right = torus_value(x - spacing, y, z, major, minor);
    return smooth_max(smooth_max(left, middle, width), right, width);
  });
}

Volume make_marschner_lobb(std::size_t n) {
  const double size = static_cast<double>(n - 1);
  constexpr double frequency = 6, alpha = 0.25;
  return sample_points(n, [=](double i, double j, double k) {
    const double x = 2 * i / size - 1, y = 2 * j / size - 1, z = 2 * k / size - 1;
    const double r = std::sqrt(x * x + y * y);
    const double radial = std::cos(2 * kPi * frequency * std::cos(kPi * r / 2));
    return (1 - std::sin(kPi * z / 2) + alpha * (1 + radial)) / (2 * (1 + alpha)) - 0.5;
  });
}

struct Blob {
  double x, y, z, radius;
  bool heavy;  // heavy droplet (positive inside) or light bubble (negative inside)
};

Volume make_mixing(std::size_t n) {
  // Layer half-width, turbulence amplitude and base frequency (per box size).
  constexpr double kLayerWidth = 0.16, kTurbulence = 0.3, kFrequency = 4;
  const double size = static_cast<double>(n - 1);
  const GradientNoise interface_noise(0x5EED0001), turbulence(0x5EED0002);

  // Detached heavy droplets below the layer and light bubbles above it.
  std::vector<Blob> blobs;
  SplitMix rng{0x5EED0003};
  for (int b = 0; b < 48; ++b) {
    Blob blob;
    blob.heavy = b % 2 == 0;
    blob.x = 0.05 + 0.9 * rng.uniform();
    blob.y = 0.05 + 0.9 * rng.uniform();
    const double depth = 0.14 + 0.14 * rng.uniform();
    blob.z = blob.heavy ? 0.5 - depth : 0.5 + depth;
    blob.radius = 0.012 + 0.025 * rng.uniform();
    blobs.push_back(blob);
  }

  // Interface height per column.
  std::vector<double> height(n * n);
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t i = 0; i < n; ++i) height[i + n * j] = 0.05 * interface_noise.fbm(3 * i / size, 3 * j / size, 0.5);

  return sample(n, [&](std::size_t k, float* slice) {
    const double uz = k / size;
    std::vector<const Blob*> nearby;
    for (const Blob& blob : blobs)
      if (std::abs(uz - blob.z) < blob.radius) nearby.push_back(&blob);
    for (std::size_t j = 0; j < n; ++j) {
      const double uy = j / size;
      for (std::size_t i = 0; i < n; ++i) {
        const double ux = i / size;
        const double s = uz - 0.5 - height[i + n * j];
        const double envelope = std::exp(-(s / kLayerWidth) * (s / kLayerWidth));
        double value = s;
        if (envelope > 1e-4)
          value += kTurbulence * envelope * turbulence.fbm(kFrequency * ux, kFrequency * uy, kFrequency * uz);
        for (const Blob* blob : nearby) {
          const double dx = ux - blob->x, dy = uy - blob->y, dz = uz - blob->z;
          const double distance = std::sqrt(dx * dx + dy * dy + dz * dz);
          value = blob->heavy ? std::max(value, blob->radius - distance) : std::min(value, distance - blob->radius);
        }
        slice[i + n * j] = static_cast<float>(value);
      }
    }
  });
}

}  // namespace

const std::vector<std::string>& builtin_field_names() {
  static const std::vector<std::string> names{"sphere", "torus", "genus3", "marschner-lobb", "mixing"};
  return names;
}

Volume make_builtin_field(const std::string& name, std::size_t n) {
  if (n < 8 || n > 1024)
    throw Error(ErrorKind::InvalidArgument, "builtin:" + name + ": size " + std::to_string(n) + " is outside 8..1024");
  if (name == "sphere") return make_sphere(n);
  if (name == "torus") return make_torus(n);
  if (name == "genus3") return make_genus3(n);
  if (name == "marschner-lobb") return make_marschner_lobb(n);
  if (name == "mixing") return make_mixing(n);
  std::string known;
  for (const std::string& candidate : builtin_field_names()) known += (known.empty() ? "" : ", ") + candidate;
  throw Error(ErrorKind::InvalidArgument, "builtin:" + name + ": unknown field (known: " + known + ")");
}

}  // namespace isowave
