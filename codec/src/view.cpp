#include "isowave/codec/view.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"
#include "isowave/transform/adaptive_mesh.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {

namespace {

// Per base face and level m in 1..L (index f (L + 1) + m): the largest class
// weight times magnitude among the face's level-m coefficients.
std::vector<double> face_details(const IswDecoded& decoded) {
  const SubdivisionHierarchy& h = *decoded.hierarchy;
  const PolygonMesh& base = h.base();
  const std::size_t stride = static_cast<std::size_t>(h.levels()) + 1;
  std::vector<double> detail(base.face_count() * stride, 0.0);
  // Level-k faces (k >= 1) are numbered by base corner, 4 per parent face.
  std::vector<std::uint32_t> corner_face(base.face_vertices.size());
  for (std::uint32_t f = 0; f < base.face_count(); ++f)
    std::fill(corner_face.begin() + base.face_offsets[f], corner_face.begin() + base.face_offsets[f + 1], f);
  for (int m = 1; m <= h.levels(); ++m) {
    const RefinementStep& s = h.step(m);
    const int shift = m >= 2 ? 2 * (m - 2) : 0;
    const auto base_face = [&](std::uint32_t p) { return m == 1 ? p : corner_face[p >> shift]; };
    const double wf = decoded.class_weights[static_cast<std::size_t>(1 + 2 * (m - 1))];
    const double we = decoded.class_weights[static_cast<std::size_t>(2 + 2 * (m - 1))];
    const auto raise = [&](std::uint32_t f, double v) {
      double& d = detail[f * stride + static_cast<std::size_t>(m)];
      d = std::max(d, v);
    };
    for (std::uint32_t p = 0; p < s.parent_face_count; ++p)
      raise(base_face(p), wf * norm(decoded.coefficients[s.first_face_vertex() + p]));
    for (std::uint32_t e = 0; e < s.parent_edge_count; ++e) {
      const double v = we * norm(decoded.coefficients[s.first_edge_vertex() + e]);
      for (int side = 0; side < 2; ++side) raise(base_face(s.edge_faces[2 * e + side] - s.first_face_vertex()), v);
    }
  }
  return detail;
}

// Distance from p to the box [lo, hi] (0 inside).
double distance_to_box(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  const Vec3 nearest{std::clamp(p.x, lo.x, hi.x), std::clamp(p.y, lo.y, hi.y), std::clamp(p.z, lo.z, hi.z)};
  return norm(p - nearest);
}

}  // namespace

ViewLevels view_face_levels(const IswDecoded& decoded, const std::vector<Vec3>& fine, const Camera& camera,
                            double pixel_error) {
  if (!decoded.hierarchy) throw Error(ErrorKind::InvalidArgument, "a view decode needs a decoded file");
  if (!(pixel_error > 0) || !std::isfinite(pixel_error))
    throw Error(ErrorKind::InvalidArgument, "the pixel error must be a positive number");
  check_camera(camera);
  const SubdivisionHierarchy& h = *decoded.hierarchy;
  const int levels = h.levels();
  const std::size_t stride = static_cast<std::size_t>(levels) + 1;
  const std::vector<double> detail = face_details(decoded);
  ViewLevels out;
  out.levels.assign(h.base().face_count(), 0);
  std::vector<std::uint8_t> culled(out.levels.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.levels.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f < r.end(); ++f) {
      constexpr double inf = std::numeric_limits<double>::infinity();
      Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
      for_each_fine_point(h, f, [&](std::size_t v) {
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min(lo[a], fine[v][a]);
          hi[a] = std::max(hi[a], fine[v][a]);
        }
        return true;
      });
      if (camera.box_outside(lo, hi)) {
        culled[f] = 1;
        continue;
      }
      const double distance = distance_to_box(camera.position, lo, hi);
      const double scale = distance > 0 ? camera.pixels_per_unit(distance) : inf;
      // The coarsest level whose omitted detail stays within the pixel error.
      double omitted = 0;
      int level = levels;
      for (int l = levels; l >= 1; --l) {
        omitted += detail[f * stride + static_cast<std::size_t>(l)];
        if (!(omitted * scale <= pixel_error)) break;
        level = l - 1;
      }
      out.levels[f] = level;
    }
  });
  out.culled = static_cast<std::size_t>(std::count(culled.begin(), culled.end(), 1));
  return out;
}

PolygonMesh view_mesh(const IswDecoded& decoded, const Camera& camera, double pixel_error, ViewLevels* report) {
  if (!decoded.hierarchy) throw Error(ErrorKind::InvalidArgument, "a view decode needs a decoded file");
  std::vector<Vec3> fine = decoded.coefficients;
  synthesize(*decoded.hierarchy, fine);
  fine.resize(decoded.hierarchy->fine_vertex_count());
  ViewLevels levels = view_face_levels(decoded, fine, camera, pixel_error);
  PolygonMesh mesh = adaptive_control_mesh(*decoded.hierarchy, levels.levels, fine);
  if (report) *report = std::move(levels);
  return mesh;
}

}  // namespace isowave
