#pragma once
// Region-of-interest reconstruction (issue #48, item 1; Gross, Staadt and
// Gatti's "magnifying glass" as a hard region): inside a region of the
// world every fine control point equals the full decode's, elsewhere only the
// most important coefficients are kept. The coefficients a region needs are
// found exactly, through the synthesis' transpose: entry k is needed iff some
// fine control point inside the region depends on it (its row of the
// synthesis has a non-zero weight there). The mesh is the fine control mesh
// where the region reaches and, where nothing else is kept, the base faces
// elsewhere, joined crack-free (transform/adaptive_mesh.h).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/region_of_interest.h"
#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"
#include "isowave/transform/patch_hierarchy.h"

namespace isowave {

// Per entry of the coarse-to-fine array (fine_vertex_count() entries): 1 if
// some fine control point of `fine` (the level-L control points, at least
// fine_vertex_count()) inside `region` depends on it; the base entries a
// region point depends on included. Cost: one transposed synthesis, O(fine
// control points), parallel; deterministic.
std::vector<std::uint8_t> entries_for_region(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& fine,
                                             const RegionOfInterest& region);
// The same for the fine control points flagged in `points` (one flag per
// fine control point).
std::vector<std::uint8_t> entries_for_points(const SubdivisionHierarchy& hierarchy,
                                             const std::vector<std::uint8_t>& points);

struct RegionReconstruction {
  std::vector<Vec3> fine;             // level-L control points
  std::size_t inside_points = 0;      // fine control points inside the region
  std::size_t region_coefficients = 0;  // non-zero wavelet coefficients the region needs
  std::size_t kept_coefficients = 0;    // non-zero wavelet coefficients kept in all
};

// The level-L control points of `decoded` (a complete decode ranked by
// importance, IswOrder::Importance) with every coefficient the region needs
// and the `outside_keep` most important others (the ranked order, or with
// region.falloff > 0 importance weighted by the Gaussian of the entry's
// distance from the region: Gross, Staadt and Gatti's magnifying glass);
// base control points always. Inside the region the points equal the
// full decode's up to rounding. Throws Error(InvalidArgument) for a decode
// without a hierarchy. Cost: two syntheses and one transposed synthesis.
RegionReconstruction reconstruct_region(const IswDecoded& decoded, const RegionOfInterest& region,
                                        std::size_t outside_keep);

// Per base face: the finest level where one of its fine control points (of
// `fine`, at least fine_vertex_count()) lies inside `region`, else
// `outside_level` (0..levels()). O(fine control points).
std::vector<int> region_face_levels(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& fine,
                                    const RegionOfInterest& region, int outside_level);

// What a region decode of a 2.2 file holds (IswDecoded::patch, from
// IswDecodeOptions::region) in place of the whole hierarchy and array.
struct RegionPatch {
  std::optional<PatchHierarchy> patch;  // none when no base face meets the region (or the frustum)
  std::vector<Vec3> coefficients;  // per patch entry, world units: base control points, then wavelet coefficients
  std::vector<std::uint8_t> exact;  // per patch base face: 1 if its fine control points equal the complete decode's
};

// What a region decode writes (decode --roi, Python's decode(roi=...)):
// reconstruct_region()'s points as the finest control mesh when coefficients
// are kept outside; with none, the base faces where no fine control point
// lies inside the region stay whole, joined crack-free to the finest faces
// of those where one does (adaptive_patch(); the vertices used only, in the
// order of their entries). A vertex of the finest faces takes its point
// (inside the region the complete decode's); a base vertex of whole faces
// only, its base control point (the base mesh). `decoded` is a complete
// decode, or a region decode's patch (then outside_keep must be 0, else
// Error(InvalidArgument)); both give the same faces, and the same points
// where the patch decoded the base control points. `counts` (optional)
// receives the reconstruction's counts, without its points.
PolygonMesh region_mesh(const IswDecoded& decoded, const RegionOfInterest& region, std::size_t outside_keep,
                        RegionReconstruction* counts = nullptr);

}  // namespace isowave
