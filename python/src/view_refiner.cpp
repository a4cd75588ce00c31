// isowave.ViewRefiner: codec/view.h's ViewRefiner for interactive viewers
// (issue #48, item 6). The points are a NumPy view of the refiner's own
// buffer (no copy; the array keeps the refiner alive); patches come as flat
// index arrays a viewer uploads as they are.
#include <optional>
#include <string>
#include <vector>

#include "arrays.h"
#include "functions.h"
#include "options.h"
#include "isowave/codec/isw_format.h"
#include "isowave/codec/view.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh.h"

namespace isowave::python {

namespace {

constexpr const char* kViewRefinerDoc = R"(ViewRefiner(path, *, view=None)

A decoded .isw file for a viewer that refines it as its camera moves (`isowave decode --view`,
incrementally). view: a camera (a dict with position, target, up, fov, viewport, or a JSON file's
path) whose frustum alone is read from a version 2.2 file; None reads the whole file. Every base face
starts at level 0 until set_view().)";

constexpr const char* kSetViewDoc = R"(set_view(view, pixel_error=1.0, cull_back_faces=False) -> uint32 array

Refines each base face until the detail left out projects to at most pixel_error pixels (faces outside
the frustum at level 0, and with cull_back_faces=True those facing away: a closed surface seen from
outside, `--cull-back-faces`) and returns, ascending, the base faces whose patch changed (their level, or a
neighbour's across a base edge): re-emit those with patches().)";

constexpr const char* kPatchesDoc = R"(patches(faces) -> (polygon_faces, ends, corners)

The polygons of the given base faces at their levels, crack-free against their neighbours: corners
(uint32 indices into points) in polygon order, ends[i] the end of polygon i in corners, polygon_faces[i]
its base face.)";

constexpr const char* kViewMeshDoc = R"(mesh(*, triangulate=False) -> (vertices, faces)

The whole current mesh, as decode(view=...) returns it.)";

py::tuple patches(const ViewRefiner& refiner, const std::vector<std::uint32_t>& faces) {
  std::vector<std::uint32_t> owners, ends, corners;
  {
    py::gil_scoped_release release;
    for (const std::uint32_t f : faces) {
      const std::size_t before = ends.size();
      refiner.patch(f, ends, corners);
      owners.insert(owners.end(), ends.size() - before, f);
    }
  }
  const auto n = static_cast<py::ssize_t>(owners.size()), m = static_cast<py::ssize_t>(corners.size());
  return py::make_tuple(owned_array<std::uint32_t>(std::move(owners), {n}),
                        owned_array<std::uint32_t>(std::move(ends), {n}),
                        owned_array<std::uint32_t>(std::move(corners), {m}));
}

}  // namespace

void define_view_refiner(py::module_& m) {
  py::class_<ViewRefiner>(m, "ViewRefiner", kViewRefinerDoc)
      .def(py::init([](const std::filesystem::path& path, const py::object& view) {
             IswDecodeOptions options;
             options.frustum = camera_argument(view);
             options.order = IswOrder::Index;
             py::gil_scoped_release release;
             return ViewRefiner(read_isw(path.string(), options));
           }),
           py::arg("path"), py::kw_only(), py::arg("view") = py::none())
      .def(
          "set_view",
          [](ViewRefiner& refiner, const py::object& view, double pixel_error, bool cull_back_faces) {
            const std::optional<Camera> camera = camera_argument(view);
            if (!camera) throw Error(ErrorKind::InvalidArgument, "set_view needs a camera");
            std::vector<std::uint32_t> changed;
            {
              py::gil_scoped_release release;
              changed = refiner.set_view(*camera, pixel_error, cull_back_faces ? BackFaces::Cull : BackFaces::Refine);
            }
            const auto n = static_cast<py::ssize_t>(changed.size());
            return owned_array<std::uint32_t>(std::move(changed), {n});
          },
          py::arg("view"), py::arg("pixel_error") = 1.0, py::arg("cull_back_faces") = false, kSetViewDoc)
      .def_property_readonly(
          "levels",
          [](const ViewRefiner& refiner) {
            std::vector<std::int32_t> levels(refiner.levels().levels.begin(), refiner.levels().levels.end());
            const auto n = static_cast<py::ssize_t>(levels.size());
            return owned_array<std::int32_t>(std::move(levels), {n});
          },
          "per base face, its current level (int32)")
      .def_property_readonly(
          "points",
          [](py::object self) {
            const std::vector<Vec3>& p = self.cast<const ViewRefiner&>().points();
            py::array_t<double> points({static_cast<py::ssize_t>(p.size()), py::ssize_t{3}},
                                       reinterpret_cast<const double*>(p.data()), self);
            points.attr("setflags")(py::arg("write") = false);
            return points;
          },
          "the fine control points, (n, 3) float64, read-only view: patches() index them")
      .def("patches", &patches, py::arg("faces"), kPatchesDoc)
      .def(
          "mesh",
          [](const ViewRefiner& refiner, bool triangulate) {
            PolygonMesh mesh;
            {
              py::gil_scoped_release release;
              mesh = refiner.mesh();
              if (triangulate) mesh = isowave::triangulate(mesh, QuadSplit::ShorterAvoidingEdges);
            }
            return mesh_arrays(std::move(mesh));
          },
          py::kw_only(), py::arg("triangulate") = false, kViewMeshDoc);
}

}  // namespace isowave::python
