// The end-to-end figures of the conversion (issue: end to end), on the shared
// miranda volume (iso 1.5, components under 50 vertices removed, L = 3) and
// the engine CT (iso 100), or on a volume given on the command line:
//  - whole convert time and peak memory (targets <= 30 s, <= 2 GB);
//  - decode at 5% time (target <= 1 s);
//  - the paper's Table 1 (RMSE in % of a cell at 20/10/5% and the base mesh,
//    against the fitted control points) next to the paper's figures, with file
//    bytes and bits per vertex at each percentage, and the RMS distance of the
//    decoded vertices to the extracted isosurface (comparable with Draco, see
//    bench/draco_rate_distortion.sh);
//  - importance weighting against selection by raw magnitude at 5% and 10%;
//  - coded bits per coefficient against zstd -19 of the same quantized
//    integers and against raw 32-bit floats.
//
// With --decode-only FILE.isw [PERCENT] it times only decoding an existing
// file at PERCENT (default 5; read, decode, synthesis to the fine control
// points; best of 5) and prints the phases, and the same with the fine
// control mesh built from them, the work `isowave decode` and the Python
// module's decode() do before writing or returning it.
//
// With --coding-stages FILE.isw it times the coding stages of convert
// (weights, quantization error, encode, the summary from the encoder's
// coefficients, and the full decode that convert --verify adds) on the file's
// decoded coefficients, with their synthesis as the fitted points (best of 3).
//
// usage: bench_codec [VOLUME --iso V [--min-component-vertices N] [--levels L] [--base-ratio R]]
//        bench_codec --decode-only FILE.isw [PERCENT]
//        bench_codec --coding-stages FILE.isw
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "isowave/core/huge_page_vector.h"
#include "isowave/pipeline/convert.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/peak_memory.h"
#include "isowave/extract/volume_io.h"
#include "isowave/core/surface_distance.h"
#include "isowave/transform/wavelet_transform.h"

using namespace isowave;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Bytes of zstd -19 on a buffer, through the zstd command (0 if unavailable).
std::size_t zstd_bytes(const std::string& data) {
  char path[] = "/tmp/isowave_bench_zstd_XXXXXX";
  const int fd = mkstemp(path);
  if (fd < 0) return 0;
  if (write(fd, data.data(), data.size()) != static_cast<ssize_t>(data.size())) {
    close(fd);
    unlink(path);
    return 0;
  }
  close(fd);
  const std::string command = std::string("zstd -19 -q -c ") + path + " 2>/dev/null | wc -c";
  std::size_t bytes = 0;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    if (std::fscanf(pipe, "%zu", &bytes) != 1) bytes = 0;
    pclose(pipe);
  }
  unlink(path);
  return bytes;
}

// The paper's Table 1 at 20, 10, 5% and base.
constexpr double kPaperTable1[4] = {7.6, 20.5, 41.7, 71.3};

struct Dataset {
  std::string name, path;
  ConvertOptions options{};
  double paper[4]{};  // the paper's Table 1 at 20, 10, 5% and base (only for the mixing data)
};

void run(const Dataset& dataset) {
  std::printf("\n== %s (%s, iso %g", dataset.name.c_str(), dataset.path.c_str(), dataset.options.prepare.extract.iso);
  const std::size_t min_component = dataset.options.prepare.extract.min_component_vertices;
  if (min_component) std::printf(", --min-component-vertices %zu", min_component);
  std::printf(")\n");
  release_freed_memory();  // the previous dataset's leftovers
  reset_peak_memory();  // each dataset's figure its own
  auto start = Clock::now();
  Volume volume = read_volume(dataset.path);
  const double load = seconds_since(start);
  ConvertOptions options = dataset.options;
  options.keep_extracted_mesh = true;
  options.summary_percents = {100, 20, 10, 5};
  start = Clock::now();
  const ConvertResult r = convert_volume(std::move(volume), dataset.path, options);
  const double convert_seconds = seconds_since(start);
  const double peak = peak_memory_bytes() / 1048576.0;
  const double cell = r.cell_size;
  std::printf("isosurface %zu vertices; base mesh %zu vertices (%.2f%% of the fine mesh), %d levels, %zu fine control points\n",
              r.extracted_vertices, r.base_vertices, 100.0 * r.base_vertices / r.fine_vertices, r.levels, r.fine_vertices);
  std::printf("convert: %.1f s (load %.2f + extract %.2f, simplify %.2f, distance %.2f, fit %.2f, analysis %.2f, "
              "encode %.2f, evaluate %.2f)   target <= 30 s\n",
              load + convert_seconds, load, r.seconds.extract, r.seconds.simplify, r.seconds.distance, r.seconds.fit,
              r.seconds.analysis, r.seconds.encode, r.seconds.evaluate);
  std::printf("peak memory (this dataset, volume included): %.0f MB   target <= 2048 MB\n", peak);
  for (const std::string& warning : r.warnings) std::printf("warning: %s\n", warning.c_str());

  // Decode at 5%: read, synthesize, build the mesh (median of 5).
  std::vector<double> times;
  for (int k = 0; k < 5; ++k) {
    start = Clock::now();
    IswDecodeOptions decode_options;
    decode_options.max_percent = 5;
    const IswDecoded d = decode_isw(r.bytes, "memory", decode_options);
    const PolygonMesh mesh = d.hierarchy->control_mesh(d.levels, reconstruct(d, d.ranked.size()));
    times.push_back(seconds_since(start));
  }
  std::sort(times.begin(), times.end());
  std::printf("decode at 5%%: %.3f s (median of 5, from memory)   target <= 1 s\n", times[2]);

  // Table 1 with sizes and the distance to the extracted surface.
  const IswDecoded full = decode_isw(r.bytes, "memory");
  const SurfaceDistance reference(r.extracted_mesh);
  std::printf("\n%9s %12s %14s %14s %10s %10s %10s %18s\n", "percent", "coefficients", "RMSE [% cell]", "paper [% cell]",
              "bytes", "bits/fine", "bits/iso", "surface RMS [% cell]");
  int row_index = 0;
  for (const RateDistortionRow& row : r.summary) {
    const std::vector<Vec3> points = reconstruct(full, row.wavelet_coefficients);
    const std::vector<double> distances = reference.distances(points);
    double sum = 0;
    for (double d : distances) sum += d * d;
    char paper[32] = "-";
    if (row.percent < 99.99 && dataset.paper[0] > 0) std::snprintf(paper, sizeof paper, "%.1f", dataset.paper[row_index++]);
    std::printf("%9.2f %12zu %14.2f %14s %10llu %10.3f %10.3f %18.2f%s\n", row.percent, row.kept, 100 * row.rms / cell,
                paper, static_cast<unsigned long long>(row.bytes), 8.0 * row.bytes / r.fine_vertices,
                8.0 * row.bytes / r.extracted_vertices, 100 * std::sqrt(sum / distances.size()) / cell,
                row.is_base ? "  (base mesh)" : "");
  }

  // Importance weighting against raw magnitude.
  const SubdivisionHierarchy& h = *full.hierarchy;
  std::vector<Vec3> coefficients = r.fit.positions;
  analyze(h, coefficients);
  const std::vector<double> unit(full.class_weights.size(), 1.0);
  for (double percent : {5.0, 10.0}) {
    std::vector<Vec3> weighted = coefficients, raw = coefficients;
    keep_most_important(h, weighted, full.class_weights, coefficients_for_percent(h, percent));
    keep_most_important(h, raw, unit, coefficients_for_percent(h, percent));
    synthesize(h, weighted);
    synthesize(h, raw);
    std::printf("%g%%: RMSE with importance weights %.2f%% of a cell, with raw magnitude %.2f%%\n", percent,
                100 * point_errors(weighted, r.fit.positions, r.fine_vertices).rms / cell,
                100 * point_errors(raw, r.fit.positions, r.fine_vertices).rms / cell);
  }

  // Bits per coefficient.
  std::string integers;
  for (int c = 1; c < coefficient_class_count(h); ++c) {
    const double step = full.step / full.class_weights[static_cast<std::size_t>(c)];
    const auto [first, last] = coefficient_class_range(h, c);
    for (std::size_t i = first; i < last; ++i)
      for (int axis = 0; axis < 3; ++axis) {
        const auto q = static_cast<std::int32_t>(std::llround(full.coefficients[i][axis] / step));
        integers.append(reinterpret_cast<const char*>(&q), 4);
      }
  }
  // The coefficients' sections: 1.0's chunks, 2.0's plane stream.
  std::uint64_t chunk_bytes = 0;
  for (const IswSectionInfo& s : full.sections)
    if (s.tag == "CHNK" || s.tag == "PLNS") chunk_bytes += s.bytes;
  const double wavelets = static_cast<double>(h.fine_vertex_count() - h.vertex_count(0));
  const std::size_t zstd = zstd_bytes(integers);
  std::printf("wavelet coefficients (vectors): %.0f, %llu non-zero after quantization (step %.3g cell)\n", wavelets,
              static_cast<unsigned long long>(full.coefficients_total), full.step / cell);
  std::printf("bits per coefficient: isowave %.2f", 8.0 * chunk_bytes / wavelets);
  if (zstd) std::printf(", zstd -19 of the same quantized int32 %.2f (%.2fx isowave)", 8.0 * zstd / wavelets, double(zstd) / chunk_bytes);
  else std::printf(", zstd unavailable");
  std::printf(", raw float32 96.00 (%.1fx isowave)\n", 96.0 * wavelets / (8.0 * chunk_bytes));
  std::printf("whole file %zu bytes = %.2f bits per fine vertex, %.2f bits per isosurface vertex\n", r.bytes.size(),
              8.0 * r.bytes.size() / r.fine_vertices, 8.0 * r.bytes.size() / r.extracted_vertices);
}

// Decoding an existing file at `percent`, as the library does it for
// `isowave decode` before the mesh is written: best of five runs, with its
// phases; and the control mesh of the finest level from the synthesis.
void run_decode_only(const std::string& path, double percent) {
  constexpr int kRuns = 5;
  double best = 0, best_with_mesh = 0;
  IswDecodeTimings best_phases;
  double best_synthesis = 0;
  std::size_t fine = 0, kept = 0;
  for (int k = 0; k < kRuns; ++k) {
    const auto start = Clock::now();
    IswDecodeOptions options;
    options.max_percent = percent;
    options.order = IswOrder::Index;  // as `isowave decode`: ranks only below 100%
    IswDecoded d = read_isw(path, options);
    const auto synthesis_start = Clock::now();
    std::vector<Vec3> points = take_reconstruction(d, d.ranked.size());
    const double synthesis = seconds_since(synthesis_start);
    const double total = seconds_since(start);
    fine = points.size();
    const PolygonMesh mesh = d.hierarchy->control_mesh(d.levels, std::move(points));
    const double with_mesh = seconds_since(start);
    std::printf("run %d: %.3f s, %.3f s with the control mesh (%zu faces)\n", k + 1, total, with_mesh,
                mesh.face_count());
    best_with_mesh = k == 0 ? with_mesh : std::min(best_with_mesh, with_mesh);
    if (k == 0 || total < best) {
      best = total;
      best_phases = d.seconds;
      best_synthesis = synthesis;
      kept = d.ranked.size();
    }
  }
  const IswDecodeTimings& p = best_phases;
  std::printf("decode at %g%% of %s: %zu fine control points, %zu coefficients\n", percent, path.c_str(), fine, kept);
  std::printf("decode at %g%%: %.3f s (best of %d: read %.3f, base mesh %.3f, chunks %.3f + rank %.3f while the "
              "hierarchy builds in %.3f, then waiting %.3f, dequantize %.3f, synthesis %.3f)   target at 5%% <= 1 s\n",
              percent, best, kRuns, p.read, p.headers, p.chunks, p.rank, p.hierarchy, p.hierarchy_wait, p.dequantize,
              best_synthesis);
  std::printf("decode at %g%% with the fine control mesh: %.3f s (best of %d)\n", percent, best_with_mesh, kRuns);
}

// The coding stages of convert_volume() one by one, so that their parts can
// be compared without the minute of fitting before them.
void run_coding_stages(const std::string& path) {
  const IswDecoded file = read_isw(path);
  const SubdivisionHierarchy& h = *file.hierarchy;
  const std::vector<Vec3> coefficients = file.coefficients;
  std::vector<Vec3> fitted = coefficients;
  synthesize(h, fitted);
  std::printf("coding stages of %s: %zu fine control points\n", path.c_str(), h.fine_vertex_count());
  constexpr int kRuns = 3;
  std::vector<double> best(8, 1e300);
  std::vector<double> last_rms;
  IswDecodeTimings phases;
  for (int k = 0; k < kRuns; ++k) {
    // As convert_volume() runs them.
    std::vector<double> t;
    auto start = Clock::now();
    IswEncodeOptions options;
    options.step = file.step;
    options.class_weights = wavelet_norms(h);
    t.push_back(seconds_since(start));
    start = Clock::now();
    std::vector<Vec3> stored = quantize_coefficients(h, coefficients, options.step, options.class_weights);
    std::vector<Vec3> full_decode = stored;
    synthesize(h, full_decode);
    IswMetadata metadata;
    record_quantization_error(point_errors(full_decode, fitted, full_decode.size()), metadata);
    t.push_back(seconds_since(start));
    start = Clock::now();
    std::vector<std::uint32_t> ranked;
    const std::string bytes = encode_isw(h, coefficients, metadata, options, &ranked);
    t.push_back(seconds_since(start));
    start = Clock::now();
    const IswDecoded expected = expected_decode(file.hierarchy, std::move(stored), std::move(ranked), bytes, "memory");
    t.push_back(seconds_since(start));
    start = Clock::now();
    const std::vector<RateDistortionRow> rows = error_table(expected, {100, 20, 10, 5}, &full_decode).rows;
    t.push_back(seconds_since(start));
    // What convert --verify adds: a full decode of the file.
    start = Clock::now();
    IswDecodeOptions decode_options;
    decode_options.hierarchy = file.hierarchy;
    const IswDecoded decoded = decode_isw(bytes, "memory", decode_options);
    t.push_back(seconds_since(start));
    if (t.back() < best[5]) phases = decoded.seconds;
    if (decoded.coefficients != expected.coefficients || decoded.ranked != expected.ranked)
      throw std::runtime_error("the file does not decode to the coded coefficients");
    t.push_back(t[0] + t[1] + t[2]);
    t.push_back(t[3] + t[4]);
    for (std::size_t i = 0; i < t.size(); ++i) best[i] = std::min(best[i], t[i]);
    last_rms.clear();
    for (const RateDistortionRow& row : rows) last_rms.push_back(row.rms);
  }
  std::printf("best of %d: weights %.3f, quantization error %.3f, encode_isw %.3f (encode stage %.3f); expected "
              "decode %.3f, error_table %.3f (evaluate stage %.3f) s; a full decode (--verify) %.3f s\nrow RMS:",
              kRuns, best[0], best[1], best[2], best[6], best[3], best[4], best[7], best[5]);
  for (double rms : last_rms) std::printf(" %.10g", rms);
  std::printf("\ndecode phases: headers %.3f, chunks %.3f, rank %.3f, dequantize %.3f s\n", phases.headers,
              phases.chunks, phases.rank, phases.dequantize);
}

}  // namespace

int main(int argc, char** argv) {
  isowave::keep_freed_memory_for_reuse();
  try {
    if ((argc == 3 || argc == 4) && std::string(argv[1]) == "--decode-only") {
      run_decode_only(argv[2], argc == 4 ? std::atof(argv[3]) : 5.0);
      return 0;
    }
    if (argc == 3 && std::string(argv[1]) == "--coding-stages") {
      run_coding_stages(argv[2]);
      return 0;
    }
    std::vector<Dataset> datasets;
    if (argc >= 2) {
      Dataset& d = datasets.emplace_back();
      d.name = d.path = argv[1];
      for (int i = 2; i + 1 < argc; i += 2) {
        const std::string flag = argv[i];
        if (flag == "--iso") d.options.prepare.extract.iso = std::atof(argv[i + 1]);
        else if (flag == "--min-component-vertices") d.options.prepare.extract.min_component_vertices = std::strtoul(argv[i + 1], nullptr, 10);
        else if (flag == "--levels") d.options.levels = std::atoi(argv[i + 1]);
        else if (flag == "--base-ratio") d.options.base.ratio = std::atof(argv[i + 1]);
        else throw std::runtime_error("unknown option " + flag);
      }
    } else {
      const std::string shared = ISOWAVE_SHARED_DATA_DIR;
      if (!std::ifstream(shared + "/volumes/miranda_256x256x256.nrrd")) {
        std::printf("shared data absent (%s): nothing to measure\n", shared.c_str());
        return 0;
      }
      // Built in place: copies of the options trip GCC 12's -Wmaybe-uninitialized on std::function.
      datasets.resize(2);
      Dataset& miranda = datasets[0];
      miranda.name = "miranda";
      miranda.path = shared + "/volumes/miranda_256x256x256.nrrd";
      miranda.options.prepare.extract.iso = 1.5;
      miranda.options.prepare.extract.min_component_vertices = 50;
      miranda.options.levels = 3;
      miranda.options.base.ratio = 0.017;
      Dataset& engine = datasets[1];
      engine.name = "engine";
      engine.path = shared + "/volumes/engine_256x256x128.nrrd";
      engine.options.prepare.extract.iso = 100;
      engine.options.levels = 3;
      engine.options.base.ratio = 0.017;
      for (Dataset& d : datasets) std::copy(std::begin(kPaperTable1), std::end(kPaperTable1), d.paper);
    }
    std::printf("the paper's Table 1 (turbulent mixing, 1.19 M fine control points): RMSE 7.6%% of a cell at 20%%, "
                "20.5%% at 10%%, 41.7%% at 5%%, 71.3%% at the base mesh (1.6%%)\n");
    for (const Dataset& d : datasets) run(d);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench_codec: %s\n", error.what());
    return 1;
  }
  return 0;
}
