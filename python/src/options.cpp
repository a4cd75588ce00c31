#include "options.h"

#include <string>

#include "arrays.h"
#include "isowave/codec/camera.h"
#include "isowave/core/error.h"

namespace isowave::python {
namespace {

// Removes `name` from `kwargs`; None when it was not given.
py::object take(py::dict& kwargs, const char* name) {
  if (!kwargs.contains(name)) return py::none();
  return kwargs.attr("pop")(name);
}

template <typename T>
T cast_as(const py::object& value, const char* name) {
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    throw py::type_error(std::string(name) + "=" + py::repr(value).cast<std::string>() + " has the wrong type");
  }
}

template <typename T>
T take_as(py::dict& kwargs, const char* name, T fallback) {
  const py::object value = take(kwargs, name);
  return value.is_none() ? fallback : cast_as<T>(value, name);
}

}  // namespace

VolumeReadOptions take_read_options(py::dict& kwargs) {
  VolumeReadOptions options;
  if (const py::object dims = take(kwargs, "dims"); !dims.is_none()) {
    const Vec3 d = vec3_from(dims, "dims");
    std::array<std::size_t, 3> counts{};
    for (int i = 0; i < 3; ++i) {
      if (!(d[i] >= 1 && d[i] <= 1e9 && d[i] == static_cast<double>(static_cast<std::size_t>(d[i]))))
        throw py::value_error("dims must be three positive integers (x, y, z)");
      counts[static_cast<std::size_t>(i)] = static_cast<std::size_t>(d[i]);
    }
    options.dims = counts;
  }
  if (const py::object type = take(kwargs, "type"); !type.is_none())
    options.type = parse_scalar_type(py::str(type).cast<std::string>());
  const std::string endian = take_as<std::string>(kwargs, "endian", "little");
  if (endian != "little" && endian != "big") throw py::value_error("endian must be 'little' or 'big', got '" + endian + "'");
  options.big_endian = endian == "big";
  if (const py::object spacing = take(kwargs, "spacing"); !spacing.is_none()) {
    options.spacing = vec3_from(spacing, "spacing");
    if (!(options.spacing->x > 0 && options.spacing->y > 0 && options.spacing->z > 0) || !is_finite(*options.spacing))
      throw py::value_error("spacing must be three positive finite numbers (x, y, z)");
  }
  if (const py::object origin = take(kwargs, "origin"); !origin.is_none()) options.origin = vec3_from(origin, "origin");
  options.field = take_as<std::string>(kwargs, "field", "");
  options.grid = take_as<std::string>(kwargs, "grid", "");
  return options;
}

ConvertOptions take_convert_options(py::dict& kwargs) {
  ConvertOptions options;
  const py::object levels = take(kwargs, "levels");
  if (!levels.is_none() && !(py::isinstance<py::str>(levels) && levels.cast<std::string>() == "auto"))
    options.levels = cast_as<int>(levels, "levels");
  const std::string fit = take_as<std::string>(kwargs, "fit", "normal");
  if (fit == "parametrization") options.fit = FitMethod::Parametrization;
  else if (fit == "normal") options.fit = FitMethod::Normal;
  else if (fit == "shrink-wrap") options.fit = FitMethod::ShrinkWrap;
  else
    throw Error(ErrorKind::InvalidArgument, "fit must be 'shrink-wrap', 'parametrization' or 'normal', not '" + fit + "'");
  options.rate.max_error_cells = take_as<double>(kwargs, "max_error", 0.0);
  options.max_error_cells = kLevelShareOfMaxError * options.rate.max_error_cells;
  options.rate.max_bytes = take_as<std::uint64_t>(kwargs, "size", 0);
  options.rate.bits_per_vertex = take_as<double>(kwargs, "bits_per_vertex", 0.0);
  const py::object base_vertices = take(kwargs, "base_vertices");
  const py::object base_ratio = take(kwargs, "base_ratio");
  if (!base_vertices.is_none() && !base_ratio.is_none())
    throw Error(ErrorKind::InvalidArgument, "give at most one of base_vertices and base_ratio");
  if (!base_vertices.is_none()) {
    options.base.vertices = cast_as<std::size_t>(base_vertices, "base_vertices");
    if (options.base.vertices < 4) throw Error(ErrorKind::InvalidArgument, "base_vertices must be at least 4");
  }
  if (!base_ratio.is_none()) options.base.ratio = cast_as<double>(base_ratio, "base_ratio");
  // As the CLI: without an explicit size the base grows until it covers the isosurface.
  options.base.growth = base_vertices.is_none() && base_ratio.is_none() ? BaseGrowth::UntilCovered : BaseGrowth::Fixed;
  options.step_cells = take_as<double>(kwargs, "step", options.step_cells);
  IsosurfaceOptions& extract = options.prepare.extract;
  extract.smooth_sigma = take_as<double>(kwargs, "smooth", 0.0);
  extract.min_component_vertices = take_as<std::size_t>(kwargs, "min_component_vertices", 0);
  extract.flip = take_as<bool>(kwargs, "flip", false);
  options.folded_fit = take_as<bool>(kwargs, "allow_folded", false) ? FoldedFit::Keep : FoldedFit::Refuse;
  return options;
}

void reject_unknown_keywords(const py::dict& kwargs, const char* function) {
  for (const auto& item : kwargs)
    throw py::type_error(std::string(function) + "() got an unexpected keyword argument '" +
                         py::str(item.first).cast<std::string>() + "'");
}

std::optional<Camera> camera_argument(const py::object& view) {
  if (view.is_none()) return std::nullopt;
  if (!py::isinstance<py::dict>(view)) return read_camera(py::str(view).cast<std::string>());
  const py::dict d = view.cast<py::dict>();
  for (const auto& item : d) {
    const std::string key = py::str(item.first);
    if (key != "position" && key != "target" && key != "up" && key != "fov" && key != "viewport")
      throw Error(ErrorKind::InvalidArgument, "view: unknown key '" + key + "'");
  }
  const auto vec = [&](const char* key) {
    if (!d.contains(key)) throw Error(ErrorKind::InvalidArgument, std::string("view: no '") + key + "'");
    const std::vector<double> v = d[key].cast<std::vector<double>>();
    if (v.size() != 3) throw Error(ErrorKind::InvalidArgument, std::string("view: '") + key + "' needs 3 numbers");
    return Vec3{v[0], v[1], v[2]};
  };
  Camera camera;
  camera.position = vec("position");
  camera.target = vec("target");
  camera.up = vec("up");
  if (!d.contains("fov") || !d.contains("viewport")) throw Error(ErrorKind::InvalidArgument, "view: needs 'fov' and 'viewport'");
  camera.fov_degrees = d["fov"].cast<double>();
  const std::vector<int> viewport = d["viewport"].cast<std::vector<int>>();
  if (viewport.size() != 2) throw Error(ErrorKind::InvalidArgument, "view: 'viewport' needs 2 numbers");
  camera.width = viewport[0];
  camera.height = viewport[1];
  check_camera(camera);
  return camera;
}

}  // namespace isowave::python
