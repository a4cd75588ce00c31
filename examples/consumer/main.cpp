// Uses the installed isowave libraries the way an application would: a
// generated sphere field, its isosurface, the whole conversion to an .isw
// file, and the file decoded back to the fine control points. Checks each
// step against the sphere's own geometry; prints the counts; exit code 0 when
// every check holds.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "isowave/codec/isw_format.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/extract/isosurface.h"
#include "isowave/pipeline/convert.h"
#include "isowave/transform/wavelet_transform.h"

namespace {

int failures = 0;

void check(bool holds, const char* what) {
  std::printf("%s: %s\n", holds ? "ok" : "FAILED", what);
  failures += holds ? 0 : 1;
}

}  // namespace

int main() {
  using namespace isowave;
  // builtin_fields.h: R - |p - c| on an N^3 grid of unit spacing, R = 0.35 (N - 1).
  const std::size_t n = 32;
  const double radius = 0.35 * double(n - 1);
  const Vec3 centre{0.5 * double(n - 1), 0.5 * double(n - 1), 0.5 * double(n - 1)};
  try {
    const Volume volume = make_builtin_field("sphere", n);
    const Isosurface surface = extract_isosurface(volume);
    const SurfaceStatistics& stats = surface.report.after;
    std::printf("isosurface: %zu vertices, %zu triangles, genus %lld, area %.2f\n", stats.vertices, stats.faces,
                stats.genus, surface_area(surface.mesh));
    check(stats.components == 1 && stats.genus == 0 && stats.boundary_edges == 0, "one closed genus-0 surface");
    const double area = 4.0 * M_PI * radius * radius;
    check(std::abs(surface_area(surface.mesh) - area) < 0.02 * area, "area within 2% of 4 pi R^2");

    ConvertOptions options;
    options.levels = 2;
    const ConvertResult result = convert_volume(volume, "builtin:sphere", options);
    const std::string path =
        (std::filesystem::temp_directory_path() / ("isowave_consumer_" + std::to_string(getpid()) + ".isw")).string();
    write_isw(path, result.bytes, /*overwrite=*/true);
    const IswDecoded decoded = read_isw(path);
    std::filesystem::remove(path);
    std::printf("file: %zu bytes; base %zu vertices, %d levels, %zu fine vertices\n", result.bytes.size(),
                decoded.base.positions.size(), decoded.levels, decoded.coefficients.size());
    check(decoded.levels == 2 && decoded.coefficients.size() == result.fine_vertices, "the file holds every level");

    // The full decode: fine control points, fitted onto the sphere.
    std::vector<Vec3> points = decoded.coefficients;
    synthesize(*decoded.hierarchy, points);
    double worst = 0;
    for (const Vec3& p : points) worst = std::max(worst, std::abs(norm(p - centre) - radius));
    std::printf("decoded fine control points: at most %.3f cells off the sphere\n", worst);
    check(worst < 0.1, "every decoded fine control point within a tenth of a cell of the sphere");
  } catch (const std::exception& error) {  // isowave::Error and std::bad_alloc
    std::fprintf(stderr, "isowave_consumer: %s\n", error.what());
    return 1;
  }
  return failures == 0 ? 0 : 1;
}
