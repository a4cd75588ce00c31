// View-dependent decoding (issue #48, items 2 and 6): a file read for a
// camera's frustum, its ViewRefiner built, the first view set and every patch
// emitted, then the camera turned by a few degrees about its up axis and
// only the changed patches emitted again. Targets (miranda, a camera inside
// the box, 1 pixel on 1920 x 1080): the first view <= 0.3 s, an update after a
// 10 degree turn <= 50 ms.
//
// usage: bench_view FILE.isw CAMERA.json [--turn DEGREES] [--pixel-error P]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/view.h"
#include "isowave/core/error.h"

using namespace isowave;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Every patch of `faces`, emitted as a viewer would (into reused buffers); the corners.
std::size_t emit(const ViewRefiner& refiner, const std::vector<std::uint32_t>& faces) {
  std::vector<std::uint32_t> offsets, corners;
  for (const std::uint32_t f : faces) refiner.patch(f, offsets, corners);
  return corners.size();
}

// The camera's target turned by `degrees` about its up axis through its position.
Camera turned(Camera c, double degrees) {
  const Vec3 d = c.target - c.position, u = normalized(c.up);
  const double a = degrees * 3.14159265358979323846 / 180;
  // Rodrigues' rotation of d about u.
  c.target = c.position + d * std::cos(a) + cross(u, d) * std::sin(a) + u * (dot(u, d) * (1 - std::cos(a)));
  return c;
}

int run(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_view FILE.isw CAMERA.json [--turn DEGREES] [--pixel-error P]\n");
    return 2;
  }
  double turn = 10, pixel_error = 1;
  for (int k = 3; k + 1 < argc; k += 2) {
    if (std::strcmp(argv[k], "--turn") == 0) turn = std::stod(argv[k + 1]);
    else if (std::strcmp(argv[k], "--pixel-error") == 0) pixel_error = std::stod(argv[k + 1]);
  }
  const Camera camera = read_camera(argv[2]);
  auto start = Clock::now();
  IswDecodeOptions options;
  options.frustum = camera;
  options.order = IswOrder::Index;
  const IswDecoded decoded = read_isw(argv[1], options);
  const double read = seconds_since(start);
  start = Clock::now();
  ViewRefiner refiner(decoded);
  const double build = seconds_since(start);
  start = Clock::now();
  const std::vector<std::uint32_t> first = refiner.set_view(camera, pixel_error);
  const std::size_t corners = emit(refiner, first);
  const double first_view = seconds_since(start);
  std::printf("%s: read %llu of %llu bytes (%zu of %zu groups) %.3f s, refiner %.3f s, first view %.3f s (%zu "
              "patches, %zu corners): %.3f s in all\n",
              argv[1], static_cast<unsigned long long>(decoded.file_bytes_read),
              static_cast<unsigned long long>(decoded.file_bytes), decoded.stream.groups_decoded,
              decoded.stream.groups, read, build, first_view, first.size(), corners, read + build + first_view);
  std::printf("  decode phases: headers %.3f, hierarchy %.3f (waited %.3f), planes %.3f, to world %.3f, rank %.3f s\n",
              decoded.seconds.headers, decoded.seconds.hierarchy, decoded.seconds.hierarchy_wait,
              decoded.seconds.chunks, decoded.seconds.dequantize, decoded.seconds.rank);
  double best = 1e9;
  std::size_t changed = 0, emitted = 0;
  for (int k = 0; k < 3; ++k) {
    refiner.set_view(camera, pixel_error);
    start = Clock::now();
    const std::vector<std::uint32_t> faces = refiner.set_view(turned(camera, turn), pixel_error);
    emitted = emit(refiner, faces);
    best = std::min(best, seconds_since(start));
    changed = faces.size();
  }
  std::printf("turn of %g degrees: %zu of %zu patches changed (%zu corners), %.1f ms (best of 3)\n", turn, changed,
              refiner.levels().levels.size(), emitted, 1000 * best);
  return 0;
}

}  // namespace

int main(int argc, char** argv) try {
  return run(argc, argv);
} catch (const std::exception& error) {
  std::fprintf(stderr, "bench_view: %s\n", error.what());
  return 1;
}
