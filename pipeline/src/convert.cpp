#include "isowave/pipeline/convert.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <future>
#include <iomanip>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <tbb/task_arena.h>

#include "isowave/codec/base_order.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/error.h"
#include "isowave/core/peak_memory.h"
#include "isowave/core/memory_check.h"
#include "isowave/core/surface_error.h"
#include "isowave/transform/wavelet_transform.h"
#include "rate_control.h"

namespace isowave {

double ConvertResult::folded_share() const {
  return fine_faces ? double(fit.folded_faces) / double(fine_faces) : 0.0;
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string number(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

// A stage's wall-clock seconds, added to the result's, and the process's
// peak resident memory at its end, raised into the result's.
class StageClock {
 public:
  StageClock() : start_(Clock::now()) {}
  void end(double& seconds, double& peak_bytes) const {
    seconds += seconds_since(start_);
    peak_bytes = std::max(peak_bytes, peak_memory_bytes());
  }

 private:
  Clock::time_point start_;
};

// A share as a percentage in fixed notation ("100.00%", never "1e+02%").
std::string percent(double share) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(2) << 100.0 * share << '%';
  return s.str();
}

void check_options(const ConvertOptions& options) {
  if (options.levels < 0 || options.levels > 6)
    throw Error(ErrorKind::InvalidArgument, "levels must be in 1..6, or 0 for automatic");
  if (!(options.base.ratio > 0 && options.base.ratio <= 1))
    throw Error(ErrorKind::InvalidArgument, "the base ratio must be in (0, 1]");
  if (!(options.step_cells > 0) || !std::isfinite(options.step_cells))
    throw Error(ErrorKind::InvalidArgument, "the quantization step must be positive");
  if (!(options.max_error_cells >= 0) || !std::isfinite(options.max_error_cells))
    throw Error(ErrorKind::InvalidArgument, "the maximum error must be a non-negative number of cells");
  const RateTarget& rate = options.rate;
  if (!(rate.max_error_cells >= 0) || !std::isfinite(rate.max_error_cells) || !(rate.bits_per_vertex >= 0) ||
      !std::isfinite(rate.bits_per_vertex))
    throw Error(ErrorKind::InvalidArgument, "a rate target must be a non-negative number");
  if ((rate.max_error_cells > 0) + (rate.max_bytes > 0) + (rate.bits_per_vertex > 0) > 1)
    throw Error(ErrorKind::InvalidArgument, "give at most one of a maximum error, a size and bits per vertex");
}

std::size_t base_target(const BaseMeshOptions& base, std::size_t extracted_vertices) {
  if (base.vertices > 0) return base.vertices;
  return std::max<std::size_t>(4, static_cast<std::size_t>(std::llround(base.ratio * double(extracted_vertices))));
}

// points[v] moved to new_of_old[v].
std::vector<Vec3> renumbered(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& new_of_old) {
  std::vector<Vec3> out(points.size());
  for (std::size_t v = 0; v < points.size(); ++v) out[new_of_old[v]] = points[v];
  return out;
}

// The signed-distance field needs only the field and the extracted mesh: it
// is computed alongside the base mesh, started when the simplification turns
// serial and leaves a core idle, on one thread (two would take the core the
// simplification runs on). No progress from it: the sink shows one
// stage at a time.
class BackgroundDistance {
 public:
  // The future's destructor waits for a computation still running (it reads `prepared`).
  BackgroundDistance(PreparedSurface& prepared, const PrepareOptions& options) : prepared_(prepared), options_(options) {}

  void start() {
    pending_ = std::async(std::launch::async, [this] {
      tbb::task_arena one_thread(1);
      return one_thread.execute([this] { return surface_distance_field(prepared_, options_); });
    });
  }

  // Puts the field into prepared.distance, once (stage "signed distance");
  // returns the seconds waited.
  double wait(ProgressSink& progress) {
    if (done_) return 0;
    const auto start_time = Clock::now();
    progress.begin_stage("signed distance");
    if (!pending_.valid()) start();
    prepared_.distance = pending_.get();
    progress.end_stage();
    done_ = true;
    return seconds_since(start_time);
  }

 private:
  PreparedSurface& prepared_;
  const PrepareOptions& options_;
  std::future<SignedDistanceField> pending_;
  bool done_ = false;
};

// One base mesh of `target` vertices (simplify, Sec. 4.1), with the map for
// the parametrization.
simplify::SimplifyResult simplify_base(const PreparedSurface& prepared,
                                       const simplify::SimplifyOptions& simplify_options,
                                       const ConvertOptions& options, ConvertResult& result, ProgressSink& progress) {
  const StageClock clock;
  simplify::SimplifyResult simplified = simplify::simplify(prepared.isosurface.mesh, simplify_options, progress);
  result.simplification = simplified.report;
  result.base_vertices = simplified.base.vertex_count();
  if (result.base_attempts == 1) result.first_base_vertices = result.base_vertices;
  clock.end(result.seconds.simplify, result.peak_bytes.simplify);
  return simplified;
}

// The automatic levels' bound on D, in cells (0 with fixed levels).
double level_error_bound(const PreparedSurface& prepared, const ConvertOptions& options) {
  if (options.levels > 0) return 0;
  if (options.max_error_cells > 0) return options.max_error_cells;
  const SurfaceDeviation deviation =
      extracted_surface_deviation(prepared.isosurface.mesh, prepared.field, options.prepare.extract.iso);
  const bool corrected = options.fit == FitMethod::Normal ||
                         (options.fit == FitMethod::Parametrization ? options.fine_points == FinePoints::OnTrilinearIsosurface
                                                                     : options.shrink_wrap.final_correction);
  return std::max(kLevelErrorFloorCells, (corrected ? kCorrectedLevelErrorShare : kLevelErrorShare) * deviation.rms);
}

}  // namespace

double max_auto_fine_vertices(FitMethod fit, std::size_t extracted_vertices) {
  const double share = fit == FitMethod::Parametrization ? kParametrizationMaxFineShare : kMaxFineShare;
  return std::min(share * double(extracted_vertices), kMaxAutoFineVertices);
}

namespace {

// The fit's options and input over `prepared` (surface_fit.h).
SurfaceFitOptions fit_options(const ConvertOptions& options, const ConvertResult& result) {
  SurfaceFitOptions fit;
  fit.method = options.fit;
  fit.levels.fixed_levels = options.levels;
  fit.levels.max_error_cells = result.max_error_cells;
  fit.levels.max_fine_vertices = max_auto_fine_vertices(options.fit, result.extracted_vertices);
  fit.fine_points = options.fine_points;
  fit.shrink_wrap = options.shrink_wrap;
  fit.normal = options.normal;
  return fit;
}

SurfaceFitInput fit_input(const PreparedSurface& prepared, const SurfaceErrorReference& against_surface,
                          const ConvertOptions& options, const ConvertResult& result) {
  SurfaceFitInput input;
  input.field = &prepared.field;
  input.iso = options.prepare.extract.iso;
  input.orientation = orientation_from_flip(options.prepare.extract.flip);
  input.isosurface = &prepared.isosurface.mesh;
  input.reference = &against_surface;
  input.cell_size = result.cell_size;
  input.distance = &prepared.distance;
  const double frame_step = kFrameStepCells * result.cell_size;
  input.directions = [frame_step](const SubdivisionHierarchy& hierarchy) -> NormalDirections {
    return [&hierarchy, frame_step](const std::vector<Vec3>& points) {
      return isw_frame_normals(hierarchy, points, frame_step);
    };
  };
  return input;
}

// The fit's figures into the result; returns its hierarchy.
std::shared_ptr<const SubdivisionHierarchy> take_fit(SurfaceFit fit, ConvertResult& result) {
  result.fit = std::move(fit.points);
  result.parametrization = fit.parametrization;
  result.normal_levels = std::move(fit.normal_levels);
  result.non_normal_coefficients = fit.non_normal_coefficients;
  result.frame_base = std::move(fit.frame_base);
  result.level_reports = std::move(fit.level_reports);
  result.levels = fit.levels;
  result.fine_vertices = fit.fine_vertices;
  result.fine_faces = fit.fine_faces;
  result.fit_isosurface = fit.isosurface;
  result.uncovered_share = fit.uncovered_share;
  return std::move(fit.hierarchy);
}

// The base mesh (simplify_base) and the fit (fit_surface); with
// BaseGrowth::UntilCovered, again from a base mesh twice as large while more
// than kUncoveredWarning of the isosurface is left out (not for the
// parametrization: its map covers every part of the surface). Returns the
// last fit's hierarchy and, in `target`, the last base mesh's target.
std::shared_ptr<const SubdivisionHierarchy> base_and_fit(PreparedSurface& prepared,
                                                         const SurfaceErrorReference& against_surface,
                                                         const ConvertOptions& options, ConvertResult& result,
                                                         std::size_t& target, ProgressSink& progress) {
  simplify::SimplifyOptions simplify_options = options.base.simplify;
  simplify_options.target_vertices = target = base_target(options.base, result.extracted_vertices);
  simplify_options.compute_distance = false;
  // Each level multiplies the vertices by about 4 (the first by about 6): a
  // lower bound of the fine mesh before the base mesh is made.
  if (options.levels > 0)
    check_memory(double(std::min(target, result.extracted_vertices)) * std::pow(4.0, options.levels),
                 kFitBytesPerFineVertex, std::to_string(options.levels) + " levels");
  const bool mapped = options.fit == FitMethod::Parametrization;
  if (mapped) {
    simplify_options.surface_map = simplify::SurfaceMapping::Build;
    simplify_options.max_vertex_area_share = kParametrizationAreaShare;
  }
  // Only the shrink-wrap searches the signed-distance field.
  const bool wrap = options.fit == FitMethod::ShrinkWrap;
  BackgroundDistance distance(prepared, options.prepare);
  if (wrap) simplify_options.serial_phase_begins = [&distance] { distance.start(); };
  const SurfaceFitOptions fit = fit_options(options, result);
  SurfaceFitInput input = fit_input(prepared, against_surface, options, result);
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  for (result.base_attempts = 1;; ++result.base_attempts) {
    const simplify::SimplifyResult simplified = simplify_base(prepared, simplify_options, options, result, progress);
    simplify_options.serial_phase_begins = nullptr;  // the distance field is on its way
    const PolygonMesh& base = simplified.base;
    if (options.levels > 0)  // before the wait
      check_memory(double(fine_vertex_count(base, options.levels)), kFitBytesPerFineVertex,
                   std::to_string(options.levels) + " levels of a " + std::to_string(base.vertex_count()) +
                       "-vertex base mesh");
    if (wrap) result.seconds.distance += distance.wait(progress);
    result.fit = ShrinkWrapResult{};  // the previous try's, before the next one's peak
    hierarchy.reset();
    input.map = &simplified.map;
    const StageClock clock;
    hierarchy = take_fit(fit_surface(base, input, fit, progress), result);
    clock.end(result.seconds.fit, result.peak_bytes.fit);
    // With the levels fixed, a larger base multiplies the fine mesh: it grows
    // only when the levels follow it.
    const std::size_t grown = 2 * base.vertex_count();
    if (mapped || options.base.growth != BaseGrowth::UntilCovered || options.levels != 0 ||
        result.uncovered_share <= kUncoveredWarning || result.base_attempts == kBaseAttempts ||
        grown > result.extracted_vertices / 4)
      break;
    simplify_options.target_vertices = target = grown;
  }
  return hierarchy;
}

// What the folds of a fit that folds more than kFoldedWarning of its fine
// faces come from, and the remedy.
// - A fine mesh too coarse for the surface (fine_mesh_too_coarse): a larger
//   base mesh or more levels.
// - Points left off the surface, or over kUncoveredCoarse of the surface
//   left out: the base mesh spans whole parts of the surface and the folds
//   are its own, which the pre-filter does not change; a larger base mesh.
//   Not more levels: those make the folds of the next case worse.
// - Otherwise the folds sit on necks, tunnels and specks under a cell across
//   (noisy scans and fine-grained fields, also where thin features are left
//   out; more levels fold more there): a one-voxel pre-filter
//   (docs/MEASUREMENTS.md has the figures), or with one already, a stronger
//   clean-up.
std::string fold_cause(const ConvertResult& result, const ConvertOptions& options) {
  if (fine_mesh_too_coarse(result.fine_vertices, result.extracted_vertices))
    return "where the base mesh is too coarse for the surface at " + std::to_string(result.levels) +
           " levels; a larger base mesh (--base-ratio, --base-vertices) or more levels (--levels) follow it";
  const bool far_off = double(result.fit_isosurface.far) > kFarPointsWarning * double(result.fine_vertices);
  if (far_off || result.uncovered_share > kUncoveredCoarse)
    return "where the base mesh is too coarse for the surface; a larger base mesh (--base-ratio, --base-vertices) "
           "follows it";
  if (options.prepare.extract.smooth_sigma == 0)
    return "mostly on necks, tunnels and specks under a cell across; a one-voxel pre-filter (--smooth 1) removes "
           "most of them";
  return "mostly on necks, tunnels and specks under a cell across that the pre-filter left; a larger --smooth or "
         "--min-component-vertices removes more of them";
}

// The warnings on the base mesh and the fit (one line each).
void add_fit_warnings(const ConvertOptions& options, std::size_t target, ConvertResult& result) {
  // The parametrization's area budget alone keeps target / share vertices.
  const double floor = options.fit == FitMethod::Parametrization ? double(target) / kParametrizationAreaShare
                                                                  : double(target);
  if (double(result.base_vertices) > 1.5 * floor) {
    std::ostringstream warning;
    warning << "the base mesh keeps " << result.base_vertices << " vertices (target " << std::llround(floor)
            << "): the isosurface has " << result.extraction.after.components << " components and genus "
            << result.extraction.after.genus
            << ", which the base mesh must keep; "
            << (options.prepare.extract.topology_tolerance > 0
                    ? "the topology still holds the base mesh large: a larger --topology-tolerance T removes more "
                      "handles and specks"
                    : "--topology-tolerance T removes handles, tunnels and specks under T cells");
    result.warnings.push_back(warning.str());
  }
  if (double(result.fit_isosurface.far) > kFarPointsWarning * double(result.fine_vertices)) {
    std::ostringstream warning;
    warning << "the fit leaves " << result.fit_isosurface.far << " of the " << result.fine_vertices
            << " fine control points (" << percent(double(result.fit_isosurface.far) / double(result.fine_vertices))
            << ") more than a cell off the isosurface (first-order estimate |f - iso| / |grad f|, largest "
            << std::setprecision(3) << result.fit_isosurface.max
            << " cells): parts of the surface lie beyond the reach of the base mesh; a larger base mesh "
               "(--base-ratio, --base-vertices) usually fixes it";
    result.warnings.push_back(warning.str());
  }
  if (result.uncovered_share > kUncoveredWarning) {
    std::ostringstream warning;
    warning << percent(result.uncovered_share) << " of the isosurface lies more than " << kUncoveredCells
            << " cells from every fine control point: the fit did not reach into features the base mesh spans; "
               "a larger base mesh (--base-ratio, --base-vertices) covers more";
    result.warnings.push_back(warning.str());
  }
  if (result.folded_share() > kFoldedWarning)
    result.warnings.push_back(percent(result.folded_share()) + " of the fine faces fold against the field gradient, " +
                              fold_cause(result, options));
}

// A fit whose faces mostly fold is a crumpled sheet: refused unless asked for.
void refuse_unusable_fit(const std::string& source, const ConvertOptions& options, const ConvertResult& result) {
  if (result.folded_share() <= kUnusableFolded || options.folded_fit == FoldedFit::Keep) return;
  const std::string cause = fold_cause(result, options);
  throw Error(ErrorKind::Unsupported, source + ": " + percent(result.folded_share()) +
                                          " of the fine faces fold against the field gradient, " + cause +
                                          "; the file would be unusable and is not written (--allow-folded writes it)");
}

IswMetadata metadata_of(const Volume& volume, const std::string& source, const ConvertOptions& options,
                        const ConvertResult& result) {
  const IsosurfaceOptions& extract = options.prepare.extract;
  IswMetadata metadata;
  metadata.values["source"] = source;
  metadata.values["isovalue"] = number(extract.iso);
  metadata.values["spacing"] = number(volume.spacing.x) + "," + number(volume.spacing.y) + "," + number(volume.spacing.z);
  metadata.values["origin"] = number(volume.origin.x) + "," + number(volume.origin.y) + "," + number(volume.origin.z);
  metadata.values["dims"] = std::to_string(volume.dims[0]) + "," + std::to_string(volume.dims[1]) + "," +
                            std::to_string(volume.dims[2]);
  metadata.values["cell_size"] = number(result.cell_size);
  if (volume.spacing.x != volume.spacing.y || volume.spacing.y != volume.spacing.z)
    metadata.values["cell_size_note"] = "geometric mean of the anisotropic spacing";
  metadata.values["levels"] = std::to_string(result.levels);
  metadata.values["extracted_vertices"] = std::to_string(result.extracted_vertices);
  metadata.values["base_vertices"] = std::to_string(result.base_vertices);
  metadata.values["fine_vertices"] = std::to_string(result.fine_vertices);
  metadata.values["fit_isosurface_rms_cells"] = number(result.fit_isosurface.rms);
  metadata.values["fit_isosurface_max_cells"] = number(result.fit_isosurface.max);
  metadata.values["isosurface_uncovered_share"] = number(result.uncovered_share);
  metadata.values["fit_folded_share"] = number(result.folded_share());
  metadata.values["options"] =
      "flip=" + std::to_string(extract.flip) + " min_component_vertices=" +
      std::to_string(extract.min_component_vertices) + " smooth_sigma=" + number(extract.smooth_sigma) +
      " levels=" + (options.levels > 0 ? std::to_string(options.levels) : std::string("auto")) +
      (options.base.vertices > 0 ? " base_vertices=" + std::to_string(options.base.vertices)
                                 : " base_ratio=" + number(options.base.ratio)) +
      " grow_base_until_covered=" + std::to_string(options.base.growth == BaseGrowth::UntilCovered) +
      " valence_flips=" + std::to_string(options.base.simplify.valence_flips) +
      " coverage_pull=" + std::to_string(options.shrink_wrap.coverage_pull) +
      " unfold_max_folded_fraction=" + number(options.shrink_wrap.unfold_max_folded_fraction) +
      " step_cells=" + number(options.step_cells);
  return metadata;
}

// The file at the plan's cut, its metadata recording the quantization error
// of that cut (the full decode against the fitted points). Under a size limit
// the final metadata's numbers may deflate to a few bytes more than the
// plan's: the cut then moves back by the excess. Returns what a 100% decode
// of the file gives (the plan's surface).
std::vector<Vec3> write_planned_file(const std::string& whole, detail::RatePlan plan, IswMetadata metadata,
                                     const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
                                     detail::FineSurfaceMeter& meter, const std::string& source,
                                     const ConvertOptions& options, ConvertResult& result) {
  const std::uint64_t limit = detail::byte_limit(options.rate, result.extracted_vertices);
  for (int attempt = 0;; ++attempt) {
    record_quantization_error(point_errors(plan.surface, result.fit.positions, plan.surface.size()), metadata);
    result.bytes = rewrite_isw(whole, IswRewrite{plan.stream_bytes, plan.table, &metadata});
    result.rate_table = plan.table;
    result.file_error = plan.error;
    if (limit == 0 || result.bytes.size() <= limit) return std::move(plan.surface);
    const std::uint64_t excess = result.bytes.size() - limit + 8;
    if (attempt == 3 || plan.stream_bytes <= excess)
      throw std::logic_error(source + ": the file does not fit the size its stream was cut for");
    detail::move_cut(plan, plan.stream_bytes - excess, whole, hierarchy, meter);
  }
}

// Per level, the share of the wavelet coefficients' energy along the
// normals of the file's local frames.
std::vector<double> normal_energy_share(const SubdivisionHierarchy& h, const std::vector<Vec3>& coefficients,
                                        const std::vector<Vec3>& normals) {
  std::vector<double> shares;
  for (int level = 1; level <= h.levels(); ++level) {
    double along = 0, all = 0;
    for (std::size_t i = h.vertex_count(level - 1); i < h.vertex_count(level); ++i) {
      along += dot(normals[i], coefficients[i]) * dot(normals[i], coefficients[i]);
      all += squared_norm(coefficients[i]);
    }
    shares.push_back(all > 0 ? along / all : 1.0);
  }
  return shares;
}

// Analysis (Sec. 3), the embedded stream down to the finest step, the cut
// the rate target asks for (rate_control.h), and the file: its metadata
// records the quantization error of the cut stream (the full decode against
// the fitted points) and its RDTB the D measured at the stream's prefixes.
// Returns what a 100% decode of the file gives; `planes` receives what the
// stream's plane ends decode to (the summary rows' prefixes).
std::vector<Vec3> analyze_and_encode(const std::shared_ptr<const SubdivisionHierarchy>& hierarchy,
                                     IswMetadata metadata, detail::FineSurfaceMeter& meter, const std::string& source,
                                     const ConvertOptions& options, ConvertResult& result, IswPlaneValues& planes,
                                     ProgressSink& progress) {
  const StageClock analysis_clock;
  progress.begin_stage("analysis");
  std::vector<Vec3> coefficients = result.fit.positions;
  analyze(*hierarchy, coefficients);
  progress.end_stage();
  analysis_clock.end(result.seconds.analysis, result.peak_bytes.analysis);

  const StageClock encode_clock;
  progress.begin_stage("encode");
  IswEncodeOptions encode_options;
  encode_options.step = options.step_cells * result.cell_size;
  encode_options.frame_step = kFrameStepCells * result.cell_size;
  if (!result.frame_base.empty()) encode_options.frame_base = &result.frame_base;
  const std::string whole = encode_isw(*hierarchy, coefficients, metadata, encode_options, planes);
  result.normal_share = normal_energy_share(*hierarchy, coefficients, planes.frame_normals());
  result.plane_bits = planes.plane_bits();
  std::vector<Vec3>().swap(coefficients);
  detail::RatePlan plan =
      detail::plan_rate(whole, planes, hierarchy, meter, options.rate, result.extracted_vertices, result.cell_size);
  if (plan.target_missed)
    result.warnings.push_back("the whole stream lies " + number(plan.error / result.cell_size) +
                              " cells from the isosurface, more than the maximum error asked for: the fit's own error "
                              "is the floor (more levels or a larger base mesh lower it)");
  std::vector<Vec3> full_decode =
      write_planned_file(whole, std::move(plan), std::move(metadata), hierarchy, meter, source, options, result);
  progress.end_stage();
  encode_clock.end(result.seconds.encode, result.peak_bytes.encode);
  return full_decode;
}

// Error summary (error_table, as stats makes it) of the file as written,
// decoded (its sections and metadata are the final ones; its surface must be
// the one the encoder planned), and each row's D against the extracted
// isosurface, measured on the row's synthesis (one at a time; a row keeping
// every coefficient is the file's, a repeated row the row before's).
void evaluate(const std::shared_ptr<const SubdivisionHierarchy>& hierarchy, const std::vector<Vec3>& full_decode,
              const IswPlaneValues& planes, detail::FineSurfaceMeter& meter, const std::string& source,
              const ConvertOptions& options, ConvertResult& result, ProgressSink& progress) {
  const StageClock clock;
  progress.begin_stage("evaluate");
  IswDecodeOptions decode_options;
  decode_options.hierarchy = hierarchy;
  const IswDecoded decoded = decode_isw(result.bytes, source, decode_options);
  if (reconstruct(decoded, SIZE_MAX) != full_decode)
    throw std::logic_error(source + ": the file written does not decode to the surface it was planned with");
  std::vector<double>& d_cells = result.summary_surface_error;
  d_cells.assign(options.summary_percents.size() + 1, result.file_error / result.cell_size);
  std::map<std::size_t, double> by_wavelets;  // rows keeping as many coefficients keep the same ones
  const auto measure_row = [&](std::size_t row, std::size_t wavelets, std::vector<Vec3>& surface) {
    const auto known = by_wavelets.find(wavelets);
    d_cells[row] = known != by_wavelets.end() ? known->second : meter.d(surface) / result.cell_size;
    by_wavelets[wavelets] = d_cells[row];
  };
  // A row reading a prefix keeps the most important of what that plane end
  // decodes to, which the encoder knows (no decoding).
  const auto prefix_values = [&](std::uint64_t stream_bytes, std::vector<Vec3>& coefficients) {
    const std::vector<std::uint64_t>& ends = planes.plane_ends();
    const auto end = std::find(ends.begin(), ends.end(), stream_bytes);
    if (end == ends.end()) throw std::logic_error(source + ": a summary row's prefix ends inside a plane");
    planes.coefficients_at(static_cast<std::size_t>(end - ends.begin()), coefficients);
  };
  ErrorTable errors = error_table(decoded, options.summary_percents, &full_decode, measure_row, prefix_values);
  result.summary = std::move(errors.rows);
  result.quantization = errors.quantization;
  progress.end_stage();
  clock.end(result.seconds.evaluate, result.peak_bytes.evaluate);
}

}  // namespace

ConvertResult convert_volume(Volume volume, const std::string& source, const ConvertOptions& options,
                             ProgressSink& progress) {
  check_options(options);
  ConvertResult result;
  result.cell_size = volume.cell_size();

  const StageClock extract_clock;
  PreparedSurface prepared = extract_surface(std::move(volume), options.prepare, source, progress);
  result.extraction = prepared.isosurface.report;
  result.extracted_vertices = prepared.isosurface.mesh.vertex_count();
  extract_clock.end(result.seconds.extract, result.peak_bytes.extract);

  std::size_t target = 0;
  // D's reference, for the levels and the summary rows, and the levels'
  // bound (in the fit's time).
  const StageClock reference_clock;
  const SurfaceErrorReference against_surface(prepared.isosurface.mesh, kErrorSamples);
  result.max_error_cells = level_error_bound(prepared, options);
  reference_clock.end(result.seconds.fit, result.peak_bytes.fit);
  const std::shared_ptr<const SubdivisionHierarchy> fitted =
      base_and_fit(prepared, against_surface, options, result, target, progress);
  add_fit_warnings(options, target, result);
  refuse_unusable_fit(source, options, result);
  // The same surface over the base in the order its coder sends compactly
  // (in the analysis' time).
  const StageClock order_clock;
  CanonicalSurface canonical = canonical_surface(fitted, std::move(result.fit.positions));
  const std::shared_ptr<const SubdivisionHierarchy> hierarchy = canonical.hierarchy;
  result.fit.positions = std::move(canonical.fine);
  if (!result.frame_base.empty()) result.frame_base = renumbered(result.frame_base, canonical.base_order);
  result.hierarchy = hierarchy;
  IswMetadata metadata = metadata_of(prepared.field, source, options, result);

  // What the coding stages no longer need goes before their peak.
  if (options.keep_extracted_mesh) result.extracted_mesh = std::move(prepared.isosurface.mesh);
  prepared = PreparedSurface{};

  // D of the rate table's prefixes and of the summary rows, over one fine mesh.
  detail::FineSurfaceMeter meter(*hierarchy, against_surface);
  order_clock.end(result.seconds.analysis, result.peak_bytes.analysis);
  IswPlaneValues planes;
  const std::vector<Vec3> full_decode =
      analyze_and_encode(hierarchy, std::move(metadata), meter, source, options, result, planes, progress);
  evaluate(hierarchy, full_decode, planes, meter, source, options, result, progress);
  return result;
}

}  // namespace isowave
