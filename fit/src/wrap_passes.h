#pragma once
// The shrink-wrap rooms' entry points for the driver (shrink_wrap.cpp) and
// for one another: the public steps' forms that reuse the driver's buffers
// and its prepared field (prepared_field_values: non-finite samples filled,
// samples enclosed by dropped components mirrored).
// Private to fit/.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "isowave/core/huge_page_vector.h"
#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"
#include "isowave/core/volume.h"
#include "isowave/fit/correction.h"
#include "isowave/fit/fold_repair.h"
#include "isowave/fit/orientation.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/fit/trilinear.h"
#include "isowave/fit/wrap_level_mesh.h"
#include "isowave/fit/wrap_steps.h"
#include "isowave/transform/hierarchy.h"
#include "coverage_pull.h"
#include "wrap_kernels.h"

namespace isowave::wrap {

// wrap_level_mesh.cpp

// make_wrap_level_mesh() into `mesh`, reusing its buffers where they have
// room: the shrink-wrap sizes them for the finest level once, since fresh
// pages are expensive (zeroed by the kernel and, in a virtual machine, often
// backed by the host on first touch).
void fill_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, int level, const std::vector<Vec3>& positions,
                          const Volume& box_volume, double iso, WrapLevelMesh& mesh);
// Room in `mesh` for the finest level of the hierarchy, the large arrays on
// huge pages faulted in on all threads.
void reserve_finest_wrap_level_mesh(const SubdivisionHierarchy& hierarchy, WrapLevelMesh& mesh);

// wrap_steps.cpp

// Every face's unit normal (single precision), `face_normals` resized to the face count.
void compute_face_normals(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, FaceNormals& face_normals);
// Unit average of the normals of the faces around v (zero if undefined).
Vec3 vertex_normal(const WrapLevelMesh& mesh, const FaceNormals& face_normals, std::size_t v);
// Where the relaxation pulls vertex v: the centroid of its two neighbours
// along its boundary curve for a vertex held on one, else of all its
// neighbours; false for a vertex without neighbours.
bool relaxation_centroid(const WrapLevelMesh& mesh, std::size_t v, const std::vector<Vec3>& positions, Vec3& centroid);
// relax() with, optionally, a flag per vertex (tangent_only, may be null): a
// flagged free vertex moves only within the plane normal to its vertex normal
// (the normal part of the move, which on a coarse closed mesh is mostly a
// shrink, is left to the attraction).
void relax_with(const WrapLevelMesh& mesh, const Volume& box_volume, double weight, const std::vector<Vec3>& in,
                std::vector<Vec3>& out, const std::uint8_t* tangent_only);
// attract() with the face-normal buffer supplied by the caller, which reuses
// it across rounds (hundreds of megabytes at the finest level).
AttractionStatistics attract_with(const WrapLevelMesh& mesh, const SignedDistanceField& distance,
                                  const AttractionOptions& options, const std::vector<Vec3>& in,
                                  std::vector<Vec3>& out, FaceNormals& face_normals);

// correction.cpp

// Moves p along the field gradient (within the vertex's box face, if held;
// with `parallel_axis` >= 0 normal to that axis) to where the trilinear field
// equals iso, at most `range` (world units) away. False if there is no
// gradient or no root within range.
bool project_onto_isosurface(const WrapLevelMesh& mesh, const Box& box, const TrilinearGrid& field, double cell,
                             double iso, double range, std::size_t v, const Vec3& p, Vec3& target,
                             int parallel_axis = -1);
// correct_to_isosurface() on a prepared field; with `nearest` (the signed-
// distance field) the from_nearest_point fallback; wide_search_sign 0 (off)
// or unfolded_sign() of the faces' orientation; `surface` and `distance`
// (its signed-distance field) both or neither.
CorrectionStatistics correct_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                  double iso, double max_move_cells, std::vector<Vec3>& positions,
                                  const TrilinearGrid* nearest, double wide_search_sign, const PolygonMesh* surface,
                                  const TrilinearGrid* distance);
// Puts the points the coverage pull moved on level L onto the isosurface (as
// correct_with, `nearest` likewise); a point without a root there, or around
// which more faces fold than at its old place, goes back where it was.
// Returns how many went back.
std::size_t settle_pulled_points(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                 double iso, Orientation orientation, double max_move_cells,
                                 const TrilinearGrid* nearest, const std::vector<PulledPoint>& pulled,
                                 std::vector<Vec3>& positions);

// fold_repair.cpp

// Sets folded[f] to face_folded() for every face and returns their number.
std::size_t find_folded_faces(const WrapLevelMesh& mesh, const TrilinearGrid& field, Orientation orientation,
                              const std::vector<Vec3>& positions, HugePageVector<std::uint8_t>& folded);
// untangle() on a prepared field, moving its selected vertices through
// `moved` (the shrink-wrap lends its second position buffer).
UntangleStatistics untangle_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                 double iso, Orientation orientation, int rounds, double max_move_cells,
                                 std::vector<Vec3>& positions, std::vector<Vec3>& moved);
// unfold() on a prepared field.
UnfoldStatistics unfold_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                             double iso, Orientation orientation, int rounds, double max_move_cells,
                             std::vector<Vec3>& positions);

}  // namespace isowave::wrap
