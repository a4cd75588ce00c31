#include "isowave/codec/view.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"
#include "isowave/transform/adaptive_mesh.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/wavelet_transform.h"
#include "isowave/codec/region.h"
#include "patch_mesh.h"

namespace isowave {

namespace {

// Per base face and level m in 1..L (index f (L + 1) + m): the largest class
// weight times magnitude among the face's level-m coefficients.
std::vector<double> face_details(const SubdivisionHierarchy& h, const std::vector<Vec3>& coefficients,
                                 const std::vector<double>& class_weights) {
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
    const double wf = class_weights[static_cast<std::size_t>(1 + 2 * (m - 1))];
    const double we = class_weights[static_cast<std::size_t>(2 + 2 * (m - 1))];
    const auto raise = [&](std::uint32_t f, double v) {
      double& d = detail[f * stride + static_cast<std::size_t>(m)];
      d = std::max(d, v);
    };
    for (std::uint32_t p = 0; p < s.parent_face_count; ++p)
      raise(base_face(p), wf * norm(coefficients[s.first_face_vertex() + p]));
    for (std::uint32_t e = 0; e < s.parent_edge_count; ++e) {
      const double v = we * norm(coefficients[s.first_edge_vertex() + e]);
      for (int side = 0; side < 2; ++side) raise(base_face(s.edge_faces[2 * e + side] - s.first_face_vertex()), v);
    }
  }
  return detail;
}

// Per base face: the box of its fine points and, per level l, the detail a
// face at level l leaves out (the sum over finer levels of face_details()).
struct FaceViewData {
  int levels = 0;
  std::vector<Vec3> lo, hi;
  std::vector<double> omitted;  // f (L + 1) + l
  // The normal cone of the face's finest faces: a unit axis and the largest
  // angle (radians) between it and a finest face's normal (pi: unknown).
  std::vector<Vec3> axis;
  std::vector<double> spread;
};

// Visits the (area-weighted) normals of base face f's finest faces: a
// level-L quad (corner, edge, centre, edge) in the parent's orientation, or
// the base polygon's own when L = 0.
template <class Visit>
void for_each_finest_normal(const SubdivisionHierarchy& h, std::size_t f, const std::vector<Vec3>& fine, Visit&& visit) {
  if (h.levels() == 0) {
    const PolygonMesh& base = h.base();
    Vec3 n{};
    for (std::uint32_t k = base.face_offsets[f]; k < base.face_offsets[f + 1]; ++k) {
      const std::uint32_t next = k + 1 < base.face_offsets[f + 1] ? k + 1 : base.face_offsets[f];
      n = n + cross(fine[base.face_vertices[k]], fine[base.face_vertices[next]]);
    }
    visit(n);
    return;
  }
  const RefinementStep& s = h.step(h.levels());
  const auto [first, end] = h.descendant_faces(f, h.levels() - 1);
  for (std::size_t p = first; p < end; ++p) {
    const Vec3& centre = fine[s.first_face_vertex() + p];
    const std::uint32_t begin = s.face_offsets[p], stop = s.face_offsets[p + 1];
    for (std::uint32_t k = begin; k < stop; ++k) {
      const std::uint32_t previous = k > begin ? k - 1 : stop - 1;
      visit(cross(centre - fine[s.face_vertices[k]], fine[s.face_edges[previous]] - fine[s.face_edges[k]]));
    }
  }
}

// The normal cone of base face f's finest faces: the axis of their summed
// normals and the widest angle from it (pi when they sum to nothing).
void normal_cone(const SubdivisionHierarchy& h, std::size_t f, const std::vector<Vec3>& fine, Vec3& axis,
                 double& spread) {
  Vec3 sum{};
  for_each_finest_normal(h, f, fine, [&](const Vec3& n) { sum = sum + n; });
  const double length = norm(sum);
  spread = std::acos(-1.0);
  if (!(length > 0) || !std::isfinite(length)) return;
  axis = sum * (1 / length);
  double widest = 0;
  for_each_finest_normal(h, f, fine, [&](const Vec3& n) {
    const double l = norm(n);
    if (l > 0) widest = std::max(widest, std::acos(std::clamp(dot(axis, n) / l, -1.0, 1.0)));  // degenerate: no direction
  });
  spread = widest;
}

// `coefficients` and `fine` over `h` (the whole hierarchy or a patch's).
FaceViewData face_view_data(const SubdivisionHierarchy& h, const std::vector<Vec3>& coefficients,
                            const std::vector<double>& class_weights, const std::vector<Vec3>& fine) {
  FaceViewData data;
  data.levels = h.levels();
  const std::size_t faces = h.base().face_count(), stride = static_cast<std::size_t>(data.levels) + 1;
  data.omitted = face_details(h, coefficients, class_weights);
  data.lo.resize(faces);
  data.hi.resize(faces);
  data.axis.resize(faces);
  data.spread.resize(faces);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f < r.end(); ++f) {
      constexpr double inf = std::numeric_limits<double>::infinity();
      Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
      for_each_fine_point(h, f, [&](std::size_t v) {
        lo = component_min(lo, fine[v]);
        hi = component_max(hi, fine[v]);
        return true;
      });
      data.lo[f] = lo;
      data.hi[f] = hi;
      normal_cone(h, f, fine, data.axis[f], data.spread[f]);
      // Detail per level into what each level leaves out: omitted[l] = sum over m > l.
      double* row = data.omitted.data() + f * stride;
      double sum = 0;
      for (int l = data.levels; l >= 0; --l) {
        const double here = row[l];
        row[l] = sum;
        sum += here;
      }
    }
  });
  return data;
}

constexpr int kOutsideFrustum = -1, kFacingAway = -2;

// Whether every finest face of f faces away from the camera at every point
// of f's box: the angle between the cone's axis and the direction to the
// box's centre, plus the cone's spread, plus the angle the box's bounding
// sphere subtends, stays below 90 degrees.
bool facing_away(const FaceViewData& data, std::size_t f, const Vec3& eye) {
  const Vec3 centre = (data.lo[f] + data.hi[f]) * 0.5, to_centre = centre - eye;
  const double distance = norm(to_centre), radius = norm(data.hi[f] - data.lo[f]) * 0.5;
  if (!(distance > radius)) return false;
  const double to_axis = std::acos(std::clamp(dot(data.axis[f], to_centre) / distance, -1.0, 1.0));
  return to_axis + data.spread[f] + std::asin(radius / distance) < std::acos(0.0);
}

// Face f's level for the camera (or kOutsideFrustum, kFacingAway: level 0).
int face_level(const FaceViewData& data, std::size_t f, const Camera& camera, double pixel_error,
               BackFaces back_faces) {
  if (camera.box_outside(data.lo[f], data.hi[f])) return kOutsideFrustum;
  if (back_faces == BackFaces::Cull && facing_away(data, f, camera.position)) return kFacingAway;
  const double distance = norm(camera.position - clamp_to_box(camera.position, data.lo[f], data.hi[f]));
  const double scale = distance > 0 ? camera.pixels_per_unit(distance) : std::numeric_limits<double>::infinity();
  // The coarsest level whose omitted detail stays within the pixel error.
  const double* omitted = data.omitted.data() + f * (static_cast<std::size_t>(data.levels) + 1);
  int level = 0;
  while (level < data.levels && !(omitted[level] * scale <= pixel_error)) ++level;
  return level;
}

void check_decode(const IswDecoded& decoded) {
  if (!decoded.hierarchy)
    throw Error(ErrorKind::InvalidArgument, decoded.patch ? "a view refiner needs the whole hierarchy (ViewScope::Whole)"
                                                          : "a view decode needs a decoded file");
  if (decoded.class_weights.size() != static_cast<std::size_t>(1 + 2 * decoded.hierarchy->levels()) ||
      decoded.coefficients.size() < decoded.hierarchy->fine_vertex_count())
    throw Error(ErrorKind::InvalidArgument, "a view decode needs the file's coefficients and class weights");
}

void check_camera_and_error(const Camera& camera, double pixel_error) {
  if (!(pixel_error > 0) || !std::isfinite(pixel_error))
    throw Error(ErrorKind::InvalidArgument, "the pixel error must be a positive number");
  check_camera(camera);
}

void check_view(const IswDecoded& decoded, const Camera& camera, double pixel_error) {
  check_decode(decoded);
  check_camera_and_error(camera, pixel_error);
}

// Every base face's level into `out` (culled faces at 0, counted).
void levels_for(const FaceViewData& data, const Camera& camera, double pixel_error, BackFaces back_faces,
                ViewLevels& out) {
  out.levels.assign(data.lo.size(), 0);
  std::vector<std::int8_t> culled(out.levels.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.levels.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f < r.end(); ++f) {
      const int level = face_level(data, f, camera, pixel_error, back_faces);
      culled[f] = static_cast<std::int8_t>(std::min(level, 0));
      out.levels[f] = std::max(level, 0);
    }
  });
  out.culled = static_cast<std::size_t>(std::count(culled.begin(), culled.end(), kOutsideFrustum));
  out.back_facing = static_cast<std::size_t>(std::count(culled.begin(), culled.end(), kFacingAway));
}

}  // namespace

ViewLevels view_face_levels(const IswDecoded& decoded, const std::vector<Vec3>& fine, const Camera& camera,
                            double pixel_error, BackFaces back_faces) {
  check_view(decoded, camera, pixel_error);
  if (fine.size() < decoded.hierarchy->fine_vertex_count())
    throw Error(ErrorKind::InvalidArgument, "a view decode needs the fine control points");
  ViewLevels out;
  levels_for(face_view_data(*decoded.hierarchy, decoded.coefficients, decoded.class_weights, fine), camera,
             pixel_error, back_faces, out);
  return out;
}

struct ViewRefiner::Data {
  std::shared_ptr<const SubdivisionHierarchy> hierarchy;
  std::vector<Vec3> points;
  FaceViewData faces;
  ViewLevels current;
};

ViewRefiner::ViewRefiner(const IswDecoded& decoded) : data_(std::make_unique<Data>()) {
  check_decode(decoded);
  data_->hierarchy = decoded.hierarchy;
  data_->points = decoded.coefficients;
  synthesize(*decoded.hierarchy, data_->points);
  data_->points.resize(decoded.hierarchy->fine_vertex_count());
  data_->faces = face_view_data(*decoded.hierarchy, decoded.coefficients, decoded.class_weights, data_->points);
  data_->current.levels.assign(decoded.hierarchy->base().face_count(), 0);
}

ViewRefiner::~ViewRefiner() = default;
ViewRefiner::ViewRefiner(ViewRefiner&&) noexcept = default;
ViewRefiner& ViewRefiner::operator=(ViewRefiner&&) noexcept = default;

std::vector<std::uint32_t> ViewRefiner::set_view(const Camera& camera, double pixel_error, BackFaces back_faces) {
  check_camera_and_error(camera, pixel_error);
  ViewLevels next;
  levels_for(data_->faces, camera, pixel_error, back_faces, next);
  // The faces whose level changed, and their neighbours across base edges
  // (their transitions change).
  const SubdivisionHierarchy& h = *data_->hierarchy;
  std::vector<std::uint8_t> dirty(next.levels.size(), 0);
  for (std::size_t f = 0; f < next.levels.size(); ++f) {
    if (next.levels[f] == data_->current.levels[f]) continue;
    dirty[f] = 1;
    if (h.levels() == 0) continue;
    const RefinementStep& s = h.step(1);
    for (std::uint32_t k = s.face_offsets[f]; k < s.face_offsets[f + 1]; ++k) {
      const std::uint32_t edge = s.face_edges[k] - s.first_edge_vertex();
      for (int side = 0; side < 2; ++side) dirty[s.edge_faces[2 * std::size_t{edge} + side] - s.first_face_vertex()] = 1;
    }
  }
  data_->current = std::move(next);
  std::vector<std::uint32_t> changed;
  for (std::size_t f = 0; f < dirty.size(); ++f)
    if (dirty[f]) changed.push_back(static_cast<std::uint32_t>(f));
  return changed;
}

const ViewLevels& ViewRefiner::levels() const { return data_->current; }

const std::vector<Vec3>& ViewRefiner::points() const { return data_->points; }

void ViewRefiner::patch(std::size_t base_face, std::vector<std::uint32_t>& offsets,
                        std::vector<std::uint32_t>& corners) const {
  adaptive_patch(*data_->hierarchy, data_->current.levels, base_face, offsets, corners);
}

PolygonMesh ViewRefiner::mesh() const {
  return adaptive_control_mesh(*data_->hierarchy, data_->current.levels, data_->points);
}

namespace {

// view_mesh() of a decode over a patch (IswDecodeOptions::ViewScope::Patch):
// the levels of the patch's exact faces (the others lie outside the
// frustum: level 0), the faces in view at their fine points, the others at
// the base control points.
PolygonMesh patch_view_mesh(const IswDecoded& decoded, const Camera& camera, double pixel_error, ViewLevels* report,
                            BackFaces back_faces) {
  const RegionPatch& p = *decoded.patch;
  if (!p.patch) {  // no face may lie in the frustum: the base mesh
    if (report) {
      *report = ViewLevels{};
      report->levels.assign(decoded.base.face_count(), 0);
      report->culled = decoded.base.face_count();
    }
    return decoded.base;
  }
  const SubdivisionHierarchy& h = p.patch->hierarchy();
  if (decoded.class_weights.size() != static_cast<std::size_t>(1 + 2 * h.levels()))
    throw Error(ErrorKind::InvalidArgument, "a view decode needs the file's class weights");
  std::vector<Vec3> fine = p.coefficients;
  synthesize(h, fine);
  const FaceViewData data = face_view_data(h, p.coefficients, decoded.class_weights, fine);
  ViewLevels levels;
  levels.levels.assign(h.base().face_count(), 0);
  std::size_t seeds = 0;
  for (std::size_t f = 0; f < levels.levels.size(); ++f) {
    if (!p.exact[f]) continue;
    ++seeds;
    const int level = face_level(data, f, camera, pixel_error, back_faces);
    levels.culled += level == kOutsideFrustum;
    levels.back_facing += level == kFacingAway;
    levels.levels[f] = std::max(level, 0);
  }
  levels.culled += decoded.base.face_count() - seeds;  // the others lie outside the frustum
  const detail::PatchDomain d{h, &p.patch->entries(), &p.patch->faces(), &p.exact};
  PolygonMesh mesh = detail::patch_mesh(d, decoded.base, decoded.base.positions, decoded.fine_vertices, levels.levels,
                                        fine, detail::BaseCorners::ExactFaces);
  if (report) {  // per base face of the whole mesh
    *report = levels;
    report->levels.assign(decoded.base.face_count(), 0);
    for (std::size_t f = 0; f < levels.levels.size(); ++f) report->levels[p.patch->faces()[f]] = levels.levels[f];
  }
  return mesh;
}

}  // namespace

PolygonMesh view_mesh(const IswDecoded& decoded, const Camera& camera, double pixel_error, ViewLevels* report,
                      BackFaces back_faces) {
  if (decoded.patch) {
    check_camera_and_error(camera, pixel_error);
    return patch_view_mesh(decoded, camera, pixel_error, report, back_faces);
  }
  check_view(decoded, camera, pixel_error);
  ViewRefiner refiner(decoded);
  refiner.set_view(camera, pixel_error, back_faces);
  PolygonMesh mesh = refiner.mesh();
  if (report) *report = refiner.levels();
  return mesh;
}

}  // namespace isowave
