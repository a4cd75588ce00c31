// Rate-distortion of the two fits (issue #33, item 2: "the default is the one
// with the lower D at equal file size"): for one volume and isovalue, what a
// user decodes from each fit's file. Each fit's convert runs in a forked
// child (surface_bench.h); for each coefficient percentage of the file's
// summary (100, 50, 20, 10, 5 and the base mesh alone) this decodes the file
// as `isowave decode --percent P` does (decode_isw with max_percent, the
// finest control mesh) and prints the bytes that decode reads (the summary
// row's file prefix), bits per vertex of the marching-cubes mesh, and D of
// the decoded mesh against the reference (the marching-cubes mesh of a 2x
// trilinear upsample). Draco's curve on the marching-cubes mesh (-qp 8..16,
// -cl 10, decoded and measured the same way) is added when draco_encoder and
// draco_decoder are on PATH.
//
// Then each pair of curves at equal size: both curves' log D, linear in log
// bytes between a curve's points, at the byte counts of both inside the range
// both cover, and a Bjontegaard-style mean of log10 D(A) - log10 D(B) over
// that range (the exact integral of the difference of the two piecewise
// linear curves), printed as the ratio of D at equal size.
//
// usage: bench_fit_rate_distortion VOLUME --iso V [--levels N] [--min-component-vertices N] [--smooth S] [--topology-tolerance T]
//                                  [--fit shrink-wrap|parametrization|normal|both|all]
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "surface_bench.h"

using namespace isowave;
using namespace isowave::bench;

namespace {

// The coefficient percentages decoded (the base-mesh row is added).
const std::vector<double> kPercents{100, 50, 20, 10, 5};
// Draco's position quantization bits and its compression level.
const std::vector<int> kDracoQuantization{8, 9, 10, 11, 12, 14, 16};
constexpr int kDracoLevel = 10;

struct RatePoint {
  std::string label;
  std::uint64_t bytes = 0;
  double d = 0;  // world units
};

struct Curve {
  std::string name;
  std::vector<RatePoint> points;
};

void print_table_head() {
  std::printf("| decode | bytes | bits/vertex | decoded vertices | D %% | forward RMS %% | backward RMS %% |\n"
              "|---|---|---|---|---|---|---|\n");
}

// Prints a point's row and adds it to `curve`.
void add_point(Curve& curve, std::string label, std::uint64_t bytes, const PolygonMesh& decoded, const Surfaces& s) {
  const SurfaceError e = surface_error(decoded, s.reference);
  const auto pct = [&](double value) { return 100 * value / s.cell; };
  std::printf("| %s %s | %llu | %.2f | %zu | %.3f | %.3f | %.3f |\n", curve.name.c_str(), label.c_str(),
              static_cast<unsigned long long>(bytes), 8.0 * double(bytes) / double(s.marching_cubes.vertex_count()),
              decoded.vertex_count(), pct(e.d()), pct(e.forward_rms), pct(e.backward_rms));
  std::fflush(stdout);
  curve.points.push_back({std::move(label), bytes, e.d()});
}

// The share of the wavelet coefficients' squared length along the normal of
// `fine` (area-weighted vertex normals; coefficient i belongs to fine vertex
// i): detail across the surface. The rest moves points along the surface,
// which costs bits and changes the surface little.
double normal_share(const std::vector<Vec3>& coefficients, std::size_t base, const PolygonMesh& fine) {
  std::vector<Vec3> normals(fine.vertex_count());
  for (std::size_t f = 0; f < fine.face_count(); ++f) {
    const std::uint32_t* v = fine.face_begin(f);
    Vec3 area;  // twice the vector area of the polygon's fan
    for (std::uint32_t c = 2; c < fine.face_size(f); ++c)
      area += cross(fine.positions[v[c - 1]] - fine.positions[v[0]], fine.positions[v[c]] - fine.positions[v[0]]);
    for (std::uint32_t c = 0; c < fine.face_size(f); ++c) normals[v[c]] += area;
  }
  double along = 0, total = 0;
  for (std::size_t i = base; i < coefficients.size(); ++i) {
    along += std::pow(dot(coefficients[i], normalized(normals[i])), 2);
    total += squared_norm(coefficients[i]);
  }
  return total > 0 ? along / total : 0;
}

// The fit's file decoded at each percentage as `isowave decode --percent P` does.
Curve fit_curve(FitMethod fit, const FitOutcome& outcome, const Surfaces& s) {
  Curve curve{fit_name(fit), {}};
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;  // built by the first decode, reused
  double full_normal_share = 0;
  for (std::size_t r = 0; r < outcome.summary.size(); ++r) {
    const RateDistortionRow& row = outcome.summary[r];
    IswDecodeOptions options;
    options.max_percent = row.is_base ? 0 : kPercents[r];
    options.hierarchy = hierarchy;
    IswDecoded decoded = decode_isw(outcome.file, curve.name, options);
    hierarchy = decoded.hierarchy;
    if (decoded.ranked.size() != row.wavelet_coefficients)
      std::printf("(%s: the decode kept %zu coefficients, the summary row %zu)\n", curve.name.c_str(),
                  decoded.ranked.size(), row.wavelet_coefficients);
    const std::vector<Vec3> coefficients = r == 0 ? decoded.coefficients : std::vector<Vec3>{};
    const PolygonMesh mesh =
        hierarchy->control_mesh(decoded.levels, take_reconstruction(decoded, decoded.ranked.size()));
    if (r == 0) full_normal_share = normal_share(coefficients, decoded.base.vertex_count(), mesh);
    char label[32];
    if (row.is_base) std::snprintf(label, sizeof label, "base (%.2f%%)", row.percent);
    else std::snprintf(label, sizeof label, "%g%%", kPercents[r]);
    add_point(curve, label, row.bytes, mesh, s);
  }
  std::printf("\n%s at 100%%: %.1f%% of the wavelet coefficients' squared length lies along the surface normal\n",
              curve.name.c_str(), 100 * full_normal_share);
  return curve;
}

// Draco's curve: the marching-cubes mesh encoded at each quantization,
// decoded, and measured like the fits'.
Curve draco_curve(const Surfaces& s) {
  Curve curve{"draco", {}};
  const DracoCoder draco(s.marching_cubes);
  for (const int qp : kDracoQuantization)
    if (const std::optional<DracoCoded> coded = draco.code(qp, kDracoLevel))
      add_point(curve, "-qp " + std::to_string(qp), coded->bytes, coded->decoded, s);
  return curve;
}

// ---------------------------------------------------------------------------
// Curves at equal size.

// (log10 bytes, log10 D) by increasing bytes; of points with equal bytes the
// lowest D (what a reader paying those bytes can have).
std::vector<std::pair<double, double>> log_points(const Curve& curve) {
  std::vector<std::pair<double, double>> points;
  for (const RatePoint& p : curve.points) points.emplace_back(std::log10(double(p.bytes)), std::log10(p.d));
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end(),
                           [](const auto& a, const auto& b) { return a.first == b.first; }),
               points.end());
  return points;
}

// log10 D on `points` at log10 bytes `x`, linear between neighbours;
// precondition: x within the points' range.
double log_d_at(const std::vector<std::pair<double, double>>& points, double x) {
  const auto above = std::lower_bound(points.begin(), points.end(), std::make_pair(x, -HUGE_VAL));
  if (above == points.begin()) return above->second;
  const auto below = above - 1;
  if (above == points.end()) return below->second;
  const double t = (x - below->first) / (above->first - below->first);
  return below->second + t * (above->second - below->second);
}

// Both curves at the byte counts of either inside the range both cover, then
// the mean log D difference over that range.
void compare(const Curve& a, const Curve& b, double cell) {
  const auto pa = log_points(a), pb = log_points(b);
  if (pa.size() < 2 || pb.size() < 2) return;
  const double low = std::max(pa.front().first, pb.front().first), high = std::min(pa.back().first, pb.back().first);
  std::printf("\n%s against %s at equal size:\n", a.name.c_str(), b.name.c_str());
  if (!(low < high)) {
    std::printf("  the curves do not overlap in bytes (%s %.0f..%.0f, %s %.0f..%.0f)\n", a.name.c_str(),
                std::pow(10, pa.front().first), std::pow(10, pa.back().first), b.name.c_str(),
                std::pow(10, pb.front().first), std::pow(10, pb.back().first));
    return;
  }
  // The byte counts of both curves inside the common range; both curves are
  // linear in between, so the trapezoid rule over them and the range's ends
  // integrates the difference exactly.
  std::vector<double> xs{low, high};
  for (const auto* points : {&pa, &pb})
    for (const auto& point : *points)
      if (point.first > low && point.first < high) xs.push_back(point.first);
  std::sort(xs.begin(), xs.end());
  std::printf("| bytes | D %% %s | D %% %s | ratio |\n|---|---|---|---|\n", a.name.c_str(), b.name.c_str());
  for (const double x : xs) {
    const double da = std::pow(10, log_d_at(pa, x)), db = std::pow(10, log_d_at(pb, x));
    std::printf("| %.0f | %.3f | %.3f | %.2f |\n", std::pow(10, x), 100 * da / cell, 100 * db / cell, da / db);
  }
  double integral = 0;
  for (std::size_t i = 1; i < xs.size(); ++i) {
    const double d0 = log_d_at(pa, xs[i - 1]) - log_d_at(pb, xs[i - 1]);
    const double d1 = log_d_at(pa, xs[i]) - log_d_at(pb, xs[i]);
    integral += 0.5 * (d0 + d1) * (xs[i] - xs[i - 1]);
  }
  const double mean = integral / (high - low);
  std::printf("mean log10 D(%s) - log10 D(%s) over %.0f..%.0f bytes: %+.3f, D(%s) = %.2f x D(%s) at equal size\n",
              a.name.c_str(), b.name.c_str(), std::pow(10, low), std::pow(10, high), mean, a.name.c_str(),
              std::pow(10, mean), b.name.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions o = parse_options(argc, argv, "bench_fit_rate_distortion");
  o.summary_percents = kPercents;
  try {
    const FitRuns runs = run_fits(o);
    const Surfaces& s = runs.surfaces;
    std::vector<Curve> curves;
    for (std::size_t i = 0; i < o.fits.size(); ++i)
      if (print_fit(o.fits[i], runs.outcomes[i], s, runs.marching_cubes_d)) {
        std::printf("\n");
        print_table_head();
        curves.push_back(fit_curve(o.fits[i], runs.outcomes[i], s));
        std::printf("\n");
      }
    if (DracoCoder::available()) {
      std::printf("draco on the marching-cubes mesh (-cl %d):\n\n", kDracoLevel);
      print_table_head();
      curves.push_back(draco_curve(s));
    } else {
      std::printf("draco_encoder or draco_decoder not on PATH: no Draco curve\n");
    }
    for (std::size_t a = 0; a < curves.size(); ++a)
      for (std::size_t b = a + 1; b < curves.size(); ++b) compare(curves[a], curves[b], s.cell);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_fit_rate_distortion: %s\n", e.what());
    return 1;
  }
  return 0;
}
