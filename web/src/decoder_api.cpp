// The browser decoder's C interface (web/README.md): the library's .isw
// decoder (codec, transform, core; no fit) compiled to WebAssembly. A page
// copies a prefix of a file into the module's memory, decodes it to a
// triangle mesh at a level, and reads the arrays below until the next
// decode. Every error is a message, never an abort: a truncated or corrupt
// prefix returns 1 and isw_error() says why.
#include <emscripten/emscripten.h>

#include <cstdint>
#include <exception>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/wavelet_transform.h"

namespace {

struct Decoded {
  std::vector<float> positions;  // 3 per vertex, world units (WebGL's float)
  std::vector<std::uint32_t> triangles;
  std::string error;
  int levels = 0, level = 0;
  double error_cells = -1;  // D of the prefix, from the file's rate table
  double stream_bytes = 0, stream_total = 0;
  bool truncated = false;
};

Decoded last;

// D (cells) the file records for the decoded stream prefix: the last rate
// table row within it; -1 without a table or a cell size.
double recorded_error(const isowave::IswDecoded& d) {
  const double cell = d.metadata.number("cell_size", 0);
  double error = -1;
  for (const isowave::IswRatePoint& row : d.stream.rate_table)
    if (row.stream_bytes <= d.stream.decoded && cell > 0) error = row.error / cell;
  return error;
}

// The triangles of `mesh` into `last`.
void keep(const isowave::PolygonMesh& mesh) {
  last.positions.resize(3 * mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a) last.positions[3 * v + static_cast<std::size_t>(a)] = static_cast<float>(mesh.positions[v][a]);
  last.triangles = mesh.face_vertices;
}

// Level `level` (-1: the finest) of what the bytes hold; the base mesh
// alone (its points at BPTS's precision) from the headers with level -2,
// which builds no hierarchy: a viewer's first frame.
void decode(const std::uint8_t* bytes, std::uint32_t size, int level, const char* name) {
  isowave::IswDecodeOptions options;
  options.order = isowave::IswOrder::Index;
  options.headers_only = level == -2;
  isowave::IswDecoded d = isowave::decode_isw(std::string(reinterpret_cast<const char*>(bytes), size), name, options);
  last.levels = d.levels;
  if (options.headers_only) {
    last.level = 0;
    keep(isowave::triangulate(d.base, isowave::QuadSplit::ShorterAvoidingEdges));
    return;
  }
  const isowave::SubdivisionHierarchy& h = *d.hierarchy;
  last.level = level < 0 || level > d.levels ? d.levels : level;
  std::vector<isowave::Vec3> points = std::move(d.coefficients);
  isowave::synthesize(h, points, last.level);
  keep(isowave::triangulate(h.control_mesh(last.level, std::move(points)),
                            last.level == 0 ? isowave::QuadSplit::ShorterAvoidingEdges : isowave::QuadSplit::Shorter));
  last.error_cells = recorded_error(d);
  last.stream_bytes = static_cast<double>(d.stream.decoded);
  last.stream_total = static_cast<double>(d.stream.bytes);
  last.truncated = d.truncated;
}

}  // namespace

extern "C" {

// Decodes `size` bytes at `bytes` (a file or a prefix of one) at `level`
// (-1: the finest; -2: the base mesh from the headers alone); `name` (UTF-8)
// heads error messages. Returns 0, or 1 with isw_error() set.
EMSCRIPTEN_KEEPALIVE int isw_decode(const std::uint8_t* bytes, std::uint32_t size, int level, const char* name) {
  last = Decoded{};
  try {
    decode(bytes, size, level, name);
    return 0;
  } catch (const std::exception& error) {
    last = Decoded{};
    last.error = error.what();
    return 1;
  }
}

EMSCRIPTEN_KEEPALIVE const char* isw_error() { return last.error.c_str(); }
EMSCRIPTEN_KEEPALIVE std::uint32_t isw_vertex_count() { return static_cast<std::uint32_t>(last.positions.size() / 3); }
EMSCRIPTEN_KEEPALIVE const float* isw_positions() { return last.positions.data(); }
EMSCRIPTEN_KEEPALIVE std::uint32_t isw_triangle_count() { return static_cast<std::uint32_t>(last.triangles.size() / 3); }
EMSCRIPTEN_KEEPALIVE const std::uint32_t* isw_triangles() { return last.triangles.data(); }
EMSCRIPTEN_KEEPALIVE int isw_levels() { return last.levels; }
EMSCRIPTEN_KEEPALIVE int isw_level() { return last.level; }
EMSCRIPTEN_KEEPALIVE double isw_error_cells() { return last.error_cells; }
EMSCRIPTEN_KEEPALIVE double isw_stream_bytes() { return last.stream_bytes; }
EMSCRIPTEN_KEEPALIVE double isw_stream_total() { return last.stream_total; }
EMSCRIPTEN_KEEPALIVE int isw_truncated() { return last.truncated ? 1 : 0; }

}  // extern "C"
