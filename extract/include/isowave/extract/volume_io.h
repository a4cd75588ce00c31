#pragma once
// Volume input: raw, NRRD (.nrrd/.nhdr), legacy VTK (.vtk), VTK XML ImageData
// (.vti), OpenVDB (.vdb), NumPy (.npy), HDF5 (.h5/.hdf5), NetCDF (.nc), and
// generated fields named builtin:NAME[:N].
//
// Every reader treats the file as hostile: sizes are checked against the file
// (or, for compressed data, against the most the compressed bytes can inflate
// to) before allocating, and any problem with the file is an Error(Format) or
// Error(Io) whose message starts with the file's path and names the problem
// (truncated data, size mismatch, unknown type, corrupt gzip/zlib, missing
// field, bad header). Usage problems (missing .raw dimensions, an unknown
// extension, a bad builtin: name) are Error(InvalidArgument).
//
// Formats, chosen by extension (case-insensitive):
//   .raw         headerless samples; dims and type from the options, the file
//                size must equal dims x sample size exactly. With dims and
//                type given, a file of any name is read this way.
//   .nrrd/.nhdr  NRRD0001-0005, attached or detached header (the data file is
//                relative to the header), raw / gzip / ascii encoding, line
//                and byte skip; 3-D scalar data only. Geometry from
//                'space directions' (axis-aligned) + 'space origin', or
//                'spacings'.
//   .vtk         legacy STRUCTURED_POINTS, ASCII or BINARY (big-endian); other
//                arrays (VECTORS, NORMALS, FIELD, cell data, ...) are skipped.
//   .vti         ImageData with ascii, inline base64 or appended (raw/base64)
//                arrays, optionally vtkZLibDataCompressor, UInt32/UInt64
//                headers, either byte order; one Piece; axis-aligned Direction.
//   .vdb         a float or double grid, densified over its active bounding
//                box (inactive voxels read as the background); the transform
//                must be linear and axis-aligned.
//   .npy         NumPy format 1.0-3.0, a 3-D array of dtype i1 u1 i2 u2 i4 u4
//                i8 u8 f2 f4 f8, either byte order, C or Fortran order.
//   .h5/.hdf5    "FILE.h5:/group/dataset" (or options.field): a 3-D integer
//                or float dataset, contiguous or chunked with any filter
//                libhdf5 decodes; unnamed, the file's only such dataset.
//   .nc          "FILE.nc:variable[@T]" (or options.field): a numeric
//                variable (z, y, x), or (time, z, y, x) read at time step T;
//                unnamed, the file's only such variable. Classic or NetCDF-4.
//                For these three the axis that varies fastest in the file is
//                x (C order: shape (nz, ny, nx)); spacing 1 and origin 0.
//                HDF5 and NetCDF datasets larger than 1032 x the file (what
//                deflate can reach) are refused before allocating; libhdf5 and
//                libnetcdf themselves are not hardened (docs/CLI.md).
// Axes with a negative step (NRRD space directions, VTI Direction, VDB
// transforms) are reversed so that the spacing is positive and every sample
// keeps its world position.
#include <array>
#include <optional>
#include <string>

#include "isowave/core/volume.h"

namespace isowave {

struct VolumeReadOptions {
  // .raw (required there; with both given, any file is read as raw): samples
  // along x, y, z and the sample type.
  std::optional<std::array<std::size_t, 3>> dims;
  std::optional<ScalarType> type;
  bool big_endian = false;  // .raw only
  // Override (for .raw: set) the grid geometry; any format.
  std::optional<Vec3> spacing;
  std::optional<Vec3> origin;
  // .vtk / .vti: the point-data array to read by name. Default: .vtk the first
  // SCALARS array of the point data; .vti the PointData's Scalars array, else
  // its first DataArray. A .vtk FIELD array with one component also qualifies
  // when named. The array must have one component. .h5: the dataset; .nc:
  // the variable, "NAME@T" for time step T (an InvalidArgument error when the
  // path names one too).
  std::string field;
  // .vdb: the grid to read by name (default: the first float or double grid).
  std::string grid;
};

// True if `path` ends (case-insensitively) in an extension with a reader of
// its own: .raw, .nrrd, .nhdr, .vtk, .vti, .vdb, .npy, .h5, .hdf5, .nc.
bool has_volume_extension(const std::string& path);

// A dataset path split into its file and selection: "FILE.h5:/group/data"
// -> {"FILE.h5", "/group/data"}, likewise .hdf5 and .nc ("FILE.nc:var@3");
// a path naming an existing file, or without such a ':', is kept whole with
// an empty selection.
struct SelectedPath {
  std::string file, selection;
};
SelectedPath split_selection(const std::string& path);

// Reads a volume. builtin:NAME[:N] calls make_builtin_field(NAME, N), N
// defaulting to 128; a .raw file, or any file without a volume extension when
// options.dims and options.type are both set, is raw samples; otherwise the
// reader is chosen by extension (case-insensitive). NaN/Inf
// samples (including float64 samples beyond the float range) are kept and
// counted in nonfinite_count.
Volume read_volume(const std::string& path, const VolumeReadOptions& options = {});

// Parses "uint8", "int16", "float32", ... (also "float" and "double");
// throws Error(InvalidArgument).
ScalarType parse_scalar_type(const std::string& name);

}  // namespace isowave
