// Rate-distortion of isowave against Draco (issue #34, item 7, and its
// targets): for one volume and isovalue, `convert` with the CLI's defaults
// (one fit; --fit picks it) runs in a forked child (surface_bench.h), then
//  - isowave's curve: prefixes of its .isw file decoded as `isowave decode`
//    does (decode_isw of the first n bytes, the finest control mesh): the
//    file cut right after its header sections (where the first coefficient
//    section starts), at every chunk end, at kLogPrefixes byte counts spaced
//    evenly in log bytes up to the whole file, and the whole file. A prefix
//    that does not decode is a bug of the format's promise (any cut decodes):
//    printed loudly, counted, and the exit code is 1.
//  - Draco's curve: `draco_encoder -cl 10 -qp Q`, Q = 6..16, on the
//    marching-cubes mesh of the field (written as PLY), decoded by
//    draco_decoder.
// Each decoded mesh's D (surface_error(): the larger RMS distance of
// area-uniform samples each way, % of a cell) is measured against two
// references: the marching-cubes mesh itself, and the marching-cubes mesh of
// the 2x-upsampled field (Surfaces::reference). Both curves are printed as
// markdown tables (bytes, bits per marching-cubes vertex, D), then the
// BD-rate of isowave against Draco for each reference (bd_rate.h), then
// encode and decode times beside Draco's on the same mesh in the same run.
//
// usage: bench_rate_distortion VOLUME --iso V [--levels N] [--min-component-vertices N] [--smooth S]
//                              [--topology-tolerance T] [--flips] [--fit shrink-wrap|parametrization|normal|both|all] [--csv FILE]
//        bench_rate_distortion --self-test   (checks bd_rate() against analytic curves; exit code 1 on failure)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <functional>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "bd_rate.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "surface_bench.h"

using namespace isowave;
using namespace isowave::bench;

namespace {

constexpr int kDracoLevel = 10;                  // draco_encoder -cl
constexpr int kDracoBitsLow = 6, kDracoBitsHigh = 16;  // draco_encoder -qp range
constexpr int kDracoTimingBits = 11;             // the -qp timed
constexpr int kTimingRuns = 3;                   // timings are the best of these
constexpr int kLogPrefixes = 16;                 // log-spaced prefix byte counts

// ---------------------------------------------------------------------------
// Curves.

struct Point {
  std::string label;
  std::uint64_t bytes = 0;
  double d_marching_cubes = 0, d_reference = 0;  // D against each reference, world units
};

struct Curve {
  std::string name;
  std::vector<Point> points;
};

// The two references, each sampled and binned once for all the meshes measured.
struct References {
  explicit References(const Surfaces& s) : marching_cubes(s.marching_cubes), upsampled(s.reference) {}
  SurfaceErrorReference marching_cubes, upsampled;
};

Point measure(std::string label, std::uint64_t bytes, const PolygonMesh& mesh, const References& r) {
  return {std::move(label), bytes, r.marching_cubes.measure(mesh).d(), r.upsampled.measure(mesh).d()};
}

// The finest control mesh of a decode, as `isowave decode` writes it (takes
// the decoded coefficients).
PolygonMesh finest_mesh(IswDecoded& decoded) {
  return decoded.hierarchy->control_mesh(decoded.levels, take_reconstruction(decoded, decoded.ranked.size()));
}

// The prefix byte counts: where the coefficients start (version 2: the
// first packet byte; 1: the first chunk), every plane's (chunk's) end,
// kLogPrefixes counts log-spaced from the first to the whole file, and the
// whole file; ascending, distinct.
std::vector<std::uint64_t> prefix_sizes(const IswDecoded& full, std::uint64_t size) {
  std::set<std::uint64_t> sizes{size};
  std::uint64_t first = size;
  if (full.major_version >= 2) {
    first = full.stream.offset;
    for (const std::uint64_t end : full.stream.plane_ends) sizes.insert(first + end);
  }
  for (const IswSectionInfo& section : full.sections)
    if (section.tag == "CHNK") {
      first = std::min(first, section.offset);
      sizes.insert(section.offset + section.bytes);
    }
  sizes.insert(first);
  for (int i = 1; i < kLogPrefixes; ++i)
    sizes.insert(std::uint64_t(std::llround(double(first) * std::pow(double(size) / double(first), double(i) / kLogPrefixes))));
  return {sizes.begin(), sizes.end()};
}

// isowave's curve from prefixes of `file`; counts the prefixes that do not decode.
Curve isowave_curve(const std::string& name, const std::string& file, const References& r, int& failures) {
  Curve curve{name, {}};
  IswDecoded full = decode_isw(file, name);
  IswDecodeOptions options;
  options.hierarchy = full.hierarchy;  // the same for every prefix: built once
  options.order = IswOrder::Index;     // as `isowave decode` without --percent
  for (const std::uint64_t size : prefix_sizes(full, file.size())) {
    try {
      IswDecoded decoded = decode_isw(file.substr(0, size), name, options);
      const std::string label = size == file.size() ? "whole file"
                                                    : "prefix, " + std::to_string(decoded.chunks_decoded) + "/" +
                                                          std::to_string(decoded.chunks_total) +
                                                          (decoded.major_version >= 2 ? " planes" : " chunks");
      curve.points.push_back(measure(label, size, finest_mesh(decoded), r));
    } catch (const std::exception& e) {
      ++failures;
      std::printf("\n!!! PREFIX OF %llu BYTES (of %zu) DOES NOT DECODE: %s\n\n",
                  static_cast<unsigned long long>(size), file.size(), e.what());
      std::fprintf(stderr, "bench_rate_distortion: prefix of %llu bytes does not decode: %s\n",
                   static_cast<unsigned long long>(size), e.what());
    }
  }
  return curve;
}

Curve draco_curve(const DracoCoder& draco, const References& r) {
  Curve curve{"draco -cl " + std::to_string(kDracoLevel), {}};
  for (int bits = kDracoBitsLow; bits <= kDracoBitsHigh; ++bits)
    if (const std::optional<DracoCoded> coded = draco.code(bits, kDracoLevel))
      curve.points.push_back(measure("-qp " + std::to_string(bits), coded->bytes, coded->decoded, r));
  return curve;
}

// ---------------------------------------------------------------------------
// Reports.

struct Scale {
  double cell = 1;                      // world units per cell
  std::size_t marching_cubes_vertices = 1;
  double percent(double world) const { return 100 * world / cell; }
  double bits_per_vertex(std::uint64_t bytes) const { return 8.0 * double(bytes) / double(marching_cubes_vertices); }
};

void print_curve(const Curve& curve, const Scale& scale) {
  std::printf("\n%s:\n\n| point | bytes | bits/vertex | D %% vs marching cubes | D %% vs reference |\n"
              "|---|---|---|---|---|\n",
              curve.name.c_str());
  for (const Point& p : curve.points)
    std::printf("| %s | %llu | %.3f | %.4f | %.4f |\n", p.label.c_str(), static_cast<unsigned long long>(p.bytes),
                scale.bits_per_vertex(p.bytes), scale.percent(p.d_marching_cubes), scale.percent(p.d_reference));
}

// How often D rises from one prefix to the next (the target: D falls as the prefix grows).
void print_monotonicity(const Curve& curve) {
  int rises_marching_cubes = 0, rises_reference = 0;
  for (std::size_t i = 1; i < curve.points.size(); ++i) {
    rises_marching_cubes += curve.points[i].d_marching_cubes > curve.points[i - 1].d_marching_cubes;
    rises_reference += curve.points[i].d_reference > curve.points[i - 1].d_reference;
  }
  std::printf("\nD rises from one prefix to the next %d times against the marching-cubes mesh, %d times against the "
              "reference (of %zu steps)\n",
              rises_marching_cubes, rises_reference, curve.points.empty() ? 0 : curve.points.size() - 1);
}

std::vector<RatePoint> rate_points(const Curve& curve, double Point::*d) {
  std::vector<RatePoint> points;
  for (const Point& p : curve.points) points.push_back({double(p.bytes), p.*d});
  return points;
}

void print_bd_rate(const Curve& isowave, const Curve& draco, const Scale& scale) {
  std::printf("\nBD-rate of %s against %s (each curve reduced to its Pareto front first: "
              "points another point beats in both bytes and D are left out; log bytes piecewise linear in log D "
              "between front points, integrated exactly over the common D range):\n\n",
              isowave.name.c_str(), draco.name.c_str());
  const std::pair<const char*, double Point::*> references[] = {{"marching cubes", &Point::d_marching_cubes},
                                                                {"reference", &Point::d_reference}};
  for (const auto& [what, d] : references) {
    const BdRate bd = bd_rate(rate_points(isowave, d), rate_points(draco, d));
    if (bd.overlap)
      std::printf("- against the %s: BD-rate %+.1f%% over D %.4f..%.4f%% of a cell (%zu and %zu front points)\n", what,
                  bd.percent, scale.percent(bd.low_distortion), scale.percent(bd.high_distortion),
                  rate_distortion_front(rate_points(isowave, d)).size(),
                  rate_distortion_front(rate_points(draco, d)).size());
    else if (bd.nearest_rate_ratio > 0)
      std::printf("- against the %s: the D ranges do not overlap; at the nearest ends (isowave D %.4f%%, Draco D "
                  "%.4f%%) isowave's bytes are %.2f x Draco's\n",
                  what, scale.percent(bd.nearest_test_distortion), scale.percent(bd.nearest_anchor_distortion),
                  bd.nearest_rate_ratio);
    else
      std::printf("- against the %s: a curve has no point\n", what);
  }
}

void write_csv(const std::string& path, const std::vector<Curve>& curves, const Scale& scale) {
  FILE* out = std::fopen(path.c_str(), "w");
  if (!out) throw std::runtime_error("cannot write " + path);
  std::fprintf(out, "curve,reference,bytes,bits_per_vertex,d_percent_cell\n");
  for (const Curve& curve : curves)
    for (const Point& p : curve.points)
      for (const auto& [what, d] : {std::pair{"marching cubes", p.d_marching_cubes}, std::pair{"reference", p.d_reference}})
        std::fprintf(out, "%s,%s,%llu,%.6g,%.6g\n", curve.name.c_str(), what,
                     static_cast<unsigned long long>(p.bytes), scale.bits_per_vertex(p.bytes), scale.percent(d));
  if (std::fclose(out) != 0) throw std::runtime_error("cannot write " + path);
  std::printf("\nwrote %s\n", path.c_str());
}

// ---------------------------------------------------------------------------
// Timing.

double best_seconds(const std::function<void()>& run) {
  double best = HUGE_VAL;
  for (int i = 0; i < kTimingRuns; ++i) {
    const auto start = std::chrono::steady_clock::now();
    run();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

struct Speeds {
  double isowave_encode = 0, isowave_decode = 0, draco_encode = HUGE_VAL, draco_decode = HUGE_VAL;
  std::size_t fine_vertices = 0;
  bool reencoded_identical = false;
};

// isowave's decode (decode_isw and the synthesis to the finest mesh) and
// encode (encode_isw on the whole decode's hierarchy and coefficients), in
// this process; Draco's encoder and decoder at kDracoTimingBits as subprocesses.
Speeds measure_speeds(const std::string& name, const std::string& file, const DracoCoder& draco) {
  Speeds speeds;
  speeds.isowave_decode = best_seconds([&] {
    IswDecodeOptions options;
    options.order = IswOrder::Index;  // as `isowave decode` without --percent
    IswDecoded decoded = decode_isw(file, name, options);
    finest_mesh(decoded);
  });
  const IswDecoded full = decode_isw(file, name);
  speeds.fine_vertices = full.hierarchy->fine_vertex_count();
  IswEncodeOptions options;
  options.step = full.step;
  std::string reencoded;
  speeds.isowave_encode =
      best_seconds([&] { reencoded = encode_isw(*full.hierarchy, full.coefficients, full.metadata, options); });
  speeds.reencoded_identical = reencoded == file;
  for (int i = 0; i < kTimingRuns; ++i)
    if (const std::optional<DracoCoded> coded = draco.code(kDracoTimingBits, kDracoLevel)) {
      speeds.draco_encode = std::min(speeds.draco_encode, coded->encode_seconds);
      speeds.draco_decode = std::min(speeds.draco_decode, coded->decode_seconds);
    }
  return speeds;
}

void print_speeds(const Speeds& s, const Scale& scale) {
  const double fine = double(s.fine_vertices) / 1e6, marching_cubes = double(scale.marching_cubes_vertices) / 1e6;
  std::printf("\nspeed (best of %d; isowave per million fine vertices (%zu), Draco -qp %d -cl %d per million "
              "marching-cubes vertices (%zu); the re-encoded file is %s the converted one):\n\n"
              "| step | isowave s | isowave s/M | Draco s | Draco s/M | ratio of s/M | ratio of s |\n"
              "|---|---|---|---|---|---|---|\n",
              kTimingRuns, s.fine_vertices, kDracoTimingBits, kDracoLevel, scale.marching_cubes_vertices,
              s.reencoded_identical ? "identical to" : "NOT identical to");
  const auto row = [&](const char* step, double isowave, double draco) {
    std::printf("| %s | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f |\n", step, isowave, isowave / fine, draco,
                draco / marching_cubes, (isowave / fine) / (draco / marching_cubes), isowave / draco);
  };
  row("encode", s.isowave_encode, s.draco_encode);
  row("decode", s.isowave_decode, s.draco_decode);
}

// ---------------------------------------------------------------------------
// Self-test of bd_rate() against analytic curves.

// rate = a D^-k at n distortions spaced evenly in log D over [low, high].
std::vector<RatePoint> power_law(double a, double k, double low, double high, int n) {
  std::vector<RatePoint> points;
  for (int i = 0; i < n; ++i) {
    const double d = low * std::pow(high / low, double(i) / (n - 1));
    points.push_back({a * std::pow(d, -k), d});
  }
  return points;
}

int self_test() {
  int failures = 0;
  const auto check = [&](const char* what, double got, double want) {
    const bool ok = std::abs(got - want) <= 1e-9 * std::max(1.0, std::abs(want));
    std::printf("%s %s: %.12g (want %.12g)\n", ok ? "ok  " : "FAIL", what, got, want);
    failures += !ok;
  };
  // Equal exponents: the rate ratio is a / b at every D, whatever the sampling.
  const std::vector<RatePoint> draco = power_law(4, 1.5, 0.01, 1, 11);
  check("identical curves", bd_rate(draco, draco).percent, 0);
  check("a quarter of the rate", bd_rate(power_law(1, 1.5, 0.003, 0.5, 7), draco).percent, -75);
  check("twice the rate", bd_rate(power_law(8, 1.5, 0.02, 3, 5), draco).percent, 100);
  // rate D^-1 against D^-2 over D in [e^-3, e^-1]: log ratio = log D, mean -2.
  check("different slopes", bd_rate(power_law(1, 1, std::exp(-4), 1, 9), power_law(1, 2, std::exp(-3), std::exp(-1), 6)).percent,
        100 * (std::exp(-2) - 1));
  // Dominated points (above the front, or past its least rate) change nothing.
  std::vector<RatePoint> noisy = power_law(1, 1.5, 0.003, 0.5, 7);
  noisy.push_back({1000, 0.05});                     // far above the curve (89 there)
  noisy.push_back({1000, 2});                        // more distortion and more rate than the last point
  noisy.push_back({2 * std::pow(0.003, -1.5), 0.003});  // the first point's distortion at twice its rate
  // The front of a cloud: the points nothing beats in both rate and distortion
  // (a concave stretch is kept: 30 -> 25 -> 6 is not convex in log-log).
  const std::vector<RatePoint> kept{{100, 1}, {30, 2}, {25, 3}, {6, 8}};
  std::vector<RatePoint> cloud = kept;
  cloud.insert(cloud.end(), {{50, 2}, {35, 3.5}, {7, 16}, {200, 1}, {30, 2}});
  const std::vector<RatePoint> front = rate_distortion_front(cloud);
  check("front size", double(front.size()), double(kept.size()));
  for (std::size_t i = 0; i < front.size() && i < kept.size(); ++i)
    check("front point's rate", front[i].rate, kept[i].rate);
  check("dominated points ignored", bd_rate(noisy, draco).percent, -75);
  // Disjoint ranges: the rate ratio at the nearest ends.
  const BdRate apart = bd_rate(power_law(1, 1, 2, 4, 3), draco);
  check("disjoint ranges overlap", apart.overlap, 0);
  check("disjoint ranges ratio", apart.nearest_rate_ratio, (1 / 2.0) / (4 * std::pow(1.0, -1.5)));
  std::printf("%s\n", failures == 0 ? "bd_rate self-test passed" : "bd_rate self-test FAILED");
  return failures == 0 ? 0 : 1;
}

// The program's own options (taken out of argv): --csv FILE.
std::string take_csv_option(int& argc, char** argv) {
  std::string csv;
  int kept = 1;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--csv") == 0 && a + 1 < argc) csv = argv[++a];
    else argv[kept++] = argv[a];
  }
  argc = kept;
  return csv;
}

int run(const BenchOptions& o, const std::string& csv) {
  const FitRuns runs = run_fits(o);
  const Surfaces& s = runs.surfaces;
  const Scale scale{s.cell, s.marching_cubes.vertex_count()};
  const References references(s);
  if (!DracoCoder::available()) throw std::runtime_error("draco_encoder or draco_decoder is not on PATH");
  const DracoCoder draco(s.marching_cubes);
  const Curve draco_points = draco_curve(draco, references);
  print_curve(draco_points, scale);
  std::vector<Curve> curves{draco_points};
  int failures = 0;
  for (std::size_t i = 0; i < o.fits.size(); ++i) {
    const FitOutcome& outcome = runs.outcomes[i];
    std::printf("\n");
    if (!print_fit(o.fits[i], outcome, s, runs.marching_cubes_d)) continue;
    const Curve curve = isowave_curve(std::string("isowave ") + fit_name(o.fits[i]), outcome.file, references, failures);
    print_curve(curve, scale);
    print_monotonicity(curve);
    print_bd_rate(curve, draco_points, scale);
    print_speeds(measure_speeds(curve.name, outcome.file, draco), scale);
    curves.push_back(curve);
  }
  if (!csv.empty()) write_csv(csv, curves, scale);
  if (failures > 0) std::printf("\n!!! %d PREFIXES DID NOT DECODE\n", failures);
  return failures > 0 ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--self-test") == 0) return self_test();
  const std::string csv = take_csv_option(argc, argv);
  BenchOptions defaults;
  const ConvertOptions convert_defaults;
  defaults.fits = {convert_defaults.fit};
  const BenchOptions o = parse_options(argc, argv, "bench_rate_distortion", defaults, " [--csv FILE] | --self-test");
  try {
    return run(o, csv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_rate_distortion: %s\n", e.what());
    return 1;
  }
}
