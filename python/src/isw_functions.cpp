// convert, decode and stats: volumes to .isw files and back, as the CLI's
// commands of the same names do it, with the results as Python objects.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "arrays.h"
#include "functions.h"
#include "options.h"
#include "isowave/codec/importance.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/region.h"
#include "isowave/codec/view.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/pipeline/convert.h"
#include "isowave/pipeline/prepare.h"
#include "isowave/transform/limit_surface.h"

namespace isowave::python {
namespace {

namespace fs = std::filesystem;

bool is_path(const py::object& value) { return py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__"); }

// The volume convert() works on: a file read with the reader's keywords, or
// a field with spacing, origin and source (its name in the file's metadata).
struct ConvertInput {
  py::object field = py::none();  // None for a file
  std::string source;
  VolumeReadOptions read;  // a field's spacing and origin here too
  Volume volume;            // once loaded
  std::size_t volume_bytes = 0;  // the samples as the input stored them
  double load_seconds = 0;
};

// Takes the input's keywords out of `kwargs`; nothing is read yet.
ConvertInput convert_input(const py::object& field_or_path, py::dict& kwargs) {
  ConvertInput input;
  if (is_path(field_or_path)) {
    input.source = py::str(py::module_::import("os").attr("fspath")(field_or_path)).cast<std::string>();
    input.read = take_read_options(kwargs);
    return input;
  }
  input.field = py::array::ensure(field_or_path);
  if (!input.field) throw py::type_error("convert() takes a path or an array as its first argument");
  if (kwargs.contains("spacing")) input.read.spacing = vec3_from(kwargs.attr("pop")("spacing"), "spacing");
  if (kwargs.contains("origin")) input.read.origin = vec3_from(kwargs.attr("pop")("origin"), "origin");
  input.source = kwargs.contains("source") ? py::str(kwargs.attr("pop")("source")).cast<std::string>() : "numpy array";
  return input;
}

void load(ConvertInput& input) {
  if (!input.field.is_none()) {
    const auto field = py::reinterpret_borrow<py::array>(input.field);
    input.volume = volume_from_field(field, input.read.spacing.value_or(Vec3{1, 1, 1}),
                                     input.read.origin.value_or(Vec3{0, 0, 0}));
    input.volume_bytes = static_cast<std::size_t>(field.nbytes());
    return;
  }
  py::gil_scoped_release release;
  const auto start = std::chrono::steady_clock::now();
  input.volume = load_volume(input.source, input.read);
  input.load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  input.volume_bytes = input.volume.sample_count() * scalar_type_size(input.volume.source_type);
}

// What the CLI checks before the work: an .isw name, and no file replaced
// without force.
void check_output(const std::string& path, bool force) {
  if (fs::path(path).extension() != ".isw")
    throw Error(ErrorKind::InvalidArgument, path + ": convert writes .isw files (name the output OUT.isw)");
  if (!force && fs::exists(path)) throw Error(ErrorKind::Io, path + ": already exists (use force=True to overwrite)");
}

// The figures `isowave convert --json` prints per result, with the same keys.
py::dict summary_of(const ConvertResult& r, const std::string& path, const ConvertInput& input) {
  const auto percent_cell = [&](double world) { return 100.0 * world / r.cell_size; };
  py::dict s;
  s["output"] = path;
  s["bytes"] = r.bytes.size();
  s["volume_bytes"] = input.volume_bytes;
  s["cell_size"] = r.cell_size;
  s["extracted_vertices"] = r.extracted_vertices;
  s["base_vertices"] = r.base_vertices;
  s["fine_vertices"] = r.fine_vertices;
  s["levels"] = r.levels;
  s["seconds"] = py::dict(py::arg("load") = input.load_seconds, py::arg("extract") = r.seconds.extract,
                          py::arg("simplify") = r.seconds.simplify, py::arg("distance") = r.seconds.distance,
                          py::arg("fit") = r.seconds.fit, py::arg("analysis") = r.seconds.analysis,
                          py::arg("encode") = r.seconds.encode, py::arg("evaluate") = r.seconds.evaluate);
  const ConvertPeaks& p = r.peak_bytes;
  const double megabyte = 1.0 / 1048576.0;
  s["peak_megabytes"] = py::dict(py::arg("extract") = p.extract * megabyte, py::arg("simplify") = p.simplify * megabyte,
                                 py::arg("fit") = p.fit * megabyte, py::arg("analysis") = p.analysis * megabyte,
                                 py::arg("encode") = p.encode * megabyte, py::arg("evaluate") = p.evaluate * megabyte);
  s["fit_isosurface_rms_cells"] = r.fit_isosurface.rms;
  s["fit_isosurface_max_cells"] = r.fit_isosurface.max;
  s["fit_points_beyond_one_cell"] = r.fit_isosurface.far;
  s["isosurface_uncovered_share"] = r.uncovered_share;
  s["fit_folded_share"] = r.folded_share();
  s["base_attempts"] = r.base_attempts;
  py::list rows;
  for (std::size_t k = 0; k < r.summary.size(); ++k) {
    const RateDistortionRow& row = r.summary[k];
    rows.append(py::dict(py::arg("percent") = row.percent, py::arg("coefficients") = row.kept,
                         py::arg("rmse_percent_cell") = percent_cell(row.rms),
                         py::arg("max_percent_cell") = percent_cell(row.max),
                         py::arg("d_percent_cell") = 100.0 * r.summary_surface_error[k], py::arg("bytes") = row.bytes,
                         py::arg("base") = row.is_base));
  }
  s["rows"] = rows;
  py::list levels;
  for (const LevelReport& l : r.level_reports)
    levels.append(py::dict(py::arg("levels") = l.levels, py::arg("fine_vertices") = l.fine_vertices,
                           py::arg("d_percent_cell") = 100.0 * l.d_cells(),
                           py::arg("forward_rms_percent_cell") = 100.0 * l.forward_rms_cells,
                           py::arg("backward_rms_percent_cell") = 100.0 * l.backward_rms_cells,
                           py::arg("folded_share") = l.folded_share, py::arg("seconds") = l.seconds));
  s["fit_levels"] = levels;
  s["quantization_rmse_percent_cell"] = percent_cell(r.quantization.rms);
  s["quantization_max_percent_cell"] = percent_cell(r.quantization.max);
  s["warnings"] = py::cast(r.warnings);
  return s;
}

// The cell edge the file records, when it is a positive finite number (a
// damaged or hostile file's is unknown: errors then stay in world units).
double recorded_cell_size(const IswMetadata& metadata) {
  const double cell = metadata.number("cell_size", 1.0);
  const bool known = metadata.values.count("cell_size") != 0 && std::isfinite(cell) && cell > 0 && std::isfinite(1.0 / cell);
  return known ? cell : 1.0;
}

}  // namespace

py::dict convert(const py::object& field_or_path, double iso, const fs::path& output, py::kwargs kwargs) {
  const std::string path = output.string();
  py::dict remaining(kwargs);
  ConvertInput input = convert_input(field_or_path, remaining);
  ConvertOptions options = take_convert_options(remaining);
  const bool force = remaining.contains("force") && remaining.attr("pop")("force").cast<bool>();
  reject_unknown_keywords(remaining, "convert");
  options.prepare.extract.iso = iso;
  check_output(path, force);
  load(input);
  ConvertResult result;
  {
    py::gil_scoped_release release;
    result = convert_volume(std::move(input.volume), input.source, options);
    write_isw(path, result.bytes, force);
  }
  return summary_of(result, path, input);
}

namespace {

// roi / roi_sphere: a sequence of 6 or 4 numbers, as the CLI's --roi and --roi-sphere.
std::optional<RegionOfInterest> region_argument(const py::object& roi, const py::object& roi_sphere, double falloff) {
  if (!roi.is_none() && !roi_sphere.is_none()) throw Error(ErrorKind::InvalidArgument, "give at most one of roi and roi_sphere");
  const bool sphere = !roi_sphere.is_none();
  const py::object& given = sphere ? roi_sphere : roi;
  if (given.is_none()) {
    if (falloff != 0) throw Error(ErrorKind::InvalidArgument, "roi_falloff needs roi or roi_sphere");
    return std::nullopt;
  }
  if (!(falloff >= 0) || !std::isfinite(falloff))
    throw Error(ErrorKind::InvalidArgument, "roi_falloff must be a non-negative distance");
  RegionOfInterest region = make_region(given.cast<std::vector<double>>(), sphere, sphere ? "roi_sphere" : "roi");
  region.falloff = falloff;
  return region;
}

// bytes and max_error (at most one): the file prefix a decode reads.
void prefix_options(const py::object& max_error, const py::object& bytes, IswDecodeOptions& options) {
  if (!max_error.is_none() && !bytes.is_none())
    throw Error(ErrorKind::InvalidArgument, "give at most one of max_error and bytes");
  if (!bytes.is_none()) options.max_file_bytes = bytes.cast<std::uint64_t>();
  if (!max_error.is_none()) {
    options.max_error_cells = max_error.cast<double>();
    if (!(options.max_error_cells > 0) || !std::isfinite(options.max_error_cells))
      throw Error(ErrorKind::InvalidArgument, "max_error must be a positive number of cells");
  }
}

// A percentage in 0..100.
double percent_argument(const py::object& percent) {
  const double value = percent.cast<double>();
  if (!(value >= 0 && value <= 100)) throw Error(ErrorKind::InvalidArgument, "percent must be in 0..100");
  return value;
}

}  // namespace

py::tuple decode(const fs::path& file, const py::object& percent, const py::object& coefficients,
                 const py::object& max_error, const py::object& bytes, const py::object& level, bool limit,
                 bool triangulate, const py::object& roi, const py::object& roi_sphere, double roi_falloff,
                 const py::object& view, double pixel_error, bool cull_back_faces, const std::string& oracle) {
  const std::string path = file.string();
  if (!percent.is_none() && !coefficients.is_none())
    throw Error(ErrorKind::InvalidArgument, "give at most one of percent and coefficients");
  const std::optional<RegionOfInterest> region = region_argument(roi, roi_sphere, roi_falloff);
  if (region && !level.is_none()) throw Error(ErrorKind::InvalidArgument, "roi gives the finest level: no level");
  const std::optional<Camera> camera = camera_argument(view);
  if (cull_back_faces && !camera) throw Error(ErrorKind::InvalidArgument, "cull_back_faces needs a view");
  if (camera && (region || !level.is_none() || !percent.is_none() || !coefficients.is_none() || limit))
    throw Error(ErrorKind::InvalidArgument, "view chooses each face's level: no roi, level, percent, coefficients or limit");
  IswDecodeOptions options;
  // The surface needs no ranking unless a limit asks for it; with a region
  // the limit applies outside it, to a whole decode ranked by importance.
  const bool limited = !percent.is_none() || !coefficients.is_none();
  options.order = region && limited ? IswOrder::Importance : IswOrder::Index;
  double percent_value = 100;
  if (!percent.is_none()) {
    percent_value = percent_argument(percent);
    if (!region) options.max_percent = percent_value;
  }
  if (!coefficients.is_none() && !region) options.max_coefficients = coefficients.cast<std::uint64_t>();
  options.oracle = oracle_from_name(oracle);
  if (options.oracle != Oracle::Weighted && (!limited || region))
    throw Error(ErrorKind::InvalidArgument, "oracle chooses what percent or coefficients keep (not with roi)");
  prefix_options(max_error, bytes, options);
  // A region with nothing kept outside, or a view, reads only the groups it needs (2.2).
  if (region && !limited) options.region = region;
  options.frustum = camera;
  options.view_scope = IswDecodeOptions::ViewScope::Patch;
  const std::size_t outside = coefficients.is_none() ? 0 : coefficients.cast<std::size_t>();
  const int requested_level = level.is_none() ? -1 : level.cast<int>();
  PolygonMesh mesh;
  std::string truncation;
  {
    py::gil_scoped_release release;
    IswDecoded decoded = read_isw(path, options);
    if (decoded.truncated) truncation = path + ": " + decoded.truncation_note;
    const int l = level.is_none() ? decoded.levels : requested_level;
    if (l < 0 || l > decoded.levels)
      throw Error(ErrorKind::InvalidArgument,
                  "level must be in 0.." + std::to_string(decoded.levels) + ", got " + std::to_string(l));
    if (camera) {
      mesh = view_mesh(decoded, *camera, pixel_error, nullptr, cull_back_faces ? BackFaces::Cull : BackFaces::Refine);
    } else if (region) {
      const std::size_t keep = percent.is_none() ? outside : coefficients_for_percent(*decoded.hierarchy, percent_value);
      mesh = region_mesh(decoded, *region, keep);
    } else {
      mesh = decoded.hierarchy->control_mesh(l, take_reconstruction(decoded, decoded.ranked.size(), l));
    }
    if (limit) mesh.positions = limit_surface(mesh).positions;
    if (triangulate)  // base faces (level 0, or outside a region) may share two corners
      mesh = isowave::triangulate(mesh, l == 0 || region || camera ? QuadSplit::ShorterAvoidingEdges : QuadSplit::Shorter);
  }
  if (!truncation.empty() && PyErr_WarnEx(PyExc_UserWarning, truncation.c_str(), 1) != 0) throw py::error_already_set();
  return mesh_arrays(std::move(mesh));
}

py::dict decode_polygons(const fs::path& file, const py::object& percent, const py::object& max_error,
                         const py::object& bytes, const py::object& level, bool limit) {
  const std::string path = file.string();
  IswDecodeOptions options;
  options.order = percent.is_none() ? IswOrder::Index : IswOrder::Importance;
  if (!percent.is_none()) options.max_percent = percent_argument(percent);
  prefix_options(max_error, bytes, options);
  PolygonMesh mesh;
  std::vector<std::int8_t> born;
  std::vector<double> detail;
  std::string truncation;
  std::uint64_t bytes_read = 0, file_bytes = 0;
  {
    py::gil_scoped_release release;
    IswDecoded decoded = read_isw(path, options);
    if (decoded.truncated) truncation = path + ": " + decoded.truncation_note;
    const int l = level.is_none() ? decoded.levels : level.cast<int>();
    if (l < 0 || l > decoded.levels)
      throw Error(ErrorKind::InvalidArgument,
                  "level must be in 0.." + std::to_string(decoded.levels) + ", got " + std::to_string(l));
    // Vertex i of a level's control mesh is entry i of the coarse-to-fine array.
    const SubdivisionHierarchy& h = *decoded.hierarchy;
    const std::size_t n = h.vertex_count(l), base = h.vertex_count(0);
    born.resize(n);
    detail.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      born[i] = static_cast<std::int8_t>(h.level_of_index(i));
      if (i >= base) detail[i] = norm(decoded.coefficients[i]);
    }
    mesh = h.control_mesh(l, take_reconstruction(decoded, decoded.ranked.size(), l));
    if (limit) mesh.positions = limit_surface(mesh).positions;
    bytes_read = decoded.file_bytes_read;
    file_bytes = decoded.file_bytes;
  }
  if (!truncation.empty() && PyErr_WarnEx(PyExc_UserWarning, truncation.c_str(), 1) != 0) throw py::error_already_set();
  const auto vertices = static_cast<py::ssize_t>(mesh.vertex_count());
  const auto offsets = static_cast<py::ssize_t>(mesh.face_offsets.size());
  const auto corners = static_cast<py::ssize_t>(mesh.face_vertices.size());
  return py::dict(py::arg("vertices") = owned_array<double>(std::move(mesh.positions), {vertices, 3}),
                  py::arg("offsets") = owned_array<std::uint32_t>(std::move(mesh.face_offsets), {offsets}),
                  py::arg("corners") = owned_array<std::uint32_t>(std::move(mesh.face_vertices), {corners}),
                  py::arg("level") = owned_array<std::int8_t>(std::move(born), {vertices}),
                  py::arg("detail") = owned_array<double>(std::move(detail), {vertices}),
                  py::arg("bytes_read") = bytes_read, py::arg("file_bytes") = file_bytes);
}

py::list stats(const fs::path& file, const std::vector<double>& percents) {
  const std::string path = file.string();
  for (double p : percents)
    if (!(p >= 0 && p <= 100)) throw Error(ErrorKind::InvalidArgument, "percents must be in 0..100");
  ErrorTable errors;
  double cell = 1, fine = 1, extracted = 0;
  {
    py::gil_scoped_release release;
    const std::string bytes = read_file_bytes(path);
    const IswDecoded decoded = decode_isw(bytes, path);
    if (decoded.truncated)
      throw Error(ErrorKind::Format, path + ": " + decoded.truncation_note + "; stats need the whole file");
    errors = error_table(decoded, percents, nullptr, nullptr, decode_prefixes(bytes));
    cell = recorded_cell_size(decoded.metadata);
    fine = static_cast<double>(decoded.fine_vertices);
    extracted = decoded.metadata.number("extracted_vertices", 0);
  }
  py::list rows;
  for (const RateDistortionRow& r : errors.rows) {
    const double bits = 8.0 * static_cast<double>(r.bytes);
    rows.append(py::dict(py::arg("coefficients") = r.kept, py::arg("percent") = r.percent,
                         py::arg("rmse_percent_cell") = 100.0 * r.rms / cell,
                         py::arg("max_percent_cell") = 100.0 * r.max / cell, py::arg("bytes") = r.bytes,
                         py::arg("bits_per_fine_vertex") = bits / fine,
                         py::arg("bits_per_isosurface_vertex") = extracted > 0 ? bits / extracted : 0.0,
                         py::arg("base") = r.is_base));
  }
  return rows;
}

}  // namespace isowave::python
