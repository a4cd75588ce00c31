#include "isowave/codec/convert.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <future>
#include <iomanip>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <tbb/task_arena.h>

#include "isowave/codec/importance.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {

double ConvertResult::tangled_share() const {
  return fine_faces ? double(fit.tangled_faces) / double(fine_faces) : 0.0;
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

LevelCounts counts_of(const PolygonMesh& base) { return level_counts(base, summarize_topology(base).edges); }

// The level whose fine mesh has about as many vertices as the isosurface.
int automatic_levels(const PolygonMesh& base, std::size_t isosurface_vertices) {
  int levels = 1;
  double best = 1e300;
  const std::vector<LevelCounts> counts = refinement_counts(counts_of(base), 6);
  for (int l = 1; l <= 6; ++l) {
    const double fine = std::floor(counts[static_cast<std::size_t>(l)].vertices);
    const double misfit = std::abs(std::log(fine / static_cast<double>(isosurface_vertices)));
    if (misfit < best) {
      best = misfit;
      levels = l;
    }
    if (fine > 4.0 * static_cast<double>(isosurface_vertices)) break;
  }
  return levels;
}

}  // namespace

std::size_t fine_vertex_count(const PolygonMesh& base, int levels) {
  return static_cast<std::size_t>(refinement_counts(counts_of(base), levels).back().vertices);
}

ConvertResult convert_volume(const Volume& volume, const std::string& source, const ConvertOptions& options,
                             ProgressSink& progress) {
  if (options.levels < 0 || options.levels > 6)
    throw Error(ErrorKind::InvalidArgument, "levels must be in 1..6, or 0 for automatic");
  if (!(options.base_ratio > 0 && options.base_ratio <= 1))
    throw Error(ErrorKind::InvalidArgument, "the base ratio must be in (0, 1]");
  if (!(options.step_cells > 0) || !std::isfinite(options.step_cells))
    throw Error(ErrorKind::InvalidArgument, "the quantization step must be positive");
  ConvertResult result;
  result.cell_size = volume.cell_size();

  // Extraction; with smoothing, the distance field and the final correction
  // must use the smoothed field the surface came from.
  auto start = Clock::now();
  const Volume smoothed = options.smooth_sigma > 0 ? gaussian_smoothed(volume, options.smooth_sigma) : Volume{};
  const Volume& field = options.smooth_sigma > 0 ? smoothed : volume;
  IsosurfaceOptions extract_options;
  extract_options.iso = options.iso;
  extract_options.flip = options.flip;
  extract_options.min_component_vertices = options.min_component_vertices;
  Isosurface surface = extract_isosurface(field, extract_options, progress);
  surface.report.smooth_sigma = options.smooth_sigma;
  result.extraction = surface.report;
  result.extracted_vertices = surface.mesh.vertex_count();
  result.seconds.extract = seconds_since(start);
  if (surface.mesh.face_count() == 0)
    throw Error(ErrorKind::InvalidArgument,
                source + ": the isosurface at " + number(options.iso) + " is empty" + value_range_note(field));

  // The signed-distance field needs only the field and the extracted mesh:
  // it is computed alongside the base mesh, started when the simplification
  // turns serial and leaves a core idle (on miranda 1.2 s sooner than when
  // both competed for the cores from the start). No progress from it: the
  // sink shows one stage at a time.
  SignedDistanceOptions distance_options;
  distance_options.iso = options.iso;
  distance_options.flip = options.flip;
  distance_options.surface = &surface.mesh;
  distance_options.band_cells = options.distance_band_cells;
  std::future<std::unique_ptr<SignedDistanceField>> distance_pending;
  const auto start_distance = [&] {
    distance_pending = std::async(std::launch::async, [&field, &distance_options] {
      // On one thread: two would take the core the simplification runs on.
      tbb::task_arena one_thread(1);
      return one_thread.execute(
          [&] { return std::make_unique<SignedDistanceField>(compute_signed_distance(field, distance_options)); });
    });
  };

  // Base mesh, levels, shrink-wrap and the fit check; with
  // options.grow_base_until_covered, again from a base mesh twice as large
  // while more than kUncoveredWarning of the isosurface is left out.
  simplify::SimplifyOptions simplify_options;
  simplify_options.target_vertices = options.base_vertices > 0
                                         ? options.base_vertices
                                         : std::max<std::size_t>(4, static_cast<std::size_t>(std::llround(
                                                                        options.base_ratio * result.extracted_vertices)));
  simplify_options.compute_distance = false;
  simplify_options.valence_flips = options.valence_flips;
  simplify_options.serial_phase_begins = start_distance;
  std::unique_ptr<SignedDistanceField> distance;
  std::shared_ptr<const SubdivisionHierarchy> shared_hierarchy;
  for (result.base_attempts = 1;; ++result.base_attempts) {
    start = Clock::now();
    simplify::SimplifyResult simplified = simplify::simplify(surface.mesh, simplify_options, progress);
    simplify_options.serial_phase_begins = nullptr;  // the distance field is on its way
    result.simplification = simplified.report;
    const PolygonMesh base = std::move(simplified.base);
    result.base_vertices = base.vertex_count();
    if (result.base_attempts == 1) result.first_base_vertices = base.vertex_count();
    result.seconds.simplify += seconds_since(start);
    result.levels = options.levels > 0 ? options.levels : automatic_levels(base, result.extracted_vertices);

    // Shrink-wrap, once the distance field is there.
    if (!distance) {
      start = Clock::now();
      progress.begin_stage("signed distance");
      distance = distance_pending.get();
      progress.end_stage();
      result.seconds.distance = seconds_since(start);
    }
    start = Clock::now();
    result.fit = ShrinkWrapResult{};  // the previous try's, before the next one's peak
    shared_hierarchy.reset();
    shared_hierarchy = std::make_shared<const SubdivisionHierarchy>(base, result.levels);
    result.fine_vertices = shared_hierarchy->fine_vertex_count();
    // Each parent face of n corners gives n quads.
    result.fine_faces =
        result.levels > 0 ? shared_hierarchy->step(result.levels).face_vertices.size() : base.face_count();
    ShrinkWrapOptions wrap_options = options.shrink_wrap;
    wrap_options.surface = &surface.mesh;
    wrap_options.coverage_pull = options.coverage_pull;
    result.fit = shrink_wrap(*shared_hierarchy, base.positions, *distance, field, wrap_options, progress);
    // The fit against the isosurface, both ways; the error rows, measured
    // against the fit, cannot show what it missed. A base mesh too coarse for
    // the surface leaves parts of it out of the attraction's reach and the
    // fine points there off the isosurface (more than a cell off: the
    // built-in torus at 48^3 from 9 base vertices 58% of the points, from 16
    // none; miranda smoothed by one voxel from 7,446 base vertices 0.66%, up
    // to 109 cells; the bench's miranda 0.065%), and parts of the isosurface
    // no fine point comes near (thin features the base mesh spans; every
    // stride-th isosurface vertex, at most 100,000, 0.1 s on miranda).
    result.fit_isosurface = isosurface_distance(result.fit.positions, result.fine_vertices, field, options.iso, 1.0);
    const std::size_t stride = std::max<std::size_t>(1, surface.mesh.vertex_count() / 100000);
    result.uncovered_share = share_farther_than(surface.mesh.positions, stride, result.fit.positions,
                                                result.fine_vertices, kUncoveredCells * result.cell_size);
    result.seconds.fit += seconds_since(start);
    // With the levels fixed, a larger base multiplies the fine mesh (miranda
    // at L = 3 from 261,000 base vertices: 18 M points): it grows only when
    // the levels follow it.
    const std::size_t grown = 2 * base.vertex_count();
    if (!options.grow_base_until_covered || options.levels != 0 || result.uncovered_share <= kUncoveredWarning ||
        result.base_attempts == kBaseAttempts || grown > result.extracted_vertices / 4)
      break;
    simplify_options.target_vertices = grown;
  }
  if (result.base_vertices > 3 * simplify_options.target_vertices / 2) {
    std::ostringstream warning;
    warning << "the base mesh keeps " << result.base_vertices << " vertices (target " << simplify_options.target_vertices
            << "): the isosurface has " << surface.report.after.components << " components and genus "
            << surface.report.after.genus
            << ", which the base mesh must keep; --min-component-vertices N and --smooth SIGMA remove small bubbles "
               "and handles";
    result.warnings.push_back(warning.str());
  }
  const bool far_off = double(result.fit_isosurface.far) > kFarPointsWarning * double(result.fine_vertices);
  if (far_off) {
    std::ostringstream warning;
    warning << "the fit leaves " << result.fit_isosurface.far << " of the " << result.fine_vertices
            << " fine control points (" << std::setprecision(2)
            << 100.0 * double(result.fit_isosurface.far) / double(result.fine_vertices)
            << "%) more than a cell off the isosurface, up to " << std::setprecision(3) << result.fit_isosurface.max
            << " cells: parts of the surface lie beyond the reach of the base mesh; a larger base mesh "
               "(--base-ratio, --base-vertices) usually fixes it";
    result.warnings.push_back(warning.str());
  }
  if (result.uncovered_share > kUncoveredWarning) {
    std::ostringstream warning;
    warning << std::setprecision(2) << 100.0 * result.uncovered_share << "% of the isosurface lies more than "
            << kUncoveredCells
            << " cells from every fine control point: the fit did not reach into features the base mesh spans; "
               "a larger base mesh (--base-ratio, --base-vertices) covers more";
    result.warnings.push_back(warning.str());
  }
  // Where the fit did not follow the surface (points left off it, parts left
  // out, or a fine mesh too coarse for it), the folds come from the base
  // mesh, which the pre-filter does not change (the torus at 160^3 from 9
  // base vertices, 3 levels: 57% folded, 44% with --smooth 1).
  const bool too_coarse = far_off || result.uncovered_share > kUncoveredWarning ||
                          fine_mesh_too_coarse(result.fine_vertices, result.extracted_vertices);
  if (result.tangled_share() > kFoldedWarning && (too_coarse || options.smooth_sigma == 0)) {
    std::ostringstream warning;
    warning << std::setprecision(2) << 100.0 * result.tangled_share() << "% of the fine faces fold against the field gradient";
    if (too_coarse)
      warning << ", where the base mesh is too coarse for the surface; a larger base mesh (--base-ratio, --base-vertices) "
                 "or more levels (--levels) follow it";
    else
      warning << ", mostly on necks, tunnels and specks under a cell across; a one-voxel pre-filter (--smooth 1) "
                 "removes most of them";
    result.warnings.push_back(warning.str());
  }
  const SubdivisionHierarchy& hierarchy = *shared_hierarchy;
  // What the coding stages no longer need goes before their peak.
  distance.reset();
  if (!options.keep_extracted_mesh) surface.mesh = PolygonMesh{};

  // Analysis and coding.
  start = Clock::now();
  progress.begin_stage("analysis");
  std::vector<Vec3> coefficients = result.fit.positions;
  analyze(hierarchy, coefficients);
  progress.end_stage();
  result.seconds.analysis = seconds_since(start);

  start = Clock::now();
  progress.begin_stage("encode");
  IswMetadata metadata;
  metadata.values["source"] = source;
  metadata.values["isovalue"] = number(options.iso);
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
  metadata.values["fit_tangled_share"] = number(result.tangled_share());
  metadata.values["options"] =
      "flip=" + std::to_string(options.flip) + " min_component_vertices=" +
      std::to_string(options.min_component_vertices) + " smooth_sigma=" + number(options.smooth_sigma) +
      " levels=" + (options.levels > 0 ? std::to_string(options.levels) : std::string("auto")) +
      (options.base_vertices > 0 ? " base_vertices=" + std::to_string(options.base_vertices)
                                 : " base_ratio=" + number(options.base_ratio)) +
      " grow_base_until_covered=" + std::to_string(options.grow_base_until_covered) +
      " valence_flips=" + std::to_string(options.valence_flips) +
      " coverage_pull=" + std::to_string(options.coverage_pull) +
      " unfold_max_tangled_fraction=" + number(options.shrink_wrap.unfold_max_tangled_fraction) +
      " step_cells=" + number(options.step_cells);
  IswEncodeOptions encode_options;
  encode_options.step = options.step_cells * result.cell_size;
  encode_options.class_weights = wavelet_norms(hierarchy);
  // Record the error quantization adds: the full decode of the coefficients
  // exactly as stored against the fitted points (the summary's rows are
  // measured against that full decode).
  std::vector<Vec3> stored =
      quantize_coefficients(hierarchy, coefficients, encode_options.step, encode_options.class_weights);
  std::vector<Vec3> full_decode = stored;
  synthesize(hierarchy, full_decode);
  record_quantization_error(point_errors(full_decode, result.fit.positions, full_decode.size()), metadata);
  std::vector<std::uint32_t> ranked;
  result.bytes = encode_isw(hierarchy, coefficients, metadata, encode_options, &ranked);
  std::vector<Vec3>().swap(coefficients);
  progress.end_stage();
  result.seconds.encode = seconds_since(start);

  // Error summary (error_table, as stats makes it), from what the file
  // holds as the encoder stored it: decoding the file again took 1.6 s of
  // the 3.3 s this stage took on miranda (options.verify_file still does).
  start = Clock::now();
  progress.begin_stage("evaluate");
  const IswDecoded expected = expected_decode(shared_hierarchy, std::move(stored), std::move(ranked), result.bytes, source);
  std::future<bool> decodes_as_expected;
  if (options.verify_file)
    decodes_as_expected = std::async(std::launch::async, [&] {
      IswDecodeOptions decode_options;
      decode_options.hierarchy = shared_hierarchy;
      const IswDecoded decoded = decode_isw(result.bytes, source, decode_options);
      return decoded.ranked == expected.ranked && decoded.coefficients == expected.coefficients;
    });
  ErrorTable errors = error_table(expected, options.summary_percents, &full_decode);
  result.summary = std::move(errors.rows);
  result.quantization = errors.quantization;
  if (decodes_as_expected.valid() && !decodes_as_expected.get())
    throw std::logic_error(source + ": the file written does not decode to the coefficients it was coded from");
  progress.end_stage();
  result.seconds.evaluate = seconds_since(start);
  if (options.keep_extracted_mesh) result.extracted_mesh = std::move(surface.mesh);
  return result;
}

}  // namespace isowave
