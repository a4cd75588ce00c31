// The header sections both format versions share (docs/FORMAT.md: META,
// BASE, BPTS).
#include "isw_headers.h"

#include <cassert>
#include <cmath>
#include <cstdlib>

#include <zlib.h>

#include "isowave/core/mesh_topology.h"
#include "base_connectivity.h"
#include "isowave/core/error.h"
#include "range_coder.h"

namespace isowave::detail {

namespace {

// Metadata lines are `key=value`, split at the first '=': a key loses its
// '=', both lose line breaks (to spaces).
std::string sanitize(const std::string& text, bool key) {
  std::string s = text;
  for (char& c : s)
    if (c == '\n' || c == '\r' || (key && c == '=')) c = ' ';
  return s;
}

// Version 2, coder 1: the cut-border machine of base_connectivity.h.
void put_base_traversal(std::string& out, const PolygonMesh& base) {
  std::string payload(1, static_cast<char>(kBaseCoderTraversal));
  const ConnectivityCounts counts = connectivity_counts(base);
  put_u32(payload, static_cast<std::uint32_t>(counts.vertices));
  put_u32(payload, static_cast<std::uint32_t>(counts.faces));
  put_u32(payload, static_cast<std::uint32_t>(counts.corners));
  std::string coded;
  RangeEncoder rc(coded);
  encode_connectivity(rc, base);
  rc.finish();
  put_coded(payload, coded);
  put_section(out, "BASE", payload);
}

}  // namespace

void put_meta(std::string& out, const IswMetadata& metadata, int major) {
  std::string text;
  for (const auto& [key, value] : metadata.values) text += sanitize(key, true) + "=" + sanitize(value, false) + "\n";
  if (major == 1) {
    put_section(out, "META", text);
    return;
  }
  uLongf size = compressBound(static_cast<uLong>(text.size()));
  std::string packed(size, '\0');
  const int status = compress2(reinterpret_cast<Bytef*>(packed.data()), &size,
                               reinterpret_cast<const Bytef*>(text.data()), static_cast<uLong>(text.size()), 9);
  assert(status == Z_OK);
  (void)status;
  packed.resize(size);
  std::string payload;
  put_u32(payload, static_cast<std::uint32_t>(text.size()));
  put_section(out, "META", payload + packed);
}

// Payload: a u64 size, then the coded bytes.
void put_coded(std::string& payload, const std::string& coded) {
  put_u64(payload, coded.size());
  payload += coded;
}

void put_base(std::string& out, const PolygonMesh& base, int major) {
  if (major >= 2 && is_canonical(base)) {
    put_base_traversal(out, base);
    return;
  }
  std::string payload;
  if (major >= 2) payload.push_back(static_cast<char>(kBaseCoderIndices));
  put_u32(payload, static_cast<std::uint32_t>(base.vertex_count()));
  put_u32(payload, static_cast<std::uint32_t>(base.face_count()));
  put_u32(payload, static_cast<std::uint32_t>(base.face_vertices.size()));
  std::vector<std::uint32_t> sharp;
  for (std::size_t v = 0; v < base.vertex_count(); ++v)
    if (base.is_sharp(v)) sharp.push_back(static_cast<std::uint32_t>(v));
  put_u32(payload, static_cast<std::uint32_t>(sharp.size()));
  std::string coded;
  RangeEncoder rc(coded);
  BaseModels m;
  std::int64_t previous_first = 0;
  for (std::size_t f = 0; f < base.face_count(); ++f) {
    const std::uint32_t* face = base.face_begin(f);
    encode_integer(rc, m.face_size, static_cast<std::int64_t>(base.face_size(f)) - 3);
    encode_integer(rc, m.first_index, static_cast<std::int64_t>(face[0]) - previous_first);
    for (std::uint32_t k = 1; k < base.face_size(f); ++k)
      encode_integer(rc, m.other_index, static_cast<std::int64_t>(face[k]) - static_cast<std::int64_t>(face[0]));
    previous_first = face[0];
  }
  std::int64_t previous_sharp = -1;
  for (std::uint32_t v : sharp) {
    encode_integer(rc, m.sharp_gap, static_cast<std::int64_t>(v) - previous_sharp);
    previous_sharp = v;
  }
  rc.finish();
  put_coded(payload, coded);
  put_section(out, "BASE", payload);
}


void put_base_points(std::string& out, const PolygonMesh& base, const std::vector<QuantizedVector>& q) {
  std::string coded;
  RangeEncoder rc(coded);
  std::array<IntegerModel, 3> models;
  const auto neighbours = earlier_neighbours(base);
  for (std::size_t v = 0; v < base.vertex_count(); ++v) {
    const QuantizedVector prediction = predict_base(q, neighbours[v], v);
    for (int axis = 0; axis < 3; ++axis)
      encode_integer(rc, models[static_cast<std::size_t>(axis)], q[v][axis] - prediction[axis]);
  }
  rc.finish();
  std::string payload;
  put_coded(payload, coded);
  put_section(out, "BPTS", payload);
}



namespace {

void decode_base_traversal(PayloadReader& reader, PolygonMesh& base) {
  ConnectivityCounts counts;
  counts.vertices = reader.read<std::uint32_t>();
  counts.faces = reader.read<std::uint32_t>();
  counts.corners = reader.read<std::uint32_t>();
  const auto coded_size = reader.read<std::uint64_t>();
  if (coded_size != reader.remaining()) reader.fail("has an inconsistent size");
  const std::string_view coded = reader.bytes(coded_size);
  RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(coded.data()), coded.size());
  try {
    base = decode_connectivity(rc, counts);
  } catch (const Error& error) {
    reader.fail(std::string("holds an invalid base mesh: ") + error.what());
  }
}

}  // namespace

void decode_meta(PayloadReader& reader, std::string_view payload, IswMetadata& metadata, int major) {
  std::string text;
  if (major >= 2) {
    const auto size = reader.read<std::uint32_t>();
    if (size > kMaxMetadataBytes) reader.fail("is too large");
    text.resize(size);
    uLongf unpacked = size;
    const std::string_view packed = payload.substr(4);
    if (uncompress(reinterpret_cast<Bytef*>(text.data()), &unpacked, reinterpret_cast<const Bytef*>(packed.data()),
                   static_cast<uLong>(packed.size())) != Z_OK ||
        unpacked != size)
      reader.fail("is corrupt (its text does not inflate)");
    payload = text;
  }
  std::size_t start = 0;
  while (start < payload.size()) {
    std::size_t end = payload.find('\n', start);
    if (end == std::string::npos) end = payload.size();
    const std::string line(payload.substr(start, end - start));
    const std::size_t eq = line.find('=');
    if (eq != std::string::npos) metadata.values[line.substr(0, eq)] = line.substr(eq + 1);
    start = end + 1;
  }
}


void decode_base(PayloadReader& reader, PolygonMesh& base, int major) {
  if (major >= 2) {
    const auto coder = reader.read<std::uint8_t>();
    if (coder == kBaseCoderTraversal) return decode_base_traversal(reader, base);
    if (coder != kBaseCoderIndices) reader.fail("uses an unknown coder");
  }
  const auto vertices = reader.read<std::uint32_t>();
  const auto faces = reader.read<std::uint32_t>();
  const auto corners = reader.read<std::uint32_t>();
  const auto sharp_count = reader.read<std::uint32_t>();
  const auto coded_size = reader.read<std::uint64_t>();
  if (coded_size != reader.remaining()) reader.fail("has an inconsistent size");
  const std::uint64_t integer_budget = kMaxIntegersPerCodedByte * (coded_size + 16);
  if (faces == 0 || corners < 3ull * faces || vertices > corners || sharp_count > vertices ||
      std::uint64_t{corners} + faces + sharp_count > integer_budget)
    reader.fail("has impossible counts");
  const std::string_view coded = reader.bytes(coded_size);
  RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(coded.data()), coded.size());
  BaseModels m;
  base.positions.assign(vertices, Vec3{});
  base.face_offsets.reserve(std::size_t{faces} + 1);
  base.face_vertices.reserve(corners);
  std::int64_t previous_first = 0;
  std::vector<std::uint32_t> face;
  for (std::uint32_t f = 0; f < faces; ++f) {
    const std::int64_t size_code = decode_integer(rc, m.face_size);
    if (size_code < 0 || base.face_vertices.size() + 3 + static_cast<std::uint64_t>(size_code) > corners)
      reader.fail("has an invalid face size");
    face.assign(static_cast<std::size_t>(size_code + 3), 0);
    const std::int64_t first = previous_first + decode_integer(rc, m.first_index);
    for (std::size_t k = 0; k < face.size(); ++k) {
      const std::int64_t index = k == 0 ? first : first + decode_integer(rc, m.other_index);
      if (index < 0 || index >= vertices) reader.fail("has a vertex index out of range");
      face[k] = static_cast<std::uint32_t>(index);
    }
    previous_first = first;
    base.add_face(face.data(), face.size());
  }
  if (base.face_vertices.size() != corners) reader.fail("has an inconsistent corner count");
  if (sharp_count > 0) base.sharp.assign(vertices, 0);
  std::int64_t previous_sharp = -1;
  for (std::uint32_t s = 0; s < sharp_count; ++s) {
    const std::int64_t v = previous_sharp + decode_integer(rc, m.sharp_gap);
    if (v <= previous_sharp || v >= vertices) reader.fail("has an invalid sharp vertex");
    base.sharp[static_cast<std::size_t>(v)] = 1;
    previous_sharp = v;
  }
  if (rc.overran()) reader.fail("is corrupt (coded data ends early)");
  try {
    require_manifold(base, "base mesh");
  } catch (const Error& error) {
    reader.fail(std::string("holds an invalid base mesh: ") + error.what());
  }
}



void decode_base_points(PayloadReader& reader, PolygonMesh& base, double step, std::vector<QuantizedVector>& q) {
  const auto coded_size = reader.read<std::uint64_t>();
  if (coded_size != reader.remaining()) reader.fail("has an inconsistent size");
  if (3ull * base.vertex_count() > kMaxIntegersPerCodedByte * (coded_size + 16)) reader.fail("is too short");
  const std::string_view coded = reader.bytes(coded_size);
  RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(coded.data()), coded.size());
  q.assign(base.vertex_count(), QuantizedVector{0, 0, 0});
  std::array<IntegerModel, 3> models;
  const auto neighbours = earlier_neighbours(base);
  const double s = step;
  for (std::size_t v = 0; v < base.vertex_count(); ++v) {
    const QuantizedVector prediction = predict_base(q, neighbours[v], v);
    for (int axis = 0; axis < 3; ++axis) {
      q[v][axis] = prediction[axis] + decode_integer(rc, models[static_cast<std::size_t>(axis)]);
      if (std::abs(q[v][axis]) > (1ll << 40)) reader.fail("holds an impossible value");
    }
    base.positions[v] = {q[v][0] * s, q[v][1] * s, q[v][2] * s};
  }
  if (rc.overran()) reader.fail("is corrupt (coded data ends early)");
}


}  // namespace isowave::detail
