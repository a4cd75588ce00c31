#include "isowave/codec/region.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/codec/importance.h"
#include "isowave/core/error.h"
#include "isowave/transform/adaptive_mesh.h"
#include "isowave/transform/wavelet_transform.h"
#include "patch_mesh.h"

namespace isowave {

using detail::BaseCorners;
using detail::PatchDomain;
using detail::patch_mesh;

namespace {

constexpr std::size_t kGrain = 1 << 15;

template <class Body>
void for_each_index(std::size_t n, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) body(i);
  });
}

// A weight in [1, 2) that depends on the index only: with distinct positive
// weights on the region's points, the transpose's sums cancel to zero only by
// coincidence, never where a point depends on an entry through one path.
double index_weight(std::size_t i, unsigned salt) {
  std::uint64_t x = (std::uint64_t(i) + 1) * 0x9E3779B97F4A7C15ull + salt * 0xBF58476D1CE4E5B9ull;
  x ^= x >> 31;
  x *= 0x94D049BB133111EBull;
  x ^= x >> 29;
  return 1.0 + double(x >> 11) * (1.0 / 9007199254740992.0);
}

// Flags the `count` most important coefficients of `decoded` besides those
// `keep` flags already: in decoded.ranked's order, or with a falloff by
// importance times the Gaussian of their entries' distance (in `fine`) from
// the region (ties by index).
void keep_outside(const IswDecoded& decoded, const std::vector<Vec3>& fine, const RegionOfInterest& region,
                  std::size_t count, std::vector<std::uint8_t>& keep) {
  if (region.falloff <= 0) {
    for (std::size_t r = 0; r < decoded.ranked.size() && count > 0; ++r)
      if (!keep[decoded.ranked[r]]) {
        keep[decoded.ranked[r]] = 1;
        --count;
      }
    return;
  }
  const CoefficientClasses classes(*decoded.hierarchy);
  if (decoded.class_weights.size() != static_cast<std::size_t>(classes.count()))
    throw Error(ErrorKind::InvalidArgument, "region: a decode without its class weights");
  const double s = 2 * region.falloff * region.falloff;
  std::vector<std::pair<double, std::uint32_t>> keyed;
  for (const std::uint32_t k : decoded.ranked) {
    if (keep[k]) continue;
    const double d = region.distance(fine[k]);
    keyed.push_back({-decoded.class_weights[static_cast<std::size_t>(classes.of(k))] * norm(decoded.coefficients[k]) *
                         std::exp(-d * d / s),
                     k});
  }
  count = std::min(count, keyed.size());
  std::nth_element(keyed.begin(), keyed.begin() + static_cast<std::ptrdiff_t>(count), keyed.end());  // pairs: ties by index
  for (std::size_t r = 0; r < count; ++r) keep[keyed[r].second] = 1;
}

}  // namespace

std::vector<std::uint8_t> entries_for_region(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& fine,
                                             const RegionOfInterest& region) {
  const std::size_t n = hierarchy.fine_vertex_count();
  if (fine.size() < n) throw Error(ErrorKind::InvalidArgument, "region: fewer points than the fine level");
  std::vector<std::uint8_t> inside(n);
  for_each_index(n, [&](std::size_t v) { inside[v] = region.contains(fine[v]); });
  return entries_for_points(hierarchy, inside);
}

std::vector<std::uint8_t> entries_for_points(const SubdivisionHierarchy& hierarchy,
                                             const std::vector<std::uint8_t>& points) {
  const std::size_t n = hierarchy.fine_vertex_count();
  if (points.size() < n) throw Error(ErrorKind::InvalidArgument, "region: fewer flags than the fine level");
  // g: distinct positive weights on the flagged points, then S^T g level by
  // level down to the base and every level's coefficients.
  std::vector<Vec3> g(n);
  for_each_index(n, [&](std::size_t v) {
    if (points[v]) g[v] = {index_weight(v, 1), index_weight(v, 2), index_weight(v, 3)};
  });
  for (int level = hierarchy.levels(); level >= 1; --level) synthesize_level_transpose(hierarchy, level, g);
  std::vector<std::uint8_t> needed(n);
  for_each_index(n, [&](std::size_t k) { needed[k] = g[k].x != 0 || g[k].y != 0 || g[k].z != 0; });
  return needed;
}

namespace {

// Flags the fine control points (of the exact faces) inside the region.
std::vector<std::uint8_t> points_inside(const PatchDomain& d, const std::vector<Vec3>& fine,
                                        const RegionOfInterest& region) {
  std::vector<std::uint8_t> inside(d.h.fine_vertex_count(), 0);
  if (!d.exact) {
    for_each_index(inside.size(), [&](std::size_t v) { inside[v] = region.contains(fine[v]); });
    return inside;
  }
  for (std::size_t f = 0; f < d.h.base().face_count(); ++f)
    if (d.is_exact(f)) for_each_fine_point(d.h, f, [&](std::size_t v) { return inside[v] = region.contains(fine[v]), true; });
  return inside;
}

// reconstruct_region() over `d`; `keep_more` flags what is kept besides
// what the region needs, given the complete decode's fine points.
template <class KeepMore>
RegionReconstruction reconstruct(const PatchDomain& d, const std::vector<Vec3>& coefficients,
                                 const RegionOfInterest& region, const KeepMore& keep_more) {
  const SubdivisionHierarchy& h = d.h;
  const std::size_t n = h.fine_vertex_count(), base = h.vertex_count(0);
  RegionReconstruction out;
  // 1. The complete decode, to know which fine points lie inside.
  std::vector<Vec3> data = coefficients;
  synthesize(h, data);
  std::vector<std::uint8_t> keep = points_inside(d, data, region);
  out.inside_points = static_cast<std::size_t>(std::count(keep.begin(), keep.end(), 1));
  // 2. What those points depend on, and what else is kept.
  keep = entries_for_points(h, keep);
  std::fill(keep.begin(), keep.begin() + static_cast<std::ptrdiff_t>(base), std::uint8_t{1});
  for (std::size_t k = base; k < n; ++k) out.region_coefficients += keep[k] && squared_norm(coefficients[k]) > 0;
  keep_more(data, keep);
  // 3. The reconstruction from the kept entries, in the same buffer.
  for (std::size_t k = 0; k < n; ++k) {
    data[k] = keep[k] ? coefficients[k] : Vec3{};
    out.kept_coefficients += k >= base && keep[k] && squared_norm(data[k]) > 0;
  }
  synthesize(h, data);
  data.resize(n);
  out.fine = std::move(data);
  return out;
}

// Per face of `d`: the finest level where one of its (exact) fine control
// points lies inside the region, else 0.
std::vector<int> inside_levels(const PatchDomain& d, const std::vector<Vec3>& fine, const RegionOfInterest& region) {
  std::vector<int> levels(d.h.base().face_count(), 0);
  if (d.h.levels() == 0) return levels;
  for_each_index(levels.size(), [&](std::size_t f) {
    const bool outside = !d.is_exact(f) ||
                         for_each_fine_point(d.h, f, [&](std::size_t v) { return !region.contains(fine[v]); });
    if (!outside) levels[f] = d.h.levels();
  });
  return levels;
}

}  // namespace

RegionReconstruction reconstruct_region(const IswDecoded& decoded, const RegionOfInterest& region,
                                        std::size_t outside_keep) {
  if (!decoded.hierarchy) throw Error(ErrorKind::InvalidArgument, "reconstruct needs a complete decode");
  return reconstruct(PatchDomain{*decoded.hierarchy}, decoded.coefficients, region,
                     [&](const std::vector<Vec3>& fine, std::vector<std::uint8_t>& keep) {
                       keep_outside(decoded, fine, region, outside_keep, keep);
                     });
}

PolygonMesh region_mesh(const IswDecoded& decoded, const RegionOfInterest& region, std::size_t outside_keep,
                        RegionReconstruction* counts) {
  if (decoded.patch && outside_keep > 0)
    throw Error(ErrorKind::InvalidArgument, "region: a region decode keeps nothing outside the region");
  if (!decoded.patch && !decoded.hierarchy) throw Error(ErrorKind::InvalidArgument, "region: not a decoded file");
  const RegionPatch* p = decoded.patch.get();
  if (p && !p->patch) {  // nothing meets the region: the base mesh
    if (counts) *counts = RegionReconstruction{};
    return decoded.base;
  }
  const PatchDomain d = p ? PatchDomain{p->patch->hierarchy(), &p->patch->entries(), &p->patch->faces(), &p->exact}
                           : PatchDomain{*decoded.hierarchy};
  const std::vector<Vec3>& coefficients = p ? p->coefficients : decoded.coefficients;
  RegionReconstruction r = reconstruct(d, coefficients, region, [&](const std::vector<Vec3>& fine, std::vector<std::uint8_t>& keep) {
    if (outside_keep > 0) keep_outside(decoded, fine, region, outside_keep, keep);
  });
  PolygonMesh mesh;
  if (outside_keep > 0) {
    mesh = decoded.hierarchy->control_mesh(decoded.levels, std::move(r.fine));
  } else {
    const PolygonMesh& base = p ? decoded.base : decoded.hierarchy->base();
    const std::vector<Vec3>& base_points = p ? decoded.base.positions : decoded.coefficients;
    const std::size_t whole = p ? decoded.fine_vertices : decoded.hierarchy->fine_vertex_count();
    mesh = patch_mesh(d, base, base_points, whole, inside_levels(d, r.fine, region), r.fine,
                              BaseCorners::RefinedFaces);
  }
  if (counts) {
    *counts = std::move(r);
    counts->fine.clear();
  }
  return mesh;
}

std::vector<int> region_face_levels(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& fine,
                                    const RegionOfInterest& region, int outside_level) {
  const int levels = hierarchy.levels();
  std::vector<int> face_levels(hierarchy.base().face_count(), outside_level);
  if (levels == 0) {
    std::fill(face_levels.begin(), face_levels.end(), 0);
    return face_levels;
  }
  for_each_index(face_levels.size(), [&](std::size_t f) {
    const bool outside = for_each_fine_point(hierarchy, f, [&](std::size_t v) { return !region.contains(fine[v]); });
    if (!outside) face_levels[f] = levels;
  });
  return face_levels;
}

}  // namespace isowave
