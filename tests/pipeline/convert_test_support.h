#pragma once
// For the conversion's tests: a conversion with its file's full decode as a
// mesh, and analytic surfaces (the builtin torus field's, any given
// distance) to measure it against.
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/mesh.h"
#include "isowave/core/surface_error.h"
#include "isowave/pipeline/convert.h"

namespace isowave::test {

// The control mesh of a decode's finest level with every coefficient it holds.
inline PolygonMesh full_decode_mesh(const IswDecoded& decoded) {
  return decoded.hierarchy->control_mesh(decoded.hierarchy->levels(), reconstruct(decoded, decoded.ranked.size()));
}

// A conversion with `fit` (the extracted mesh kept, the 100% summary row
// only) and its file's full decode.
struct DecodedConversion {
  ConvertResult result;
  IswDecoded decoded;
  PolygonMesh fine;  // full_decode_mesh(decoded)
};
inline DecodedConversion convert_and_decode(const Volume& field, const std::string& name, FitMethod fit) {
  ConvertOptions options;
  options.fit = fit;
  options.keep_extracted_mesh = true;
  options.summary_percents = {100};
  DecodedConversion out;
  out.result = convert_volume(field, name, options);
  out.decoded = decode_isw(out.result.bytes, name);
  out.fine = full_decode_mesh(out.decoded);
  return out;
}

// Distance to the builtin torus at n samples per axis (builtin_fields.h):
// unit spacing, centre (n-1)/2, radii 0.25 (n-1) and 0.1 (n-1); its field is
// the signed distance, so this is exact.
inline double torus_distance(const Vec3& p, std::size_t n) {
  const double size = double(n - 1), c = 0.5 * size;
  const double ring = std::hypot(p.x - c, p.y - c) - 0.25 * size;
  return std::abs(std::hypot(ring, p.z - c) - 0.1 * size);
}

// RMS of distance(p) over 100,000 area-uniform samples p of `mesh`.
template <class Distance>
double rms_distance(const PolygonMesh& mesh, const Distance& distance) {
  double sum = 0;
  const std::vector<Vec3> samples = area_samples(mesh, 100000, 7);
  for (const Vec3& p : samples) sum += distance(p) * distance(p);
  return std::sqrt(sum / double(samples.size()));
}

// RMS distance of area-uniform samples of `mesh` from the analytic torus.
inline double rms_from_torus(const PolygonMesh& mesh, std::size_t n) {
  return rms_distance(mesh, [n](const Vec3& p) { return torus_distance(p, n); });
}

}  // namespace isowave::test
