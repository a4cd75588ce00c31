// read_volume and extract: volumes to NumPy and fields to isosurfaces.
#include "arrays.h"
#include "functions.h"
#include "options.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"

namespace isowave::python {

py::tuple read_volume(const std::filesystem::path& path, py::kwargs kwargs) {
  py::dict remaining(kwargs);
  const VolumeReadOptions options = take_read_options(remaining);
  reject_unknown_keywords(remaining, "read_volume");
  Volume volume;
  {
    py::gil_scoped_release release;
    volume = isowave::read_volume(path.string(), options);
  }
  const Vec3 spacing = volume.spacing, origin = volume.origin;
  return py::make_tuple(field_array(std::move(volume)), vec3_tuple(spacing), vec3_tuple(origin));
}

py::tuple extract(const py::array& field, double iso, const py::object& spacing, const py::object& origin,
                  bool flip, std::size_t min_component_vertices, double smooth) {
  const Volume volume = volume_from_field(field, vec3_from(spacing, "spacing"), vec3_from(origin, "origin"));
  IsosurfaceOptions options;
  options.iso = iso;
  options.flip = flip;
  options.min_component_vertices = min_component_vertices;
  options.smooth_sigma = smooth;
  Isosurface surface;
  {
    py::gil_scoped_release release;
    surface = extract_isosurface(volume, options);
  }
  return mesh_arrays(std::move(surface.mesh));
}

}  // namespace isowave::python
