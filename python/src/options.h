#pragma once
// Keyword arguments of the isowave module's functions, turned into the
// library's option structs. Keywords are the CLI's option names with '_' for
// '-' (base_ratio for --base-ratio) and take typed values (dims=(64, 64, 32),
// levels="auto" or 3, flip=True); the library checks most ranges itself
// (isowave::Error, so isowave.Error with the CLI's message).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>

#include "isowave/codec/camera.h"
#include "isowave/extract/volume_io.h"
#include "isowave/pipeline/convert.h"

namespace isowave::python {

namespace py = pybind11;

// Takes the keywords it knows out of `kwargs` and reads them: the reader's
// dims, type, endian, spacing, origin, field, grid. py::value_error for a
// malformed value.
VolumeReadOptions take_read_options(py::dict& kwargs);

// The same for convert's options: levels, fit, max_error, base_vertices,
// base_ratio, step, smooth, min_component_vertices, flip, size, bits_per_vertex,
// allow_folded.
ConvertOptions take_convert_options(py::dict& kwargs);

// view=: a camera as a dict (position, target, up, fov, viewport) or a JSON
// file's path; nothing for None. isowave::Error for a camera that is not one.
std::optional<Camera> camera_argument(const py::object& view);

// Raises TypeError, as Python does, when `kwargs` still holds a keyword
// (unknown to `function`).
void reject_unknown_keywords(const py::dict& kwargs, const char* function);

}  // namespace isowave::python
