#pragma once
// Private: the header sections both format versions share (docs/FORMAT.md:
// META, BASE, BPTS), written by isw_encoder.cpp and read by isw_decoder.cpp.
#include <string>
#include <string_view>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/core/mesh.h"
#include "isw_models.h"
#include "isw_sections.h"

namespace isowave::detail {

// META: `key=value` lines; version 2 deflates them (u32 text size, then zlib).
void put_meta(std::string& out, const IswMetadata& metadata, int major);
void decode_meta(PayloadReader& reader, std::string_view payload, IswMetadata& metadata, int major);

// BASE: counts and the range-coded faces and sharp flags. Version 2 first
// writes a u8 coder id: kBaseCoderTraversal (base_connectivity.h) for a base
// in its canonical order, else kBaseCoderIndices (version 1's coder).
constexpr std::uint8_t kBaseCoderIndices = 0;
constexpr std::uint8_t kBaseCoderTraversal = 1;
void put_base(std::string& out, const PolygonMesh& base, int major);
void decode_base(PayloadReader& reader, PolygonMesh& base, int major);

// BPTS: base control points quantized to multiples of `step`, predicted
// from decoded neighbours. `q` holds the integers.
void put_base_points(std::string& out, const PolygonMesh& base, const std::vector<QuantizedVector>& q);
void decode_base_points(PayloadReader& reader, PolygonMesh& base, double step, std::vector<QuantizedVector>& q);

// Payload: a u64 size, then the coded bytes.
void put_coded(std::string& payload, const std::string& coded);

}  // namespace isowave::detail
