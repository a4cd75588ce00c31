#include "arrays.h"

#include <cmath>
#include <string>

namespace isowave::python {
namespace {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles to be viewed as (n, 3)");

// Copies `count` samples into `values` as float, counting the non-finite ones.
template <typename T>
std::size_t copy_samples(const T* source, std::size_t count, std::vector<float>& values) {
  values.resize(count);
  std::size_t nonfinite = 0;
  for (std::size_t i = 0; i < count; ++i) {
    values[i] = static_cast<float>(source[i]);
    nonfinite += std::isfinite(values[i]) ? 0 : 1;
  }
  return nonfinite;
}

ScalarType scalar_type_of(const py::dtype& dtype) {
  const char kind = dtype.kind();
  const auto size = dtype.itemsize();
  if (kind == 'f') return size == 8 ? ScalarType::Float64 : ScalarType::Float32;
  const bool is_signed = kind == 'i';
  switch (size) {
    case 1: return is_signed ? ScalarType::Int8 : ScalarType::UInt8;
    case 2: return is_signed ? ScalarType::Int16 : ScalarType::UInt16;
    default: return is_signed ? ScalarType::Int32 : ScalarType::UInt32;
  }
}

}  // namespace

py::tuple mesh_arrays(PolygonMesh&& mesh) {
  const std::size_t faces = mesh.face_count();
  const std::size_t corners = faces ? mesh.face_size(0) : 3;
  for (std::size_t f = 0; f < faces; ++f)
    if (mesh.face_size(f) != corners)
      throw py::value_error("the mesh mixes faces of " + std::to_string(corners) + " and " +
                            std::to_string(mesh.face_size(f)) + " vertices; pass triangulate=True for triangles");
  const auto vertex_count = static_cast<py::ssize_t>(mesh.vertex_count());
  py::array vertices = owned_array<double>(std::move(mesh.positions), {vertex_count, 3});
  py::array face_array =
      owned_array<std::uint32_t>(std::move(mesh.face_vertices), {static_cast<py::ssize_t>(faces), static_cast<py::ssize_t>(corners)});
  return py::make_tuple(vertices, face_array);
}

py::array field_array(Volume&& volume) {
  const std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(volume.dims[2]), static_cast<py::ssize_t>(volume.dims[1]),
                                       static_cast<py::ssize_t>(volume.dims[0])};
  return owned_array<float>(std::move(volume.values), shape);
}

Volume volume_from_field(const py::array& field, const Vec3& spacing, const Vec3& origin) {
  if (field.ndim() != 3)
    throw py::value_error("the field must be a 3-D array indexed [z, y, x], got " + std::to_string(field.ndim()) +
                          " dimensions");
  if (!(spacing.x > 0 && spacing.y > 0 && spacing.z > 0) || !is_finite(spacing))
    throw py::value_error("spacing must be three positive finite numbers (x, y, z)");
  if (!is_finite(origin)) throw py::value_error("origin must be three finite numbers (x, y, z)");
  const char kind = field.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b')
    throw py::value_error("the field must hold numbers, got dtype " + py::str(field.dtype()).cast<std::string>());
  const bool direct = (field.flags() & py::array::c_style) &&
                      (field.dtype().is(py::dtype::of<float>()) || field.dtype().is(py::dtype::of<double>()));
  // The second copy the header names: NumPy's conversion to C-order float32.
  const py::array source = direct ? field : py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(field);
  if (!source) throw py::error_already_set();

  Volume volume;
  volume.dims = {static_cast<std::size_t>(field.shape(2)), static_cast<std::size_t>(field.shape(1)),
                 static_cast<std::size_t>(field.shape(0))};
  volume.spacing = spacing;
  volume.origin = origin;
  volume.source_type = scalar_type_of(field.dtype());
  const bool is_double = source.dtype().is(py::dtype::of<double>());
  const void* samples = source.data();
  const std::size_t count = volume.sample_count();
  py::gil_scoped_release release;
  volume.nonfinite_count = is_double ? copy_samples(static_cast<const double*>(samples), count, volume.values)
                                     : copy_samples(static_cast<const float*>(samples), count, volume.values);
  return volume;
}

Vec3 vec3_from(const py::handle& value, const char* what) {
  try {
    const auto v = value.cast<std::vector<double>>();
    if (v.size() == 3) return {v[0], v[1], v[2]};
  } catch (const py::cast_error&) {
  }
  throw py::value_error(std::string(what) + " must be three numbers (x, y, z)");
}

py::tuple vec3_tuple(const Vec3& v) { return py::make_tuple(v.x, v.y, v.z); }

}  // namespace isowave::python
