#pragma once
// Polygon mesh files: PLY (ASCII, binary little- and big-endian), OBJ and OFF,
// chosen by extension (case-insensitive).
//
// These readers are our own rather than OpenMesh's IO layer because OpenMesh's
// importer (9.0) cannot represent a non-manifold file and silently changes it:
// on three triangles sharing one edge it reports success but duplicates the
// vertices of the face it cannot add (5 vertices become 8), printing only a
// warning. isowave must load such files unchanged and say exactly what is
// wrong with them (require_manifold). A test checks that both readers agree on
// the real meshes. Every byte is treated as hostile: counts are checked
// against the file size before anything is allocated.
#include <string>

#include "isowave/core/mesh.h"

namespace isowave {

enum class MeshFormat { Ply, Obj, Off };

// Throws Error(InvalidArgument) for an extension other than .ply, .obj, .off.
MeshFormat mesh_format_from_path(const std::string& path);

// Reads a mesh; the PLY vertex property `sharp` (any numeric type, non-zero =
// sharp) fills PolygonMesh::sharp. Throws Error(Io) if the file cannot be read
// and Error(Format), naming the file and the problem, if it is malformed:
// truncated, counts that do not match, indices out of range, non-finite
// coordinates, faces with fewer than 3 vertices. Topology is not checked here
// (see require_manifold()).
PolygonMesh read_mesh(const std::string& path);

// The whole file's bytes. Throws Error(Io) naming the path and the cause (no
// such file, a directory, no permission, a failed read).
std::string read_file_bytes(const std::string& path);

struct MeshWriteOptions {
  bool ascii = false;             // PLY only; OBJ and OFF are always text
  // Coordinates as double instead of float. Chosen anyway when float would
  // lose the geometry (float_loses_geometry()).
  bool double_precision = false;
};

// True when float32 coordinates would not keep `mesh`'s shape: its largest
// coordinate rounds by more than a millionth of its bounding box (a
// georeferenced origin far from a small surface), or it is near float's range
// limits (huge or tiny).
bool float_loses_geometry(const PolygonMesh& mesh);

// Writes atomically (AtomicFileWriter). An existing file is replaced: the
// caller decides whether that is allowed. PLY gets the uchar vertex property `sharp`
// when any vertex is sharp; OBJ and OFF cannot carry it. Throws
// Error(InvalidArgument) for an unknown extension, Error(Format) for a mesh
// that fails validate_indices(), Error(Io) if the file cannot be written.
// O(vertices + corners).
void write_mesh(const std::string& path, const PolygonMesh& mesh, const MeshWriteOptions& options = {});

}  // namespace isowave
