// Global oracles compared at equal coefficient counts (issue #48, item 3):
// for each file, the wavelet coefficients a --percent keeps by magnitude,
// by class weight x magnitude (the default) and by Staadt, Gross and Weber's
// greedy rejection, then the paper's RMSE over the fine control points
// against the full decode and, with the volume, D (surface_error.h) between
// the fine control mesh and the volume's marching-cubes isosurface; all in %
// of the volume's cell (the file's cell_size without a volume); and each
// oracle's time (--batches: greedy's smallest batches, fractions of the
// coefficients kept). The target: greedy's RMSE at 5% and 10% against weighted's.
//
// usage: bench_oracles FILE.isw [--volume VOLUME --iso V] [--percents 5,10] [--batches F,F,...]
#include <chrono>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/error.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "isowave/transform/wavelet_transform.h"

using namespace isowave;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::vector<double> numbers(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) out.push_back(std::stod(item));
  return out;
}

struct Options {
  std::string file, volume;
  double iso = 0;
  std::vector<double> percents{5, 10};
  std::vector<double> batches{1.0 / 64};  // keep_greedy's smallest_batch
};

Options parse(int argc, char** argv) {
  if (argc < 2) throw Error(ErrorKind::InvalidArgument, "usage: bench_oracles FILE.isw [--volume VOLUME --iso V] [--percents 5,10] [--batches F,...]");
  Options o;
  o.file = argv[1];
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--volume") o.volume = value;
    else if (key == "--iso") o.iso = std::stod(value);
    else if (key == "--percents") o.percents = numbers(value);
    else if (key == "--batches") o.batches = numbers(value);
    else throw Error(ErrorKind::InvalidArgument, "unknown option " + key);
  }
  return o;
}

// A row: an oracle over the whole stream, or (`prefix`) what decode
// --percent reads and keeps (the PCNT prefix of a 2.2 file).
struct Choice {
  std::string name;
  Oracle oracle;
  double smallest_batch;
  bool prefix;
};

// The coefficients `choice` keeps at `percent` and the seconds it took.
std::vector<Vec3> kept_by(const Choice& choice, const IswDecoded& decoded, const std::string& file, double percent,
                          double& seconds) {
  const SubdivisionHierarchy& h = *decoded.hierarchy;
  const std::size_t keep = coefficients_for_percent(h, percent);
  const auto start = Clock::now();
  if (choice.prefix) {
    IswDecodeOptions limit;
    limit.max_percent = percent;
    IswDecoded part = read_isw(file, limit);
    seconds = seconds_since(start);
    const IswDecodeTimings& t = part.seconds;
    std::printf("%8.2f %12s read %llu of %llu file bytes (%.1f%%); seconds: read %.3f, headers %.3f, hierarchy %.3f "
                "(waited %.3f), planes %.3f, rank %.3f, to world %.3f\n",
                percent, "prefix", static_cast<unsigned long long>(part.file_bytes_read),
                static_cast<unsigned long long>(part.file_bytes),
                100.0 * static_cast<double>(part.file_bytes_read) / static_cast<double>(part.file_bytes), t.read,
                t.headers, t.hierarchy, t.hierarchy_wait, t.chunks, t.rank, t.dequantize);
    return std::move(part.coefficients);
  }
  std::vector<Vec3> kept = decoded.coefficients;
  if (choice.oracle == Oracle::Greedy) {
    keep_greedy(h, kept, keep, choice.smallest_batch);
  } else {
    const std::vector<double> unit(decoded.class_weights.size(), 1.0);
    keep_most_important(h, kept, choice.oracle == Oracle::Magnitude ? unit : decoded.class_weights, keep);
  }
  seconds = seconds_since(start);
  return kept;
}

int run(const Options& o) {
  IswDecodeOptions whole;
  whole.order = IswOrder::Index;
  const IswDecoded decoded = read_isw(o.file, whole);
  const SubdivisionHierarchy& h = *decoded.hierarchy;
  std::vector<Vec3> full = decoded.coefficients;
  synthesize(h, full);
  double cell = std::stod(decoded.metadata.values.count("cell_size") ? decoded.metadata.values.at("cell_size") : "1");
  std::optional<SurfaceErrorReference> reference;
  if (!o.volume.empty()) {
    const Volume volume = read_volume(o.volume);
    cell = volume.cell_size();
    IsosurfaceOptions extract;
    extract.iso = o.iso;
    reference.emplace(extract_isosurface(volume, extract).mesh);
  }
  std::vector<Choice> choices{{"magnitude", Oracle::Magnitude, 0, false},
                              {"weighted", Oracle::Weighted, 0, false},
                              {"prefix", Oracle::Weighted, 0, true}};
  for (double b : o.batches) {
    char name[32];
    std::snprintf(name, sizeof name, "greedy/%g", b);
    choices.push_back({name, Oracle::Greedy, b, false});
  }
  std::printf("%s: %zu fine points, %zu base, %d levels\n", o.file.c_str(), h.fine_vertex_count(), h.vertex_count(0), h.levels());
  std::printf("%8s %12s %14s %12s %10s\n", "percent", "oracle", "RMSE [% cell]", "D [% cell]", "seconds");
  for (double percent : o.percents)
    for (const Choice& choice : choices) {
      double seconds = 0;
      std::vector<Vec3> kept = kept_by(choice, decoded, o.file, percent, seconds);
      synthesize(h, kept);
      const double rms = point_errors(kept, full, h.fine_vertex_count()).rms;
      double d = -1;
      if (reference) d = reference->measure(h.control_mesh(h.levels(), std::move(kept))).d();
      std::printf("%8.2f %12s %14.3f %12.3f %10.3f\n", percent, choice.name.c_str(), 100 * rms / cell,
                  d < 0 ? -1.0 : 100 * d / cell, seconds);
    }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_oracles: %s\n", e.what());
    return 1;
  }
}
