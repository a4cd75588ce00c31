// convert_volume(): the fit check that the error rows cannot make (they are
// measured against the fit itself).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "isowave/codec/convert.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/surface_distance.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/fit/fit_quality.h"

namespace isowave {
namespace {

bool warns_about_the_fit(const ConvertResult& result) {
  return std::any_of(result.warnings.begin(), result.warnings.end(),
                     [](const std::string& w) { return w.find("off the isosurface") != std::string::npos; });
}

// 99th percentile of the distance, in cells, from the extracted vertices to
// the decoded finest control mesh (quads split in two): an independent,
// exact measure of how much of the surface the fit misses.
double coverage_p99(const ConvertResult& result) {
  const IswDecoded decoded = decode_isw(result.bytes, "test");
  const std::vector<Vec3> points = reconstruct(decoded, decoded.ranked.size());
  const PolygonMesh fitted = decoded.hierarchy->control_mesh(decoded.hierarchy->levels(), points);
  PolygonMesh triangles;
  triangles.positions = fitted.positions;
  for (std::size_t f = 0; f < fitted.face_count(); ++f) {
    const std::uint32_t* face = fitted.face_begin(f);
    for (std::uint32_t k = 1; k + 1 < fitted.face_size(f); ++k) triangles.add_face({face[0], face[k], face[k + 1]});
  }
  std::vector<double> distances = SurfaceDistance(triangles).distances(result.extracted_mesh.positions);
  return percentile(distances, 0.99) / result.cell_size;
}

TEST(Convert, WarnsWhenTheFitLeavesPartsOfTheSurfaceOut) {
  const Volume torus = make_builtin_field("torus", 48);
  ConvertOptions options;
  options.keep_extracted_mesh = true;
  options.summary_percents = {100};

  // Nine base vertices: the shrink-wrap cannot reach the surface from them.
  options.base_vertices = 9;
  const ConvertResult coarse = convert_volume(torus, "torus", options);
  ASSERT_EQ(coarse.base_vertices, 9u);
  EXPECT_TRUE(warns_about_the_fit(coarse));
  EXPECT_GT(double(coarse.fit_isosurface.far), kFarPointsWarning * double(coarse.fine_vertices));
  EXPECT_GT(coverage_p99(coarse), 1.0);

  // The default base mesh (2% of the extracted vertices) follows it.
  options.base_vertices = 0;
  const ConvertResult fine = convert_volume(torus, "torus", options);
  EXPECT_FALSE(warns_about_the_fit(fine));
  EXPECT_LE(double(fine.fit_isosurface.far), kFarPointsWarning * double(fine.fine_vertices));
  EXPECT_LT(coverage_p99(fine), 0.5);
}

}  // namespace
}  // namespace isowave
