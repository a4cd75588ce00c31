// convert_volume() with the normal fit (FitMethod::Normal, issue #47):
// against the analytic torus, the decoded surface lies within 1.25 times the
// marching-cubes mesh's own distance from the true surface, without folds;
// every wavelet coefficient of the file decodes along its frame normal (the
// frames of the fit's frame base, renumbered with the base): no tangential
// detail at all, and almost no bits spent on tangential parts. A thin fin
// the base cannot span: its points' lines miss, so their coefficients are
// non-normal, and the fin is still covered. A truncated stream's surface
// moves along the normal only, where the parametrization's slides along
// itself.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/statistics.h"
#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/fit/trilinear.h"
#include "isowave/pipeline/convert.h"
#include "support/test_meshes.h"
#include "convert_test_support.h"

namespace isowave {
namespace {

using test::rms_from_torus;

TEST(ConvertNormal, DecodedTorusIsNearTheTrueSurfaceWithOnlyNormalDetail) {
  constexpr std::size_t n = 48;
  const test::DecodedConversion conversion = test::convert_and_decode(make_builtin_field("torus", n), "torus", FitMethod::Normal);
  const ConvertResult& result = conversion.result;
  EXPECT_EQ(result.non_normal_coefficients, 0u);
  EXPECT_EQ(result.fit.folded_faces, 0u);
  ASSERT_EQ(result.normal_share.size(), std::size_t(result.levels));
  for (const double share : result.normal_share) EXPECT_GT(share, 1 - 1e-12);
  // Codec 2.1 spends on tangential parts only one flag (0) per wavelet
  // coefficient that becomes significant: at most 0.0221 bits each once its
  // context has adapted, and under 32 bits per context to get there
  // (tests/codec/test_bitplane_coder.cpp derives both); 4 contexts per class
  // (1 + 2 levels) and group (G = clamp(round(N / 2^17), 1, 64), docs/FORMAT.md).
  const std::size_t groups = std::min<std::size_t>(64, std::max<std::size_t>(1, (result.fine_vertices + 65536) >> 17));
  const std::size_t classes = 1 + 2 * std::size_t(result.levels);
  EXPECT_GT(result.plane_bits.total(), 0);
  EXPECT_LE(result.plane_bits.tangential(), 0.0221 * double(result.fine_vertices) + 32.0 * 4 * classes * groups);
  EXPECT_EQ(result.plane_bits.tangential_sign + result.plane_bits.tangential_refinement, 0.0);

  const IswDecoded& decoded = conversion.decoded;
  const double marching_cubes = rms_from_torus(result.extracted_mesh, n), fitted = rms_from_torus(conversion.fine, n);
  std::printf("torus %zu: marching cubes %.4f cell RMS from the torus, decoded normal fit %.4f (levels %d)\n", n,
              marching_cubes, fitted, result.levels);
  EXPECT_LE(fitted, 1.25 * marching_cubes);

  ASSERT_EQ(result.frame_base.size(), decoded.hierarchy->vertex_count(0));
  const std::vector<Vec3> normals =
      isw_frame_normals(*decoded.hierarchy, result.frame_base, kFrameStepCells * result.cell_size);
  std::size_t nonzero = 0;
  for (std::size_t i = decoded.hierarchy->vertex_count(0); i < decoded.coefficients.size(); ++i) {
    const Vec3& c = decoded.coefficients[i];
    const Vec3& m = normals[i];
    EXPECT_LE(norm(c - m * dot(m, c)), 1e-12 * (1 + norm(c))) << "coefficient " << i;
    nonzero += norm(c) > 0;
  }
  EXPECT_GT(nonzero, decoded.coefficients.size() / 4);  // the check above is not vacuous
}

// A sphere cut by two faces of the box: the surface's boundary curves lie on
// them. Every decoded point stays in the box (the field is clamped beyond it,
// so its isosurface would go on outside), the decoded surface lies as near
// the true sphere as the marching-cubes mesh, and few coefficients are
// non-normal (the boundary curves' are: a large share of this small mesh).
TEST(ConvertNormal, SphereCutByTheBoxStaysInsideIt) {
  const Vec3 c{0.3, 20.2, 41.6};
  const double r = 14;
  const Volume field = test::sampled_volume(
      {36, 40, 44}, [&](double x, double y, double z) { return r - std::sqrt(squared_norm(Vec3{x, y, z} - c)); });
  const test::DecodedConversion conversion = test::convert_and_decode(field, "cut sphere", FitMethod::Normal);
  const ConvertResult& result = conversion.result;
  const PolygonMesh& fine = conversion.fine;
  const auto from_sphere = [&](const PolygonMesh& mesh) {
    return test::rms_distance(mesh, [&](const Vec3& p) { return std::sqrt(squared_norm(p - c)) - r; });
  };
  double beyond = 0, fitted_beyond = 0;
  for (const Vec3& p : fine.positions) beyond = std::max({beyond, -p.x, p.z - 43});
  for (const Vec3& p : result.fit.positions) fitted_beyond = std::max({fitted_beyond, -p.x, p.z - 43});
  std::printf("cut sphere: points at most %.4f cells beyond the box, fitted %.4f\n", beyond, fitted_beyond);
  EXPECT_LE(fitted_beyond, 1e-3);
  EXPECT_LE(beyond, 0.05);  // plus the quantization: a few of the finest steps
  const double marching_cubes = from_sphere(result.extracted_mesh), fitted = from_sphere(fine);
  std::printf("cut sphere: marching cubes %.4f cell RMS from the sphere, decoded normal fit %.4f; %zu of %zu "
              "coefficients non-normal\n",
              marching_cubes, fitted, result.non_normal_coefficients, result.fine_vertices - result.base_vertices);
  EXPECT_LE(fitted, 1.25 * marching_cubes);
  EXPECT_LT(double(result.non_normal_coefficients), 0.1 * double(result.fine_vertices - result.base_vertices));
}

// A sphere of radius 12 cells with a fin 0.6 cells thick and 6 cells high
// standing 9 cells out of it along +x: the field is the larger of the two
// solids' inside distances (the fin's a box's, by its nearest face).
struct FinField {
  Vec3 c{24.3, 23.8, 24.1};
  double r = 12, half_thickness = 0.3, half_height = 3, tip = 21;
  double operator()(const Vec3& p) const {
    const Vec3 q = p - c;
    const double sphere = r - std::sqrt(squared_norm(q));
    const double fin = std::min({half_thickness - std::abs(q.y), half_height - std::abs(q.z), tip - q.x, q.x});
    return std::max(sphere, fin);
  }
  bool on_fin(const Vec3& p) const { return p.x - c.x > r + 1.5; }
};

// The share of a decoded coefficient's length off its frame normal.
double tangential_share(const Vec3& c, const Vec3& n) {
  const double length = norm(c);
  return length > 0 ? norm(c - n * dot(n, c)) / length : 0.0;
}

TEST(ConvertNormal, ThinFinIsCoveredByNonNormalCoefficients) {
  const FinField fin;
  const Volume field = test::sampled_volume({49, 48, 49}, [&](double x, double y, double z) { return fin({x, y, z}); });
  const test::DecodedConversion conversion = test::convert_and_decode(field, "fin", FitMethod::Normal);
  const ConvertResult& result = conversion.result;
  const IswDecoded& decoded = conversion.decoded;
  const PolygonMesh& fine = conversion.fine;
  const std::vector<Vec3> normals =
      isw_frame_normals(*decoded.hierarchy, result.frame_base, kFrameStepCells * result.cell_size);

  // Coefficients the file holds off their frame normals, and those of fine points on the fin.
  const TrilinearGrid grid(field);
  std::size_t off_normal = 0, on_fin = 0, on_fin_off_normal = 0;
  double off_normal_sum = 0;
  for (std::size_t i = decoded.hierarchy->vertex_count(0); i < decoded.coefficients.size(); ++i) {
    const bool off = tangential_share(decoded.coefficients[i], normals[i]) > 0.1;
    const Vec3& p = fine.positions[i];
    if (off) {
      const TrilinearSample s = grid.sample(p);
      const double d = std::abs(s.value) / norm(s.gradient);
      off_normal_sum += d * d;
      ++off_normal;
    }
    if (fin.on_fin(p)) on_fin_off_normal += off, ++on_fin;
  }
  // Every extracted vertex on the fin near the decoded surface.
  const BinnedSurfaceDistance decoded_surface(fine);
  double fin_worst = 0;
  for (const Vec3& p : result.extracted_mesh.positions)
    if (fin.on_fin(p)) fin_worst = std::max(fin_worst, decoded_surface.distance(p));
  const double off_normal_rms = off_normal ? std::sqrt(off_normal_sum / double(off_normal)) : 0.0;
  std::printf("fin: %zu coefficients off their normal (%zu counted by the fit), %zu of %zu fin points; those "
              "points %.4f cell RMS off the isosurface; the fin's extracted vertices at most %.3f cells from the "
              "decoded surface\n",
              off_normal, result.non_normal_coefficients, on_fin_off_normal, on_fin, off_normal_rms, fin_worst);
  ASSERT_GT(on_fin, 20u);
  EXPECT_GT(on_fin_off_normal, 0u);
  EXPECT_GE(result.non_normal_coefficients, off_normal);
  EXPECT_LT(off_normal_rms, 0.05);
  EXPECT_LT(fin_worst, 0.5);
}

// Per fine vertex of `mesh`: its unit area-weighted normal.
std::vector<Vec3> vertex_normals(const PolygonMesh& mesh) {
  std::vector<Vec3> normals(mesh.vertex_count());
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* v = mesh.face_begin(f);
    const std::uint32_t n = mesh.face_size(f);
    Vec3 area;
    for (std::uint32_t k = 0; k < n; ++k) area += cross(mesh.positions[v[k]], mesh.positions[v[(k + 1) % n]]);
    for (std::uint32_t k = 0; k < n; ++k) normals[v[k]] += area;
  }
  for (Vec3& n : normals) n = norm(n) > 0 ? n * (1.0 / norm(n)) : n;
  return normals;
}

// The share of the squared moves from the full decode to the decode of the
// first quarter of the plane stream that lies along the full decode's
// vertex normals.
double truncation_normal_share(const ConvertResult& result, const std::string& name) {
  const IswDecoded full = decode_isw(result.bytes, name);
  IswDecodeOptions options;
  options.max_stream_bytes = full.stream.bytes / 4;
  const IswDecoded cut = decode_isw(result.bytes, name, options);
  const PolygonMesh a = test::full_decode_mesh(full), b = test::full_decode_mesh(cut);
  const std::vector<Vec3> normals = vertex_normals(a);
  double along = 0, all = 0;
  for (std::size_t v = 0; v < a.vertex_count(); ++v) {
    const Vec3 move = b.positions[v] - a.positions[v];
    along += dot(move, normals[v]) * dot(move, normals[v]);
    all += squared_norm(move);
  }
  return all > 0 ? along / all : 1.0;
}

TEST(ConvertNormal, TruncatedStreamMovesAlongTheNormalNotAlongTheSurface) {
  constexpr std::size_t n = 48;
  const Volume torus = make_builtin_field("torus", n);
  ConvertOptions options;
  options.summary_percents = {100};
  options.fit = FitMethod::Normal;
  const double normal = truncation_normal_share(convert_volume(torus, "torus", options), "torus");
  options.fit = FitMethod::Parametrization;
  const double parametrized = truncation_normal_share(convert_volume(torus, "torus", options), "torus");
  std::printf("torus %zu, a quarter of the plane stream: %.1f%% of the squared moves along the normal with the "
              "normal fit, %.1f%% with the parametrization\n",
              n, 100 * normal, 100 * parametrized);
  EXPECT_GT(normal, 0.9);
  EXPECT_LT(parametrized, normal);
}

}  // namespace
}  // namespace isowave
