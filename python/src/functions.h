#pragma once
// The functions of the isowave module (paths: str or os.PathLike) (module.cpp documents them for Python
// users). Each releases the GIL for the library's work and raises
// isowave.Error for what the library throws as isowave::Error.
#include <filesystem>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

namespace isowave::python {

namespace py = pybind11;

// volume_functions.cpp
py::tuple read_volume(const std::filesystem::path& path, py::kwargs kwargs);
py::tuple extract(const py::array& field, double iso, const py::object& spacing, const py::object& origin,
                  bool flip, std::size_t min_component_vertices, double smooth);

// isw_functions.cpp
py::dict convert(const py::object& field_or_path, double iso, const std::filesystem::path& path, py::kwargs kwargs);
py::tuple decode(const std::filesystem::path& path, const py::object& percent, const py::object& coefficients,
                 const py::object& max_error, const py::object& bytes, const py::object& level, bool limit,
                 bool triangulate, const py::object& roi, const py::object& roi_sphere, double roi_falloff,
                 const py::object& view, double pixel_error, bool cull_back_faces, const std::string& oracle);
py::dict decode_polygons(const std::filesystem::path& path, const py::object& percent, const py::object& max_error,
                         const py::object& bytes, const py::object& level, bool limit);
py::list stats(const std::filesystem::path& path, const std::vector<double>& percents);
// isowave.ViewRefiner (view_refiner.cpp).
void define_view_refiner(py::module_& m);

}  // namespace isowave::python
