#pragma once
// A fitted-surface stand-in for codec tests: S^L of a jittered base mesh plus
// details at every level, analysed into coefficients.
#include <random>

#include "isowave/codec/isw_format.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/wavelet_transform.h"
#include "support/test_meshes.h"

namespace isowave::test {

struct CodedSurface {
  PolygonMesh base;
  int levels = 0;
  std::unique_ptr<SubdivisionHierarchy> hierarchy;
  std::vector<Vec3> fine;          // fine control points
  std::vector<Vec3> coefficients;  // their analysis
};

// Metadata for coded test surfaces: a source and a cell edge of 0.05.
inline IswMetadata sample_metadata() {
  IswMetadata m;
  m.values["source"] = "generated";
  m.values["cell_size"] = "0.05";
  return m;
}

inline CodedSurface make_coded_surface(PolygonMesh base, int levels, double detail, std::uint32_t seed) {
  CodedSurface s;
  jitter(base, 0.1, seed);
  s.base = base;
  s.levels = levels;
  s.hierarchy = std::make_unique<SubdivisionHierarchy>(base, levels);
  // Details of decreasing size at finer levels, as on a real surface.
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Vec3> data(s.hierarchy->fine_vertex_count());
  for (std::size_t i = 0; i < base.vertex_count(); ++i) data[i] = base.positions[i];
  for (std::size_t i = base.vertex_count(); i < data.size(); ++i) {
    const int level = s.hierarchy->level_of_index(i);
    const double size = detail / static_cast<double>(1 << level);
    data[i] = {size * noise(rng), size * noise(rng), size * noise(rng)};
  }
  s.coefficients = data;
  synthesize(*s.hierarchy, data);
  s.fine = data;
  return s;
}

}  // namespace isowave::test
