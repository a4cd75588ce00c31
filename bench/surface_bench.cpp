#include "surface_bench.h"

#include <fcntl.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/mesh_topology.h"
#include "isowave/fit/fold_repair.h"
#include "isowave/fit/wrap_level_mesh.h"
#include "isowave/pipeline/prepare.h"
#include "isowave/transform/hierarchy.h"

namespace isowave::bench {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

[[noreturn]] void exit_with_usage(const char* program, const std::string& problem, const char* extra_usage) {
  std::fprintf(stderr,
               "%s: %s\nusage: %s VOLUME --iso V [--levels N] [--min-component-vertices N] [--smooth S] "
               "[--topology-tolerance T] [--flips] [--fit shrink-wrap|parametrization|normal|both|all]%s\n",
               program, problem.c_str(), program, extra_usage);
  std::exit(2);
}

}  // namespace

BenchOptions parse_options(int argc, char** argv, const char* program, BenchOptions defaults,
                           const char* extra_usage) {
  const auto usage = [&](const std::string& problem) { exit_with_usage(program, problem, extra_usage); };
  BenchOptions o = std::move(defaults);
  bool has_iso = false;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    const auto next = [&]() -> std::string {
      if (a + 1 >= argc) usage("missing value for " + arg);
      return argv[++a];
    };
    try {
      if (arg == "--iso") {
        o.extract.iso = std::stod(next());
        has_iso = true;
      } else if (arg == "--levels") {
        o.levels = std::stoi(next());
      } else if (arg == "--min-component-vertices") {
        o.extract.min_component_vertices = std::stoul(next());
      } else if (arg == "--smooth") {
        o.extract.smooth_sigma = std::stod(next());
      } else if (arg == "--topology-tolerance") {
        o.extract.topology_tolerance = std::stod(next());
      } else if (arg == "--flips") {
        o.valence_flips = true;
      } else if (arg == "--fit") {
        const std::string fit = next();
        if (fit == "shrink-wrap") o.fits = {FitMethod::ShrinkWrap};
        else if (fit == "parametrization") o.fits = {FitMethod::Parametrization};
        else if (fit == "normal") o.fits = {FitMethod::Normal};
        else if (fit == "both") o.fits = {FitMethod::ShrinkWrap, FitMethod::Parametrization};
        else if (fit == "all") o.fits = {FitMethod::ShrinkWrap, FitMethod::Parametrization, FitMethod::Normal};
        else usage("--fit expects shrink-wrap, parametrization, normal, both or all");
      } else if (arg.rfind("--", 0) == 0 || !o.input.empty()) {
        usage("unexpected argument " + arg);
      } else {
        o.input = arg;
      }
    } catch (const std::logic_error&) {  // std::stod and friends
      usage("bad value for " + arg);
    }
  }
  if (o.input.empty() || !has_iso) usage("a volume and --iso are required");
  return o;
}

const char* fit_name(FitMethod fit) {
  switch (fit) {
    case FitMethod::ShrinkWrap: return "shrink-wrap";
    case FitMethod::Parametrization: return "parametrization";
    case FitMethod::Normal: return "normal";
  }
  return "?";
}

// ---------------------------------------------------------------------------
// The fits, each in a forked child.

namespace {

void write_bytes(int fd, const void* data, std::size_t size) {
  const char* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t written = write(fd, bytes, size);
    if (written <= 0) _exit(3);
    bytes += written;
    size -= std::size_t(written);
  }
}

template <typename T>
void write_array(int fd, const std::vector<T>& values) {
  const std::uint64_t count = values.size();
  write_bytes(fd, &count, sizeof count);
  write_bytes(fd, values.data(), count * sizeof(T));
}

// All the bytes a child wrote, until it closed the pipe.
std::string read_all(int fd) {
  std::string bytes;
  char buffer[1 << 16];
  ssize_t got;
  while ((got = read(fd, buffer, sizeof buffer)) > 0) bytes.append(buffer, std::size_t(got));
  return bytes;
}

// Reads from `bytes` at `at`; false when they end too soon.
bool read_bytes(const std::string& bytes, std::size_t& at, void* out, std::size_t size) {
  if (bytes.size() - at < size) return false;
  std::copy_n(bytes.data() + at, size, static_cast<char*>(out));
  at += size;
  return true;
}

template <typename T>
bool read_array(const std::string& bytes, std::size_t& at, std::vector<T>& values) {
  std::uint64_t count = 0;
  if (!read_bytes(bytes, at, &count, sizeof count) || count > (bytes.size() - at) / sizeof(T)) return false;
  values.resize(count);
  return read_bytes(bytes, at, values.data(), count * sizeof(T));
}

// The child's work: convert the volume as the CLI does by default and send
// the outcome to `fd`.
void run_fit(const BenchOptions& o, FitMethod fit, int fd) {
  FitStatus status = FitStatus::Done;
  std::string message;
  try {
    ConvertOptions options;
    options.prepare.extract = o.extract;
    options.levels = o.levels;
    options.fit = fit;
    options.base.simplify.valence_flips = o.valence_flips;
    options.base.growth = BaseGrowth::UntilCovered;  // the CLI's default without a base size
    options.folded_fit = FoldedFit::Keep;
    options.summary_percents = o.summary_percents;
    const ConvertResult result = convert_volume(load_volume(o.input, {}), o.input, options);
    const PolygonMesh fine = result.hierarchy->control_mesh(result.levels, result.fit.positions);
    const FitFigures figures{result.levels,           result.base_vertices,    result.fine_vertices,
                             result.folded_share(),   result.seconds.simplify, result.seconds.distance,
                             result.seconds.fit,      result.seconds.total()};
    write_bytes(fd, &status, sizeof status);
    write_bytes(fd, &figures, sizeof figures);
    write_array(fd, fine.positions);
    write_array(fd, fine.face_offsets);
    write_array(fd, fine.face_vertices);
    write_array(fd, std::vector<char>(result.bytes.begin(), result.bytes.end()));
    write_array(fd, result.summary);
    return;
  } catch (const Error& e) {
    status = e.kind() == ErrorKind::Unsupported ? FitStatus::NotAvailable : FitStatus::Failed;
    message = e.what();
  } catch (const std::exception& e) {
    status = FitStatus::Failed;
    message = e.what();
  }
  write_bytes(fd, &status, sizeof status);
  write_array(fd, std::vector<char>(message.begin(), message.end()));
}

FitOutcome decode_outcome(const std::string& bytes) {
  FitOutcome outcome;
  std::size_t at = 0;
  std::vector<char> message, file;
  const bool complete =
      read_bytes(bytes, at, &outcome.status, sizeof outcome.status) &&
      (outcome.status == FitStatus::Done
           ? read_bytes(bytes, at, &outcome.figures, sizeof outcome.figures) &&
                 read_array(bytes, at, outcome.fine.positions) && read_array(bytes, at, outcome.fine.face_offsets) &&
                 read_array(bytes, at, outcome.fine.face_vertices) && read_array(bytes, at, file) &&
                 read_array(bytes, at, outcome.summary)
           : read_array(bytes, at, message));
  outcome.message.assign(message.begin(), message.end());
  outcome.file.assign(file.begin(), file.end());
  if (!complete) {
    outcome.status = FitStatus::Failed;
    outcome.message = "the child's report ended early";
  }
  return outcome;
}

}  // namespace

FitOutcome fit_in_child(const BenchOptions& o, FitMethod fit) {
  int pipe_ends[2];
  if (pipe(pipe_ends) != 0) throw std::runtime_error("pipe() failed");
  std::fflush(stdout);
  const pid_t child = fork();
  if (child < 0) throw std::runtime_error("fork() failed");
  if (child == 0) {
    close(pipe_ends[0]);
    run_fit(o, fit, pipe_ends[1]);
    close(pipe_ends[1]);
    _exit(0);
  }
  close(pipe_ends[1]);
  FitOutcome outcome = decode_outcome(read_all(pipe_ends[0]));
  close(pipe_ends[0]);
  int status = 0;
  rusage usage_of_child{};
  wait4(child, &status, 0, &usage_of_child);
  outcome.peak_megabytes = double(usage_of_child.ru_maxrss) / 1024.0;  // Linux: kilobytes
  if (WIFSIGNALED(status)) {
    outcome.status = FitStatus::Failed;
    outcome.message = "the child died of signal " + std::to_string(WTERMSIG(status));
  }
  return outcome;
}

// ---------------------------------------------------------------------------
// The reference and the measures.

namespace {

// The field sampled at twice the resolution by trilinear interpolation:
// dims 2n - 1 per axis, spacing halved, same origin. Sample (i, j, k) is the
// mean of the input samples at (floor or ceil of i/2, j/2, k/2): the
// trilinear value at that midpoint (NaN where one of them is NaN).
Volume upsampled_twice(const Volume& field) {
  Volume fine;
  for (int a = 0; a < 3; ++a) fine.dims[a] = 2 * field.dims[a] - 1;
  fine.spacing = 0.5 * field.spacing;
  fine.origin = field.origin;
  fine.source_type = field.source_type;
  fine.values.resize(fine.sample_count());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fine.dims[2]), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k)
      for (std::size_t j = 0; j < fine.dims[1]; ++j)
        for (std::size_t i = 0; i < fine.dims[0]; ++i) {
          double sum = 0;
          for (int corner = 0; corner < 8; ++corner)
            sum += field.at((i + (corner & 1)) / 2, (j + (corner >> 1 & 1)) / 2, (k + (corner >> 2)) / 2);
          fine.values[fine.index(i, j, k)] = float(sum / 8);
        }
  });
  return fine;
}

// The cell of the grid of `field` that holds p (clamped to the grid).
std::size_t cell_of(const Volume& field, const Vec3& p) {
  std::size_t index[3];
  for (int a = 0; a < 3; ++a) {
    const double at = std::floor((p[a] - field.origin[a]) / field.spacing[a]);
    index[a] = std::size_t(std::clamp(at, 0.0, double(field.dims[a] - 2)));
  }
  return index[0] + (field.dims[0] - 1) * (index[1] + (field.dims[1] - 1) * index[2]);
}

Vec3 centroid(const PolygonMesh& mesh, std::size_t f) {
  Vec3 sum;
  for (std::uint32_t c = 0; c < mesh.face_size(f); ++c) sum += mesh.positions[mesh.face_begin(f)[c]];
  return sum * (1.0 / mesh.face_size(f));
}

// Leaves out the faces of `reference` whose cell of `field`'s grid holds
// faces of components of the contour under min_vertices vertices and none of
// larger ones.
void leave_out_dropped_cells(PolygonMesh& reference, const Volume& field, double iso, bool flip,
                             std::size_t min_vertices) {
  const PolygonMesh contour = contour_volume(field, iso, flip);
  std::vector<std::uint32_t> face_component;
  const std::vector<TopologySummary> components = summarize_components(contour, &face_component);
  enum : std::uint8_t { kKept = 1, kDropped = 2 };
  std::vector<std::uint8_t> cells((field.dims[0] - 1) * (field.dims[1] - 1) * (field.dims[2] - 1), 0);
  for (std::size_t f = 0; f < contour.face_count(); ++f)
    cells[cell_of(field, centroid(contour, f))] |=
        components[face_component[f]].vertices < min_vertices ? kDropped : kKept;
  PolygonMesh kept;
  for (std::size_t f = 0; f < reference.face_count(); ++f)
    if (cells[cell_of(field, centroid(reference, f))] != kDropped)
      kept.add_face(reference.face_begin(f), reference.face_size(f));
  kept.positions = std::move(reference.positions);
  remove_unreferenced_vertices(kept);
  reference = std::move(kept);
}

}  // namespace

Surfaces extract_surfaces(const BenchOptions& o) {
  PrepareOptions prepare;
  prepare.extract = o.extract;
  prepare.extract.topology_tolerance = 0;  // D is against the isosurface the user had
  PreparedSurface prepared = extract_surface(load_volume(o.input, {}), prepare, o.input);
  Surfaces s;
  s.cell = prepared.field.cell_size();
  s.marching_cubes = std::move(prepared.isosurface.mesh);
  const auto start = Clock::now();
  const Volume fine = upsampled_twice(prepared.field);
  s.reference = contour_volume(fine, o.extract.iso, o.extract.flip);
  if (o.extract.min_component_vertices > 1)
    leave_out_dropped_cells(s.reference, prepared.field, o.extract.iso, o.extract.flip, o.extract.min_component_vertices);
  std::printf("%s, iso %g: %zu x %zu x %zu samples, cell %g\n", o.input.c_str(), o.extract.iso, prepared.field.dims[0],
              prepared.field.dims[1], prepared.field.dims[2], s.cell);
  std::printf("marching cubes: %zu vertices; reference (%zu x %zu x %zu upsample): %zu vertices, in %.1f s\n",
              s.marching_cubes.vertex_count(), fine.dims[0], fine.dims[1], fine.dims[2], s.reference.vertex_count(),
              seconds_since(start));
  // The marching-cubes mesh by the fits' fold test (face normal against the field gradient at its centroid).
  const SubdivisionHierarchy as_base(s.marching_cubes, 0);
  const WrapLevelMesh level = make_wrap_level_mesh(as_base, 0, s.marching_cubes.positions, prepared.field, o.extract.iso);
  const std::size_t folded = count_folded_faces(level, s.marching_cubes.positions, prepared.field,
                                                orientation_from_flip(o.extract.flip));
  std::printf("marching cubes: %.3f%% of its faces folded by the fits' test\n",
              100.0 * double(folded) / double(std::max<std::size_t>(1, s.marching_cubes.face_count())));
  if (o.extract.topology_tolerance > 0) {
    IsosurfaceOptions tolerant = o.extract;
    tolerant.smooth_sigma = 0;  // prepared.field is already pre-filtered
    Volume cleaned = prepared.field;
    s.tolerant = extract_isosurface_in_place(cleaned, tolerant).mesh;
    s.kept_reference = contour_volume(upsampled_twice(cleaned), o.extract.iso, o.extract.flip);
  }
  return s;
}

SurfaceError print_error(const char* what, const PolygonMesh& mesh, const PolygonMesh& against, double cell) {
  const SurfaceError e = surface_error(mesh, against);
  const auto pct = [&](double value) { return 100 * value / cell; };
  std::printf("  %-28s D %7.3f%%   forward rms %7.3f%% max %8.2f%%   backward rms %7.3f%% max %8.2f%%\n", what,
              pct(e.d()), pct(e.forward_rms), pct(e.forward_max), pct(e.backward_rms), pct(e.backward_max));
  return e;
}

FitRuns run_fits(const BenchOptions& o) {
  FitRuns runs;
  for (const FitMethod fit : o.fits) runs.outcomes.push_back(fit_in_child(o, fit));
  runs.surfaces = extract_surfaces(o);
  const Surfaces& s = runs.surfaces;
  runs.marching_cubes_d = print_error("marching cubes vs reference", s.marching_cubes, s.reference, s.cell).d();
  if (s.tolerant.face_count() > 0) {
    print_error("marching cubes, tolerance", s.tolerant, s.reference, s.cell);
    runs.kept_marching_cubes_d = print_error("  the same vs kept reference", s.tolerant, s.kept_reference, s.cell).d();
  }
  return runs;
}

bool print_fit(FitMethod fit, const FitOutcome& outcome, const Surfaces& s, double marching_cubes_d,
               double kept_marching_cubes_d) {
  if (outcome.status != FitStatus::Done) {
    std::printf("%s: %s (%s)\n", fit_name(fit), outcome.status == FitStatus::NotAvailable ? "not available" : "failed",
                outcome.message.c_str());
    return false;
  }
  const FitFigures& f = outcome.figures;
  std::printf(
      "%s: levels %d, base %llu vertices, fine %llu vertices, folded %.3f%%, file %zu bytes\n"
      "  seconds: simplify %.2f, wait for the distance field %.2f, fit %.2f, whole convert %.2f; peak %.0f MB (the "
      "whole convert, in a child)\n",
      fit_name(fit), f.levels, static_cast<unsigned long long>(f.base_vertices),
      static_cast<unsigned long long>(f.fine_vertices), 100 * f.folded_share, outcome.file.size(), f.simplify_seconds,
      f.distance_seconds,
      f.fit_seconds, f.convert_seconds, outcome.peak_megabytes);
  const double d = print_error("fine mesh vs reference", outcome.fine, s.reference, s.cell).d();
  print_error("fine mesh vs marching cubes", outcome.fine, s.marching_cubes, s.cell);
  const double bound = std::max(1.25 * marching_cubes_d, 0.01 * s.cell);
  std::printf("  D(fit) / D(marching cubes) vs reference: %.2f  (target D <= %.3f%% of a cell: %s)\n",
              d / marching_cubes_d, 100 * bound / s.cell, d <= bound ? "met" : "missed");
  if (kept_marching_cubes_d > 0) {
    const double kept = print_error("fine mesh vs kept reference", outcome.fine, s.kept_reference, s.cell).d();
    std::printf("  D(fit) / D(marching cubes after the tolerance) vs the kept reference: %.2f\n",
                kept / kept_marching_cubes_d);
  }
  return true;
}

// ---------------------------------------------------------------------------
// Draco.

namespace {

// Runs `command` (found on PATH, output discarded) and waits for it; its
// wall-clock seconds, or a negative number if it could not run or failed.
double run_quietly(const std::vector<std::string>& command) {
  std::vector<char*> args;
  for (const std::string& arg : command) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  std::fflush(stdout);
  const auto start = Clock::now();
  const pid_t child = fork();
  if (child < 0) return -1;
  if (child == 0) {
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    dup2(null, STDERR_FILENO);
    execvp(args[0], args.data());
    _exit(127);
  }
  int status = 0;
  if (waitpid(child, &status, 0) != child || !WIFEXITED(status) || WEXITSTATUS(status) != 0) return -1;
  return seconds_since(start);
}

}  // namespace

bool DracoCoder::available() {
  return std::system("command -v draco_encoder >/dev/null 2>&1 && command -v draco_decoder >/dev/null 2>&1") == 0;
}

DracoCoder::DracoCoder(const PolygonMesh& mesh) {
  char directory[] = "/tmp/isowave_bench_draco_XXXXXX";
  if (!mkdtemp(directory)) throw std::runtime_error("mkdtemp() failed");
  directory_ = directory;
  write_mesh(directory_ + "/surface.ply", mesh);
}

DracoCoder::~DracoCoder() {
  for (const char* file : {"/surface.ply", "/coded.drc", "/decoded.ply"}) unlink((directory_ + file).c_str());
  rmdir(directory_.c_str());
}

std::optional<DracoCoded> DracoCoder::code(int quantization_bits, int level) const {
  const std::string surface = directory_ + "/surface.ply", coded = directory_ + "/coded.drc",
                    decoded = directory_ + "/decoded.ply";
  DracoCoded result;
  result.encode_seconds = run_quietly({"draco_encoder", "-i", surface, "-o", coded, "-qp",
                                       std::to_string(quantization_bits), "-cl", std::to_string(level)});
  result.decode_seconds =
      result.encode_seconds < 0 ? -1 : run_quietly({"draco_decoder", "-i", coded, "-o", decoded});
  struct stat info {};
  if (result.decode_seconds < 0 || stat(coded.c_str(), &info) != 0) {
    std::printf("(draco at -qp %d -cl %d failed)\n", quantization_bits, level);
    return std::nullopt;
  }
  result.bytes = std::uint64_t(info.st_size);
  result.decoded = read_mesh(decoded);
  return result;
}

}  // namespace isowave::bench
