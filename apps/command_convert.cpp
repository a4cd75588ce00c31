// isowave convert: volumes to .isw files, one per input and isovalue, with a
// summary table; a failing input is reported and skipped.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <glob.h>
#include <mutex>
#include <set>
#include <thread>

#include "cli.h"
#include "commands.h"
#include "console_progress.h"
#include "job_report.h"
#include "isowave/pipeline/convert.h"
#include "isowave/pipeline/prepare.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/peak_memory.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/extract/volume_io.h"
#include "volume_options.h"
#ifdef ISOWAVE_WITH_MPI
#include "mpi_batch.h"
#endif

namespace isowave::commands {
namespace {

namespace fs = std::filesystem;

struct Job {
  std::string input;
  double iso = 0;
  std::string output;   // empty for an input with a problem
  std::string problem;  // see Input
};

struct JobOutcome {
  bool ok = false;
  std::string error;
  bool usage_error = false;  // failed with ErrorKind::InvalidArgument (what exit code 2 means)
  double load_seconds = 0;
  double load_peak_bytes = 0;    // core/peak_memory.h: restarted before the load, read after it
  std::size_t volume_bytes = 0;  // the samples as the input stores them
  ConvertResult result;
};

// An input argument's files. A directory or pattern that yields none is an
// input that failed (`problem`), reported in the summary like the others.
struct Input {
  std::string path;
  std::string problem;
};

// Files, directories (their volume files, sorted) and glob patterns.
std::vector<Input> expand_inputs(const std::vector<std::string>& arguments) {
  std::vector<Input> inputs;
  for (const std::string& argument : arguments) {
    std::error_code error;
    if (argument.rfind("builtin:", 0) == 0) {
      inputs.push_back({argument, {}});
    } else if (fs::is_directory(argument, error)) {
      std::vector<std::string> found;
      for (fs::directory_iterator it(argument, error), end; !error && it != end; it.increment(error))
        if (it->is_regular_file() && has_volume_extension(it->path().string())) found.push_back(it->path().string());
      std::sort(found.begin(), found.end());
      if (error) inputs.push_back({argument, "cannot list this directory (" + error.message() + ")"});
      else if (found.empty()) inputs.push_back({argument, "no volume files in this directory"});
      for (std::string& path : found) inputs.push_back({std::move(path), {}});
    } else if (argument.find_first_of("*?[") != std::string::npos && !fs::exists(argument, error)) {
      glob_t matches{};
      const bool any = glob(argument.c_str(), 0, nullptr, &matches) == 0 && matches.gl_pathc > 0;
      for (std::size_t i = 0; any && i < matches.gl_pathc; ++i) inputs.push_back({matches.gl_pathv[i], {}});
      globfree(&matches);
      if (!any) inputs.push_back({argument, "no file matches this pattern"});
    } else {
      inputs.push_back({argument, {}});  // a missing file is reported when its job runs
    }
  }
  return inputs;
}

// An input's name for its output file: a builtin field's name and size, a
// file's stem, and for a dataset of an HDF5 or NetCDF file (FILE.h5:/g/d,
// FILE.nc:var@T) the selection too, so that each dataset and time step of
// one file gets a file of its own ("run.nc:rho@3" gives run_rho_3).
std::string stem_of(const std::string& input) {
  const auto underscored = [](std::string name) {
    std::replace_if(name.begin(), name.end(), [](char c) { return c == ':' || c == '/' || c == '@'; }, '_');
    return name;
  };
  if (input.rfind("builtin:", 0) == 0) return underscored(input.substr(8));
  const SelectedPath selected = split_selection(input);
  if (!selected.selection.empty()) {
    std::string selection = underscored(selected.selection);
    selection.erase(0, selection.find_first_not_of('_'));
    const std::string stem = fs::path(selected.file).stem().string();
    return selection.empty() ? stem : stem + "_" + selection;
  }
  return fs::path(input).stem().string();
}

std::string iso_text(double iso) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", iso);
  return text;
}

cli::CommandSpec convert_spec() {
  std::vector<cli::OptionSpec> options = {
      {"iso", true, "isovalue(s), comma separated (default 0 for builtin: inputs)", "V[,V2,...]"},
      {"fit", true,
       "how the fine mesh is fitted: 'normal' (default: detail as one scalar along the normal, the fewest bits), "
       "'shrink-wrap' (the paper's) or 'parametrization' (the points of a MAPS map of the extracted surface, "
       "moved onto the trilinear isosurface)",
       "METHOD"},
      {"levels", true,
       "subdivision levels 1..6, or 'auto' (default): the fewest whose fitted surface lies within --max-error of "
       "the isosurface, with a fine mesh of at most 4 times the isosurface's vertices (16 with the "
       "parametrization) and 8 million",
       "L|auto"},
      {"max-error", true,
       "the decoded surface's error D against the isosurface, in cells: the levels are the fewest whose fit lies "
       "within 0.9 of it, and the file keeps the shortest prefix of its embedded stream within it (default: levels "
       "within the marching-cubes mesh's own distance from the isosurface, the whole stream)",
       "CELLS"},
      {"size", true, "the file's size limit in bytes: the embedded stream is cut to fit", "BYTES"},
      {"bits-per-vertex", true, "the size limit in bits per isosurface vertex", "B"},
      {"base-vertices", true, "base mesh vertex target", "N"},
      {"base-ratio", true,
       "base mesh vertex target as a fraction of the isosurface's vertices (default 0.0625; without --base-vertices "
       "and --base-ratio, and with --levels auto, the base mesh doubles, up to twice, while the fit leaves more than "
       "1% of the isosurface over 2 cells away)",
       "R"},
      {"allow-folded", false, "write the file even when most of the fit's faces fold (unusable)", ""},
      {"step", true, "the step of the stream's last bit plane in cells (default 0.01): the finest it goes", "CELLS"},
      {"output", true, "output file (one input and one isovalue)", "OUT.isw"},
      {"out-dir", true, "output directory: NAME.isw, or NAME_isoV.isw with several isovalues", "DIR"},
      {"jobs", true, "convert this many inputs at once (default 1)", "N"},
      {"force", false, "overwrite existing outputs", ""},
      {"quiet", false, "print nothing but errors", ""},
      {"json", false, "print machine-readable results as one JSON object", ""},
  };
  cli::add_extraction_options(options);
  cli::add_volume_options(options);
  return cli::CommandSpec{
      "convert",
      "INPUT... --iso V[,V2,...] [--levels L|auto] [--base-vertices N | --base-ratio R] [extract options]\n"
      "                (-o OUT.isw | --out-dir DIR) [--jobs N] [--force] [--quiet] [--json]",
      "Converts isosurfaces of volumes into wavelet files: extraction -> base mesh -> fit (--fit) ->\n"
      "wavelet analysis -> embedded coding. INPUT may be files, directories (all their\n"
      "volume files) or glob patterns. A failing input is reported and skipped; the exit code is non-zero if\n"
      "any failed. Outputs are written atomically and never overwritten without --force. Prints each\n"
      "input's value range on load ('isowave info VOLUME' shows it with a histogram, to choose V).",
      options,
      1,
      -1,
      "convert engine.nrrd --iso 100 -o engine.isw"};
}

ConvertOptions convert_options_from(const cli::Arguments& args) {
  if (args.has("base-vertices") && args.has("base-ratio"))
    throw Error(ErrorKind::InvalidArgument, "give at most one of --base-vertices and --base-ratio");
  ConvertOptions options;
  options.prepare.extract = cli::extraction_options(args);
  const std::string levels_text = args.get("levels", "auto");
  options.levels = levels_text == "auto" ? 0 : args.get_int("levels", 0, 1, 6);
  const std::string fit = args.get("fit", "normal");
  if (fit == "parametrization") options.fit = FitMethod::Parametrization;
  else if (fit == "normal") options.fit = FitMethod::Normal;
  else if (fit == "shrink-wrap") options.fit = FitMethod::ShrinkWrap;
  else
    throw Error(ErrorKind::InvalidArgument, "--fit must be 'shrink-wrap', 'parametrization' or 'normal', not '" + fit + "'");
  options.rate.max_error_cells = args.get_double("max-error", 0.0);
  if (!(options.rate.max_error_cells > 0) && args.has("max-error"))
    throw Error(ErrorKind::InvalidArgument, "--max-error must be a positive number of cells");
  options.max_error_cells = kLevelShareOfMaxError * options.rate.max_error_cells;
  const double size = args.get_double("size", 0.0);
  if (args.has("size") && !(size >= 1 && size <= 1e15 && size == std::floor(size)))
    throw Error(ErrorKind::InvalidArgument, "--size must be a whole number of bytes");
  options.rate.max_bytes = static_cast<std::uint64_t>(size);
  options.rate.bits_per_vertex = args.get_double("bits-per-vertex", 0.0);
  if (args.has("bits-per-vertex") && !(options.rate.bits_per_vertex > 0 && options.rate.bits_per_vertex < 1e6))
    throw Error(ErrorKind::InvalidArgument, "--bits-per-vertex must be a positive number");
  if (args.has("max-error") + args.has("size") + args.has("bits-per-vertex") > 1)
    throw Error(ErrorKind::InvalidArgument, "give at most one of --max-error, --size and --bits-per-vertex");
  options.base.vertices = static_cast<std::size_t>(args.get_int("base-vertices", 0, 4, 1 << 30));
  options.base.ratio = args.get_double("base-ratio", options.base.ratio);
  if (!(options.base.ratio > 0 && options.base.ratio <= 1))
    throw Error(ErrorKind::InvalidArgument, "--base-ratio must be in (0, 1]");
  options.base.growth =
      args.has("base-vertices") || args.has("base-ratio") ? BaseGrowth::Fixed : BaseGrowth::UntilCovered;
  options.step_cells = args.get_double("step", options.step_cells);
  if (!(options.step_cells > 0)) throw Error(ErrorKind::InvalidArgument, "--step must be positive");
  options.folded_fit = args.has("allow-folded") ? FoldedFit::Keep : FoldedFit::Refuse;
  return options;
}

// One job per input file and isovalue, with its output path; checks that
// the outputs can be written and that no two jobs write one file.
std::vector<Job> plan_jobs(const cli::Arguments& args) {
  std::vector<Job> jobs;
  for (const auto& [input, problem] : expand_inputs(args.positional())) {
    if (!problem.empty()) {
      jobs.push_back({input, std::nan(""), {}, problem});
      continue;
    }
    std::vector<double> isovalues;
    if (args.has("iso")) isovalues = args.get_double_list("iso", "", -HUGE_VAL, HUGE_VAL);
    else if (cli::is_builtin_volume(input)) isovalues = {0.0};
    else throw Error(ErrorKind::InvalidArgument, "missing --iso (needed for " + input + ")");
    for (double iso : isovalues) {
      Job job{input, iso, {}, {}};
      if (args.has("output")) {
        job.output = args.get("output");
      } else {
        const std::string name = stem_of(input) + (isovalues.size() > 1 ? "_iso" + iso_text(iso) : "") + ".isw";
        job.output = (fs::path(args.get("out-dir")) / name).string();
      }
      jobs.push_back(job);
    }
  }
  if (args.has("output") && jobs.size() != 1)
    throw Error(ErrorKind::InvalidArgument, "-o takes one input and one isovalue; use --out-dir for batches");
  if (args.has("output")) {
    const fs::path parent = fs::path(args.get("output")).parent_path();
    if (!parent.empty() && !fs::is_directory(parent))
      throw Error(ErrorKind::Io, args.get("output") + ": the directory " + parent.string() + " does not exist");
    if (fs::is_directory(args.get("output"))) throw Error(ErrorKind::Io, args.get("output") + ": is a directory");
  }
  // Two jobs writing one file would lose one of them (same stems in a
  // directory, isovalues equal in their file names).
  for (std::size_t j = 0; j < jobs.size(); ++j)
    for (std::size_t k = 0; k < j && jobs[j].problem.empty(); ++k)
      if (jobs[k].problem.empty() && jobs[k].output == jobs[j].output)
        throw Error(ErrorKind::InvalidArgument, jobs[k].input + " and " + jobs[j].input + " (iso " + iso_text(jobs[k].iso) +
                                                    ", " + iso_text(jobs[j].iso) + ") would both write " +
                                                    jobs[j].output + "; convert them in separate runs");
  if (args.has("out-dir")) {
    std::error_code ignored;
    fs::create_directories(args.get("out-dir"), ignored);
    if (!fs::is_directory(args.get("out-dir")))
      throw Error(ErrorKind::Io, args.get("out-dir") + ": cannot create the output directory");
  }
  return jobs;
}

// How the batch reports as it runs.
struct RunSettings {
  VolumeReadOptions read;
  ConvertOptions convert;
  cli::ProgressMode mode = cli::ProgressMode::Quiet;
  bool force = false, warn = true, label_iso = false;
  cli::LoadReport load_report = cli::LoadReport::RangeAndWarnings;  // the value range printed on load
};

// Loads, converts and writes one job; throws what goes wrong.
void run_job(const Job& job, const RunSettings& settings, JobOutcome& outcome, cli::ConsoleProgress& progress) {
  if (!job.problem.empty()) throw Error(ErrorKind::Io, job.input + ": " + job.problem);
  if (!settings.force && fs::exists(job.output))
    throw Error(ErrorKind::Io, job.output + ": already exists (use --force to overwrite)");
  const auto start = std::chrono::steady_clock::now();
  reset_peak_memory();
  Volume volume = load_volume(job.input, settings.read, progress);
  outcome.load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  outcome.load_peak_bytes = peak_memory_bytes();
  cli::report_loaded_volume("convert", job.input, volume, settings.load_report, &progress);
  outcome.volume_bytes = volume.sample_count() * scalar_type_size(volume.source_type);
  ConvertOptions options = settings.convert;
  options.prepare.extract.iso = job.iso;
  outcome.result = convert_volume(std::move(volume), job.input, options, progress);
  write_isw(job.output, outcome.result.bytes, settings.force);
  outcome.ok = true;
}

// The batch's time left, estimated as the wall-clock time per finished job
// so far times the jobs not finished (with --jobs N the time per job is
// already shared among the threads).
class TimeLeft {
 public:
  explicit TimeLeft(std::size_t jobs) : jobs_(jobs) {}
  // Returns the jobs finished so far, this one included.
  std::size_t job_finished() { return ++finished_; }
  std::size_t finished() const { return finished_; }
  // "about 40 s left" ("12 min", "1.5 h") with `finished` jobs done; empty
  // before the first job has finished and after the last.
  std::string text(std::size_t finished) const {
    if (finished == 0 || finished >= jobs_) return {};
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double left = elapsed / double(finished) * double(jobs_ - finished);
    char text[48];
    if (left < 90) std::snprintf(text, sizeof text, "about %.0f s left", std::ceil(left));
    else if (left < 5400) std::snprintf(text, sizeof text, "about %.0f min left", left / 60);
    else std::snprintf(text, sizeof text, "about %.1f h left", left / 3600);
    return text;
  }

 private:
  const std::size_t jobs_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::atomic<std::size_t> finished_{0};
};

// Runs one job under its progress line and reports how it ended: "wrote
// OUT (bytes, s)" or its error, once (a line of its own when quiet); when
// the lines are written whole, the batch's time left after it.
void run_and_report(const Job& job, const RunSettings& settings, JobOutcome& outcome, cli::ConsoleProgress& progress,
                    TimeLeft& time_left, std::mutex& print_mutex) {
  std::string ending;
  try {
    run_job(job, settings, outcome, progress);
    char done[64];
    std::snprintf(done, sizeof done, " (%zu bytes, %.1f s)", outcome.result.bytes.size(),
                  outcome.load_seconds + outcome.result.seconds.total());
    ending = "wrote " + job.output + done;
  } catch (const std::exception& error) {
    outcome.error = error.what();
    const auto* isowave_error = dynamic_cast<const Error*>(&error);
    outcome.usage_error = isowave_error && isowave_error->kind() == ErrorKind::InvalidArgument;
    // Most errors from reading name the input already.
    if (outcome.error.rfind(job.input + ":", 0) != 0) outcome.error = job.input + ": " + outcome.error;
    ending = "FAILED: " + outcome.error + " (skipped)";
  }
  // Under the lock, so that the lines come in the order the jobs finished.
  std::lock_guard<std::mutex> lock(print_mutex);
  const std::size_t finished = time_left.job_finished();
  const std::string left = settings.mode == cli::ProgressMode::BufferedLine ? time_left.text(finished) : std::string();
  if (!outcome.ok && settings.mode == cli::ProgressMode::Quiet)
    std::fprintf(stderr, "isowave convert: %s (skipped)\n", outcome.error.c_str());
  progress.finish(ending + (left.empty() ? "" : "; " + left));
  if (outcome.ok && settings.warn)
    for (const std::string& warning : outcome.result.warnings)
      std::fprintf(stderr, "isowave convert: warning: %s: %s\n", job.input.c_str(), warning.c_str());
}

// Runs the jobs `order` names (indices into `jobs`, in that order) on
// `threads` threads; each reports one line ("k of N" in its label, k and N
// of the whole batch), a failure with its error, once. With several jobs a
// line tells the time left of the jobs in `order`: before its job's stages
// when it is written as they run, after its job when written whole (jobs
// side by side). Returns the outcomes in the order of `order`.
std::vector<JobOutcome> run_jobs(const std::vector<Job>& jobs, const std::vector<std::size_t>& order,
                                 const RunSettings& settings, int threads) {
  std::vector<JobOutcome> outcomes(order.size());
  std::atomic<std::size_t> next{0};
  std::mutex print_mutex;
  TimeLeft time_left(order.size());
  const auto worker = [&] {
    for (std::size_t i = next++; i < order.size(); i = next++) {
      const std::size_t j = order[i];
      const Job& job = jobs[j];
      const std::string label = "[" + std::to_string(j + 1) + "/" + std::to_string(jobs.size()) + "] " +
                                stem_of(job.input) + (settings.label_iso ? " @" + iso_text(job.iso) : "");
      cli::ConsoleProgress progress(label, settings.mode);
      const std::string left = time_left.text(time_left.finished());
      if (settings.mode != cli::ProgressMode::BufferedLine && !left.empty()) progress.note(left);
      run_and_report(job, settings, outcomes[i], progress, time_left, print_mutex);
      release_freed_memory();  // what this input left must not stay under the next one
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min<int>(threads, static_cast<int>(order.size())); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  return outcomes;
}

double rmse_percent(const ConvertResult& r, double value) { return 100.0 * value / r.cell_size; }

// printf onto the end of `text`.
__attribute__((format(printf, 2, 3))) void appendf(std::string& text, const char* format, ...) {
  std::va_list arguments;
  va_start(arguments, format);
  std::va_list again;
  va_copy(again, arguments);
  const int length = std::vsnprintf(nullptr, 0, format, arguments);
  va_end(arguments);
  const std::size_t size = text.size();
  text.resize(size + static_cast<std::size_t>(length) + 1);
  std::vsnprintf(text.data() + size, static_cast<std::size_t>(length) + 1, format, again);
  va_end(again);
  text.resize(size + static_cast<std::size_t>(length));
}

// The batch's totals: inputs (volume files, builtin fields, or arguments
// that gave none), jobs (inputs times isovalues), failed jobs, bytes in (the
// samples, as their inputs store them, of each volume converted at least
// once; counted once however many isovalues) and out (the files written),
// their ratio and the wall-clock time.
struct Totals {
  std::size_t inputs = 0, jobs = 0, failed = 0, bytes_in = 0, bytes_out = 0;
  double seconds = 0;
  double ratio() const { return bytes_out ? double(bytes_in) / double(bytes_out) : 0.0; }
};

Totals totals_of(const std::vector<Job>& jobs, const std::vector<cli::JobReport>& reports, double seconds) {
  Totals t;
  t.jobs = jobs.size();
  t.seconds = seconds;
  std::set<std::string> inputs, converted;
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    inputs.insert(jobs[j].input);
    if (!reports[j].ok) {
      ++t.failed;
      continue;
    }
    t.bytes_out += reports[j].bytes_out;
    if (converted.insert(jobs[j].input).second) t.bytes_in += reports[j].volume_bytes;
  }
  t.inputs = inputs.size();
  return t;
}

// The plane stream's estimated bits by what they code (IswPlaneBits), and the tangential share.
void render_json_plane_bits(std::string& out, const IswPlaneBits& b) {
  if (b.total() <= 0) return;
  appendf(out,
          "\"tangential_bit_share\": %.6g, \"plane_bits\": {\"base\": %.0f, \"normal_significance\": %.0f, "
          "\"normal_sign\": %.0f, \"normal_refinement\": %.0f, \"tangential_significance\": %.0f, "
          "\"tangential_sign\": %.0f, \"tangential_refinement\": %.0f, \"joint_significance\": %.0f, "
          "\"descendants\": %.0f}, ",
          b.tangential_share(), b.base, b.normal_significance, b.normal_sign, b.normal_refinement,
          b.tangential_significance, b.tangential_sign, b.tangential_refinement, b.joint_significance, b.descendants);
}

// Each stage's peak memory, and per isosurface vertex its time and peak:
// the profile issue #51 starts from.
void render_json_profile(std::string& out, const JobOutcome& o) {
  const ConvertResult& r = o.result;
  const ConvertPeaks& p = r.peak_bytes;
  using Figures = std::vector<std::pair<const char*, double>>;
  const Figures peaks{{"load", o.load_peak_bytes}, {"extract", p.extract},   {"simplify", p.simplify},
                      {"fit", p.fit},              {"analysis", p.analysis}, {"encode", p.encode},
                      {"evaluate", p.evaluate}};
  const Figures seconds{{"load", o.load_seconds},         {"extract", r.seconds.extract},
                        {"simplify", r.seconds.simplify}, {"distance", r.seconds.distance},
                        {"fit", r.seconds.fit},           {"analysis", r.seconds.analysis},
                        {"encode", r.seconds.encode},     {"evaluate", r.seconds.evaluate}};
  const auto object = [&](const char* key, const Figures& figures, double scale, const char* format) {
    appendf(out, "\"%s\": {", key);
    for (std::size_t k = 0; k < figures.size(); ++k) {
      appendf(out, "%s\"%s\": ", k ? ", " : "", figures[k].first);
      appendf(out, format, figures[k].second * scale);
    }
    out += "}";
  };
  const double per_vertex = 1.0 / std::max<double>(1.0, static_cast<double>(r.extracted_vertices));
  object("peak_megabytes", peaks, 1.0 / 1048576.0, "%.1f");
  out += ", \"per_isosurface_vertex\": {";
  object("microseconds", seconds, 1e6 * per_vertex, "%.4g");
  out += ", ";
  object("peak_bytes", peaks, per_vertex, "%.4g");
  out += "}, ";
}

void render_json_result(std::string& out, const JobOutcome& o) {
  const ConvertResult& r = o.result;
  appendf(out,
          ", \"bytes\": %zu, \"volume_bytes\": %zu, \"cell_size\": %.9g, \"extracted_vertices\": %zu, "
          "\"base_vertices\": %zu, \"fine_vertices\": %zu, \"levels\": %d, \"seconds\": {\"load\": %.3f, "
          "\"extract\": %.3f, \"simplify\": %.3f, \"distance\": %.3f, \"fit\": %.3f, \"analysis\": %.3f, "
          "\"encode\": %.3f, \"evaluate\": %.3f}, \"fit_isosurface_rms_cells\": %.6g, "
          "\"fit_isosurface_max_cells\": %.6g, \"fit_points_beyond_one_cell\": %zu, "
          "\"isosurface_uncovered_share\": %.6g, \"fit_folded_share\": %.6g, \"base_attempts\": %d, ",
          r.bytes.size(), o.volume_bytes, r.cell_size, r.extracted_vertices, r.base_vertices, r.fine_vertices,
          r.levels, o.load_seconds, r.seconds.extract, r.seconds.simplify, r.seconds.distance, r.seconds.fit,
          r.seconds.analysis, r.seconds.encode, r.seconds.evaluate, r.fit_isosurface.rms, r.fit_isosurface.max,
          r.fit_isosurface.far, r.uncovered_share, r.folded_share(), r.base_attempts);
  render_json_profile(out, o);
  if (r.max_error_cells > 0) appendf(out, "\"max_error_percent_cell\": %.6g, ", 100.0 * r.max_error_cells);
  if (r.extraction.topology_tolerance > 0)
    appendf(out, "\"topology_tolerance\": %s, ", cli::topology_tolerance_json(r.extraction).c_str());
  out += "\"fit_levels\": [";
  for (std::size_t k = 0; k < r.level_reports.size(); ++k) {
    const LevelReport& l = r.level_reports[k];
    appendf(out,
            "%s{\"levels\": %d, \"fine_vertices\": %zu, \"d_percent_cell\": %.6g, "
            "\"forward_rms_percent_cell\": %.6g, \"backward_rms_percent_cell\": %.6g, \"folded_share\": %.6g, "
            "\"stretch_min\": %.6g, \"stretch_median\": %.6g, \"stretch_max\": %.6g, \"seconds\": %.3f}",
            k ? ", " : "", l.levels, l.fine_vertices, 100.0 * l.d_cells(), 100.0 * l.forward_rms_cells,
            100.0 * l.backward_rms_cells, l.folded_share, l.stretch_min, l.stretch_median, l.stretch_max, l.seconds);
  }
  out += "], ";
  if (r.parametrization.fine_vertices > 0)
    appendf(out, "\"fit_fallback_points\": %zu, ", r.parametrization.fallback_points);
  for (std::size_t k = 0; k < r.normal_share.size(); ++k)
    appendf(out, "%s%.6g%s", k ? ", " : "\"normal_energy_share\": [", r.normal_share[k],
            k + 1 == r.normal_share.size() ? "], " : "");
  render_json_plane_bits(out, r.plane_bits);
  for (std::size_t k = 0; k < r.normal_levels.size(); ++k) {
    const NormalFitLevelStatistics& l = r.normal_levels[k];
    appendf(out,
            "%s{\"level\": %d, \"vertices\": %zu, \"coefficients\": %zu, \"non_normal\": %zu, \"unpierced\": %zu, "
            "\"rms_cells\": %.6g, \"max_cells\": %.6g, \"seconds\": %.3f}%s",
            k ? ", " : "\"normal_fit_levels\": [", l.level, l.vertices, l.coefficients, l.non_normal, l.unpierced,
            l.rms_cells, l.max_cells, l.seconds, k + 1 == r.normal_levels.size() ? "], " : "");
  }
  for (std::size_t k = 0; k < r.warnings.size(); ++k)
    appendf(out, "%s%s", k ? ", " : "\"warnings\": [", cli::json_string(r.warnings[k]).c_str());
  appendf(out, "%s\"rows\": [", r.warnings.empty() ? "" : "], ");
  for (std::size_t k = 0; k < r.summary.size(); ++k) {
    const RateDistortionRow& row = r.summary[k];
    appendf(out,
            "%s{\"percent\": %.4f, \"coefficients\": %zu, \"rmse_percent_cell\": %.6g, \"max_percent_cell\": "
            "%.6g, \"d_percent_cell\": %.6g, \"bytes\": %llu, \"base\": %s}",
            k ? ", " : "", row.percent, row.kept, rmse_percent(r, row.rms), rmse_percent(r, row.max),
            100.0 * r.summary_surface_error[k], static_cast<unsigned long long>(row.bytes),
            row.is_base ? "true" : "false");
  }
  appendf(out, "], \"quantization_rmse_percent_cell\": %.6g, \"quantization_max_percent_cell\": %.6g}",
          rmse_percent(r, r.quantization.rms), rmse_percent(r, r.quantization.max));
}

// The job's object in the --json results.
std::string render_json(const Job& job, const JobOutcome& o) {
  std::string out;
  if (job.problem.empty())
    appendf(out, "{\"input\": %s, \"iso\": %.10g, \"output\": %s, \"ok\": %s", cli::json_string(job.input).c_str(),
            job.iso, cli::json_string(job.output).c_str(), o.ok ? "true" : "false");
  else
    appendf(out, "{\"input\": %s, \"iso\": null, \"output\": null, \"ok\": false", cli::json_string(job.input).c_str());
  if (o.ok) render_json_result(out, o);
  else appendf(out, ", \"error\": %s}", cli::json_string(o.error).c_str());
  return out;
}

void print_json(const std::vector<cli::JobReport>& reports, const Totals& totals) {
  std::printf("{\"inputs\": %zu, \"jobs\": %zu, \"converted\": %zu, \"failed\": %zu, \"volume_bytes\": %zu, "
              "\"bytes\": %zu, \"ratio\": %.6g, \"seconds\": %.3f, \"results\": [",
              totals.inputs, totals.jobs, totals.jobs - totals.failed, totals.failed, totals.bytes_in,
              totals.bytes_out, totals.ratio(), totals.seconds);
  for (std::size_t j = 0; j < reports.size(); ++j) std::printf("%s%s", j ? ", " : "", reports[j].json.c_str());
  std::printf("]}\n");
}

// One line per level the fit tried: D both ways, folds and stretch.
void render_level_reports(std::string& out, const ConvertResult& r) {
  for (const LevelReport& l : r.level_reports)
    appendf(out,
            "%-28s level %d (%zu fine vertices): D %.3g%% cell (fitted -> isosurface %.3g, isosurface -> "
            "fitted %.3g)%s; %.2f%% of the fine faces folded; face areas %.2g..%.2g of their mean (median "
            "%.2g); %.2f s\n",
            "", l.levels, l.fine_vertices, 100.0 * l.d_cells(), 100.0 * l.forward_rms_cells,
            100.0 * l.backward_rms_cells,
            r.max_error_cells > 0 ? (l.d_cells() <= r.max_error_cells ? ", within the bound" : ", over the bound")
                                  : "",
            100.0 * l.folded_share, l.stretch_min, l.stretch_max, l.stretch_median, l.seconds);
  if (r.max_error_cells > 0)
    appendf(out, "%-28s levels by error: the bound on D is %.3g%% cell\n", "", 100.0 * r.max_error_cells);
}

void render_table_rows(std::string& out, const std::string& output, const JobOutcome& o) {
  const ConvertResult& r = o.result;
  std::string errors;
  const RateDistortionRow* previous = nullptr;
  for (const RateDistortionRow& row : r.summary) {
    // Percentages below the base mesh's share all give the base mesh: one entry.
    if (previous && previous->kept == row.kept) continue;
    previous = &row;
    const double d = r.summary_surface_error[static_cast<std::size_t>(&row - r.summary.data())];
    appendf(errors, "%s%.4g%%: %.3g (D %.3g)", errors.empty() ? "" : "  ", row.percent, rmse_percent(r, row.rms),
            100.0 * d);
  }
  appendf(out, "%-28s %10zu %9zu %9zu %10zu %3d %8.1f  %s\n", output.c_str(), r.bytes.size(), r.extracted_vertices,
          r.base_vertices, r.fine_vertices, r.levels, o.load_seconds + r.seconds.total(), errors.c_str());
  appendf(out,
          "%-28s stages: load %.2f, extract %.2f, simplify %.2f, distance %.2f, fit %.2f, analysis %.2f, "
          "encode %.2f, evaluate %.2f s; %.2f bits per fine vertex\n",
          "", o.load_seconds, r.seconds.extract, r.seconds.simplify, r.seconds.distance, r.seconds.fit,
          r.seconds.analysis, r.seconds.encode, r.seconds.evaluate,
          8.0 * static_cast<double>(r.bytes.size()) / static_cast<double>(r.fine_vertices));
  appendf(out,
          "%-28s fit: the fine control points lie %.3g cell RMS (max %.3g) off the isosurface, %zu of them "
          "more than a cell; %.2f%% of the isosurface lies more than %g cells from all of them; %.2f%% of the "
          "fine faces are folded against the field gradient\n",
          "", r.fit_isosurface.rms, r.fit_isosurface.max, r.fit_isosurface.far, 100.0 * r.uncovered_share,
          kUncoveredCells, 100.0 * r.folded_share());
  appendf(out, "%-28s %s\n", "", describe_quantization_error(r.quantization, r.cell_size).c_str());
  if (r.extraction.topology_tolerance > 0)
    appendf(out, "%-28s %s; genus %lld -> %lld, components %zu -> %zu\n", "",
            cli::topology_tolerance_line(r.extraction).c_str(), static_cast<long long>(r.extraction.before.genus),
            static_cast<long long>(r.extraction.after.genus), r.extraction.before.components,
            r.extraction.after.components);
  if (r.base_attempts > 1)
    appendf(out, "%-28s the base mesh grew from %zu to %zu vertices (%d tries) to cover the isosurface\n", "",
            r.first_base_vertices, r.base_vertices, r.base_attempts);
  render_level_reports(out, r);
  if (r.parametrization.fine_vertices > 0)
    appendf(out, "%-28s parametrization: %zu points located by the nearest input triangle\n", "",
            r.parametrization.fallback_points);
  if (!r.normal_share.empty()) {
    std::string shares;
    for (std::size_t k = 0; k < r.normal_share.size(); ++k)
      appendf(shares, "%s level %zu %.1f%%", k ? "," : "", k + 1, 100.0 * r.normal_share[k]);
    appendf(out, "%-28s detail energy along the local frames' normals:%s\n", "", shares.c_str());
  }
  if (const IswPlaneBits& b = r.plane_bits; b.total() > 0)
    appendf(out,
            "%-28s plane stream (estimated bits): tangential %.1f%%, normal %.1f%%, normal and tangential together "
            "%.1f%%, tree %.1f%%, base points %.1f%%\n",
            "", 100 * b.tangential_share(), 100 * b.normal() / b.total(), 100 * b.joint_significance / b.total(),
            100 * b.descendants / b.total(), 100 * b.base / b.total());
  for (const NormalFitLevelStatistics& l : r.normal_levels)
    appendf(out,
            "%-28s normal fit level %d: %zu points %.3g cell RMS (max %.3g) off their targets, %zu without one; "
            "%zu of %zu coefficients non-normal; %.2f s\n",
            "", l.level, l.vertices, l.rms_cells, l.max_cells, l.unpierced, l.non_normal, l.coefficients, l.seconds);
}

// The job's summary as data: its numbers and its table rows and JSON object.
cli::JobReport report_of(const Job& job, const JobOutcome& o) {
  cli::JobReport report;
  report.ok = o.ok;
  report.usage_error = o.usage_error;
  report.error = o.error;
  report.volume_bytes = o.volume_bytes;
  report.bytes_out = o.ok ? o.result.bytes.size() : 0;
  if (o.ok) render_table_rows(report.table_rows, job.output, o);
  else appendf(report.table_rows, "%-28s FAILED (the error is above)\n", (job.problem.empty() ? job.output : job.input).c_str());
  report.json = render_json(job, o);
  return report;
}

// The reports of the jobs `order` names, from their outcomes (in that order).
std::vector<cli::JobReport> reports_of(const std::vector<Job>& jobs, const std::vector<std::size_t>& order,
                                       const std::vector<JobOutcome>& outcomes) {
  std::vector<cli::JobReport> reports;
  reports.reserve(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) reports.push_back(report_of(jobs[order[i]], outcomes[i]));
  return reports;
}

// The summary table; a failed input's error was printed as it happened.
void print_table(const std::vector<cli::JobReport>& reports, const Totals& totals) {
  std::printf("\n%-28s %10s %9s %9s %10s %3s %8s  %s\n", "output", "bytes", "isosurf.", "base", "fine", "L",
              "seconds",
              "RMSE [% cell] against the full decode (D: against the isosurface) at percent kept (base last)");
  for (const cli::JobReport& report : reports) std::fputs(report.table_rows.c_str(), stdout);
  std::printf("\n%zu input%s", totals.inputs, totals.inputs == 1 ? "" : "s");
  if (totals.jobs != totals.inputs) std::printf(", %zu jobs", totals.jobs);
  std::printf(", %zu failed", totals.failed);
  if (totals.bytes_out > 0)
    std::printf("; volumes %.3g MB in, %.3g MB out (%.1f : 1)", 1e-6 * double(totals.bytes_in),
                1e-6 * double(totals.bytes_out), totals.ratio());
  std::printf("; %.1f s\n", totals.seconds);
}

// 0 when every job succeeded; 2 when every failure was a usage error (as the
// other commands exit for the same input), else 1.
int exit_code(const std::vector<cli::JobReport>& reports) {
  bool failed = false, other_failure = false;
  for (const cli::JobReport& r : reports) {
    failed |= !r.ok;
    other_failure |= !r.ok && !r.usage_error;
  }
  return !failed ? 0 : other_failure ? 1 : 2;
}

enum class Summary { Table, Json, Nothing };

// Prints the batch's summary of every job's report (in job order) and
// returns the exit code.
int summarize(const std::vector<Job>& jobs, const std::vector<cli::JobReport>& reports,
              std::chrono::steady_clock::time_point start, Summary summary) {
  const Totals totals =
      totals_of(jobs, reports, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (summary == Summary::Json) print_json(reports, totals);
  else if (summary == Summary::Table) print_table(reports, totals);
  return exit_code(reports);
}

#ifdef ISOWAVE_WITH_MPI
// The job's estimated cost for assigning it to a rank: its input file's
// size, or a builtin field's samples times 4 (0 when it cannot be known).
double job_cost(const Job& job) {
  if (cli::is_builtin_volume(job.input)) {
    const std::size_t colon = job.input.find(':', std::strlen("builtin:"));
    const double n = colon == std::string::npos ? 128.0 : std::atof(job.input.c_str() + colon + 1);
    return 4.0 * n * n * n;
  }
  std::error_code error;
  const std::uintmax_t size = fs::file_size(job.input, error);
  return error ? 0.0 : double(size);
}

// The batch spread over the ranks of `mpi` (apps/mpi_batch.h); every rank
// returns the exit code, rank 0 prints the summary.
int convert_on_ranks(const cli::MpiSession& mpi, const std::vector<Job>& jobs, const RunSettings& settings,
                     int threads, Summary summary) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> costs;
  for (const Job& job : jobs) costs.push_back(job_cost(job));
  const std::vector<cli::JobReport> reports =
      cli::run_on_ranks(mpi, costs, [&](const std::vector<std::size_t>& mine) {
        return reports_of(jobs, mine, run_jobs(jobs, mine, settings, threads));
      });
  return mpi.broadcast_from_root(mpi.rank() == 0 ? summarize(jobs, reports, start, summary) : 0);
}
#endif

}  // namespace

int convert(const Args& raw) {
  const cli::CommandSpec spec = convert_spec();
  const cli::Arguments args(spec, raw);
  if (cli::print_help_if_requested(spec, args)) return 0;
  if (args.has("output") == args.has("out-dir"))
    throw Error(ErrorKind::InvalidArgument, "give exactly one of -o OUT.isw and --out-dir DIR");
  if (args.has("output") && !cli::has_extension(args.get("output"), ".isw"))
    throw Error(ErrorKind::InvalidArgument, args.get("output") + ": convert writes .isw files (name the output OUT.isw)");
  RunSettings settings;
  settings.read = cli::volume_read_options(args);
  settings.convert = convert_options_from(args);
  const int threads = args.get_int("jobs", 1, 1, 64);
  settings.force = args.has("force");
  const bool json = args.has("json");
  // --json keeps stdout for the JSON object; warnings still go to stderr.
  const bool quiet = args.has("quiet") || json;
  settings.warn = !args.has("quiet");
  settings.label_iso = args.has("iso");
  settings.load_report = !settings.warn ? cli::LoadReport::Nothing
                                        : (quiet ? cli::LoadReport::WarningsOnly : cli::LoadReport::RangeAndWarnings);
  const std::vector<Job> jobs = plan_jobs(args);
  const Summary summary = json ? Summary::Json : quiet ? Summary::Nothing : Summary::Table;

#ifdef ISOWAVE_WITH_MPI
  if (cli::launched_by_mpi()) {
    const cli::MpiSession mpi;
    if (mpi.ranks() > 1) {
      // Ranks side by side write their lines whole.
      settings.mode = quiet ? cli::ProgressMode::Quiet : cli::ProgressMode::BufferedLine;
      return convert_on_ranks(mpi, jobs, settings, threads, summary);
    }
  }
#endif
  // Runs side by side write their lines whole.
  settings.mode = quiet ? cli::ProgressMode::Quiet
                        : (threads > 1 && jobs.size() > 1 ? cli::ProgressMode::BufferedLine
                                                          : cli::default_progress_mode(false));
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::size_t> order(jobs.size());
  for (std::size_t j = 0; j < jobs.size(); ++j) order[j] = j;
  return summarize(jobs, reports_of(jobs, order, run_jobs(jobs, order, settings, threads)), start, summary);
}

}  // namespace isowave::commands
