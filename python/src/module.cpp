// The Python module isowave: the library's read, extract, convert, decode
// and stats steps as functions on NumPy arrays (docs/PYTHON.md). The
// docstrings here are the module's reference.
#include "arrays.h"
#include "functions.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"

namespace py = pybind11;

namespace {

constexpr const char* kModuleDoc = R"(Bicubic subdivision-surface wavelet compression of isosurfaces (Bertram et al. 2000).

Fields are NumPy arrays indexed field[z, y, x] (shape (nz, ny, nx)): the last axis is x, as in the
library's C-order layout. spacing and origin are (x, y, z) triples; vertices are rows (x, y, z) in
world units; faces are rows of vertex indices (uint32), counter-clockwise seen from the lower values.
Returned arrays own the library's buffers (no copy). Errors from files or arguments raise
isowave.Error (a RuntimeError) with the message the CLI prints and the kind in its .kind attribute.
Every function releases the GIL while the library works.)";

constexpr const char* kReadVolumeDoc = R"(read_volume(path, **reader_options) -> (field, spacing, origin)

Reads a volume file (.raw, .nrrd/.nhdr, .vtk, .vti, .vdb) or a generated field 'builtin:NAME[:N]'.
field: float32 array of shape (nz, ny, nx), owning the samples read (no copy); spacing and origin:
(x, y, z) tuples. reader_options, as the CLI's: dims=(nx, ny, nz) and type='float32' (raw input),
endian='little'|'big', spacing=(sx, sy, sz), origin=(ox, oy, oz) (override the file's), field='NAME'
(.vtk/.vti array), grid='NAME' (.vdb grid).)";

constexpr const char* kExtractDoc = R"(extract(field, iso, spacing=(1, 1, 1), origin=(0, 0, 0), *, flip=False, min_component_vertices=0, smooth=0) -> (vertices, faces)

The manifold isosurface of field (3-D, indexed [z, y, x]) at iso, as `isowave extract`: vertices
(n, 3) float64 world coordinates, faces (m, 3) uint32 triangles with normals toward lower values
(flip=True: higher). min_component_vertices drops smaller components; smooth is a Gaussian
pre-filter in voxels. The field is copied once into the library's float32 volume: read directly
when it is C-contiguous float32 or float64, else after NumPy's conversion to C-order float32 (a
second copy, e.g. for a Fortran-order or integer array).)";

constexpr const char* kConvertDoc = R"(convert(field_or_path, iso, path, **options) -> dict

Converts the isosurface at iso of a volume (a path or builtin: name as read_volume takes, or a 3-D
array indexed [z, y, x], copied as extract() copies it) into the .isw file `path`, as `isowave
convert -o path`. Options are the CLI's with '_' for '-': levels=1..6|'auto', fit='normal' (default)|
'shrink-wrap'|'parametrization', max_error (cells), size (bytes), bits_per_vertex, base_vertices, base_ratio,
step (cells), smooth, min_component_vertices, flip, allow_folded, force (replace an existing file); for a path
the reader options of read_volume; for an array spacing, origin and source (its name in the
file's metadata, default 'numpy array'). Returns the result `isowave convert --json` prints for it
(bytes, vertex counts, levels, seconds per stage, fit quality, the rate-distortion rows with D, the
quantization error, warnings).)";

constexpr const char* kDecodeDoc = R"(decode(path, *, percent=None, coefficients=None, max_error=None, bytes=None, level=None, limit=False, triangulate=False, roi=None, roi_sphere=None, roi_falloff=0, view=None, pixel_error=1.0, cull_back_faces=False, oracle="weighted") -> (vertices, faces)

Rebuilds the surface of an .isw file as `isowave decode`: the base mesh and the most important
wavelet coefficients, at most one of percent (0..100 of full resolution, counted as the paper does;
the default is 100) or coefficients (a count besides the base mesh), chosen by oracle ("weighted":
class weight x magnitude; "magnitude"; "greedy": least error added, as `--oracle`). level: the control mesh of this
level (default the finest; 0 is the base mesh); limit=True moves the vertices to the limit surface;
triangulate=True splits quads. vertices (n, 3) float64 and faces (m, k) uint32 (k = 4 above level
0) own the decoder's buffers (no copy). bytes reads only the file's first bytes (any prefix of a
version 2 stream decodes); max_error (cells) reads the shortest prefix whose error the file records
within it. roi=(x0, y0, z0, x1, y1, z1) or roi_sphere=(cx, cy, cz, r), world units: the finest level
with every point inside the region equal to the full decode's, percent or coefficients applying
outside it (none: the base mesh's surface there: then only the bytes the region needs are read from
a version 2.2 file), as `isowave decode --roi`; roi_falloff (world units) weights importance outside
by a Gaussian of the distance from the region (`--roi-falloff`). view: a camera, a dict {"position": (x, y, z),
"target": (x, y, z), "up": (x, y, z), "fov": degrees, "viewport": (width, height)} or the path of
such a JSON file: each base face refined until the detail left out projects to at most pixel_error
pixels, faces outside the view frustum kept whole (and with cull_back_faces=True those facing away,
`--cull-back-faces`), as `isowave decode --view`. A file cut inside its
coefficients decodes what it holds, with a UserWarning.)";

constexpr const char* kDecodePolygonsDoc = R"(decode_polygons(path, *, percent=None, max_error=None, bytes=None, level=None, limit=False) -> dict

The control mesh of one level as `decode` gives it, for viewers (the ParaView reader): faces as
polygons of any size (the base mesh mixes them), and per-vertex arrays. Keys: vertices (n, 3)
float64; offsets (m + 1,) uint32 and corners uint32, face f's vertices being
corners[offsets[f]:offsets[f + 1]] (VTK's cell arrays); level (n,) int8, the level each vertex
first appears on (0: a base vertex); detail (n,) float64, the magnitude of the decoded wavelet
coefficient at each vertex (world units; 0 at base vertices and where nothing was kept);
bytes_read and file_bytes. percent, max_error, bytes, level and limit as in decode.)";

constexpr const char* kStatsDoc = R"(stats(path, percents=(100, 20, 10, 5)) -> list of dict

The paper's Table 1 for an .isw file, as the rows of `isowave stats --json`: per percentage, then the
base mesh alone (base=True): coefficients (kept, base vertices included), percent, rmse_percent_cell
and max_percent_cell (against the full-resolution decode, in percent of the cell edge), bytes (the
file prefix a progressive reader needs), bits_per_fine_vertex, bits_per_isosurface_vertex.)";

constexpr const char* kKeepMemoryDoc = R"(keep_freed_memory_for_reuse() -> None

Makes this process's malloc keep the memory the library frees for its next allocations, as the CLI
does for itself: repeated decodes and conversions then reuse pages already faulted in instead of
having the kernel zero fresh ones (about a second per GB on slow virtual machines). The process
keeps its peak memory until release_freed_memory() or exit. Process-wide (it tunes glibc's malloc
for every allocation of the interpreter), so the module never calls it by itself.)";

constexpr const char* kReleaseMemoryDoc = R"(release_freed_memory() -> None

Gives the memory kept for reuse back to the kernel (malloc_trim).)";

}  // namespace

PYBIND11_MODULE(isowave, m) {
  using namespace isowave::python;
  // Every array the module hands over is NumPy's: without NumPy in this
  // interpreter, say so at import rather than at the first call.
  try {
    py::module_::import("numpy");
  } catch (py::error_already_set&) {
    const std::string python = py::module_::import("sys").attr("executable").cast<std::string>();
    throw py::import_error("isowave needs NumPy, which " + python +
                           " cannot import (Debian: apt install python3-numpy; else: " + python +
                           " -m pip install numpy)");
  }
  m.doc() = kModuleDoc;
  static py::exception<isowave::Error> error_type(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const isowave::Error& e) {
      py::object instance = py::handle(error_type.ptr())(e.what());
      instance.attr("kind") = isowave::to_string(e.kind());
      PyErr_SetObject(error_type.ptr(), instance.ptr());
    }
  });
  m.def("read_volume", &read_volume, py::arg("path"), kReadVolumeDoc);
  m.def("extract", &extract, py::arg("field"), py::arg("iso"), py::arg("spacing") = py::make_tuple(1.0, 1.0, 1.0),
        py::arg("origin") = py::make_tuple(0.0, 0.0, 0.0), py::kw_only(), py::arg("flip") = false,
        py::arg("min_component_vertices") = 0, py::arg("smooth") = 0.0, kExtractDoc);
  m.def("convert", &convert, py::arg("field_or_path"), py::arg("iso"), py::arg("path"), kConvertDoc);
  m.def("decode", &decode, py::arg("path"), py::kw_only(), py::arg("percent") = py::none(),
        py::arg("coefficients") = py::none(), py::arg("max_error") = py::none(), py::arg("bytes") = py::none(),
        py::arg("level") = py::none(), py::arg("limit") = false, py::arg("triangulate") = false,
        py::arg("roi") = py::none(), py::arg("roi_sphere") = py::none(), py::arg("roi_falloff") = 0.0,
        py::arg("view") = py::none(),
        py::arg("pixel_error") = 1.0, py::arg("cull_back_faces") = false, py::arg("oracle") = "weighted", kDecodeDoc);
  define_view_refiner(m);
  m.def("decode_polygons", &decode_polygons, py::arg("path"), py::kw_only(), py::arg("percent") = py::none(),
        py::arg("max_error") = py::none(), py::arg("bytes") = py::none(), py::arg("level") = py::none(),
        py::arg("limit") = false, kDecodePolygonsDoc);
  m.def("stats", &stats, py::arg("path"), py::arg("percents") = std::vector<double>{100, 20, 10, 5}, kStatsDoc);
  m.def("keep_freed_memory_for_reuse", &isowave::keep_freed_memory_for_reuse, kKeepMemoryDoc);
  m.def("release_freed_memory", &isowave::release_freed_memory, kReleaseMemoryDoc);
  m.attr("__version__") = ISOWAVE_VERSION;
}
