// View-dependent decoding (issue #48, items 2 and 6): a file read for a
// camera's frustum, its ViewRefiner built, the first view set and every patch
// emitted, then the camera turned by a few degrees about its up axis and
// only the changed patches emitted again; then one camera's mesh with the
// whole hierarchy and over a patch (decode --view). Targets (miranda, a camera inside
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

// One camera's mesh (decode --view): read_isw and view_mesh() with the
// whole hierarchy and over a patch (best of 3 each), and the two meshes
// compared (faces equal; the largest distance between vertices of faces in
// view, in units of the longest side of the base mesh's box).
void compare_scopes(const char* path, const Camera& camera, double pixel_error) {
  PolygonMesh meshes[2];
  ViewLevels levels[2];
  for (const auto scope : {IswDecodeOptions::ViewScope::Whole, IswDecodeOptions::ViewScope::Patch}) {
    const int k = scope == IswDecodeOptions::ViewScope::Patch;
    IswDecodeOptions options;
    options.frustum = camera;
    options.order = IswOrder::Index;
    options.view_scope = scope;
    double best = 1e9;
    for (int run = 0; run < 3; ++run) {
      const auto start = Clock::now();
      meshes[k] = view_mesh(read_isw(path, options), camera, pixel_error, &levels[k]);
      best = std::min(best, seconds_since(start));
    }
    std::printf("view_mesh over %s: %.3f s (best of 3), %zu vertices, %zu faces, %zu base faces outside the frustum\n",
                k ? "a patch" : "the whole hierarchy", best, meshes[k].vertex_count(), meshes[k].face_count(),
                levels[k].culled);
  }
  const bool same = meshes[0].face_vertices == meshes[1].face_vertices && levels[0].levels == levels[1].levels &&
                    meshes[0].vertex_count() == meshes[1].vertex_count();
  // Vertices of faces at level 1 or finer, and of level-0 faces in view (every vertex but base vertices of culled faces only).
  double largest = 0, extent = 0;
  Vec3 lo = meshes[0].positions.empty() ? Vec3{} : meshes[0].positions[0], hi = lo;
  for (const Vec3& p : meshes[0].positions) {
    lo = component_min(lo, p);
    hi = component_max(hi, p);
  }
  for (int a = 0; a < 3; ++a) extent = std::max(extent, hi[a] - lo[a]);
  std::size_t compared = 0;
  for (std::size_t v = 0; same && v < meshes[0].vertex_count(); ++v)
    if (!camera.box_outside(meshes[0].positions[v], meshes[0].positions[v])) {
      ++compared;
      largest = std::max(largest, norm(meshes[0].positions[v] - meshes[1].positions[v]));
    }
  std::printf("  faces and levels %s; %zu vertices in the frustum, largest distance there %.3g of the box's side\n",
              same ? "equal" : "DIFFER", compared, extent > 0 ? largest / extent : 0.0);
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
  compare_scopes(argv[1], camera, pixel_error);
  return 0;
}

}  // namespace

int main(int argc, char** argv) try {
  return run(argc, argv);
} catch (const std::exception& error) {
  std::fprintf(stderr, "bench_view: %s\n", error.what());
  return 1;
}
