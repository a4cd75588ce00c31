#pragma once
// NumPy arrays in and out of the isowave module, and who owns their memory.
//
// Out: every array the module returns owns the C++ buffer it views (the
// std::vector is moved into a capsule that is the array's base), so no
// sample, vertex or index is copied on the way out.
// In: the library's Volume owns its samples as float32 (core/volume.h), so a
// field is copied once into it; a C-contiguous float32 or float64 array is
// read directly (float64 rounded to float32 in that copy), any other array
// (another dtype, Fortran order, a strided view) is first converted by NumPy
// to a C-contiguous float32 array, a second copy.
//
// Axis order: a field is indexed field[z, y, x] (shape (nz, ny, nx)), so its
// last axis is x, the library's fastest-varying one: a C-order array has the
// library's layout. Spacing and origin are (x, y, z) triples, vertices
// (x, y, z) rows in world units.
#include <cstdint>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"

namespace isowave::python {

namespace py = pybind11;

// A NumPy array of `shape` viewing `values`, which it takes over (Scalar is
// the element type NumPy sees, e.g. double for Vec3). No copy.
template <typename Scalar, typename Element>
py::array owned_array(std::vector<Element>&& values, const std::vector<py::ssize_t>& shape) {
  static_assert(sizeof(Element) % sizeof(Scalar) == 0, "an element must be whole scalars");
  auto owner = std::make_unique<std::vector<Element>>(std::move(values));
  const Scalar* data = reinterpret_cast<const Scalar*>(owner->data());
  py::capsule base(owner.get(), [](void* p) { delete static_cast<std::vector<Element>*>(p); });
  owner.release();  // the capsule owns it now
  return py::array_t<Scalar>(shape, data, base);
}

// (n, 3) float64 vertices and (m, k) uint32 faces of `mesh`, which they take
// over. Throws py::value_error when the faces differ in size (a level-0 mesh
// of mixed polygons; `triangulate=True` gives triangles).
py::tuple mesh_arrays(PolygonMesh&& mesh);

// (nz, ny, nx) float32 samples of `volume`, taken over.
py::array field_array(Volume&& volume);

// The library's volume of a 3-D array indexed [z, y, x] (one copy; see the
// header comment), with NaN/Inf samples counted as the readers count them.
// Throws py::value_error for another number of dimensions, a dtype NumPy
// cannot convert to float32, or spacing or origin outside Volume's contract.
// Copies with the GIL released.
Volume volume_from_field(const py::array& field, const Vec3& spacing, const Vec3& origin);

// (x, y, z) from a sequence of three numbers; py::value_error naming `what`
// otherwise.
Vec3 vec3_from(const py::handle& value, const char* what);
py::tuple vec3_tuple(const Vec3& v);

}  // namespace isowave::python
