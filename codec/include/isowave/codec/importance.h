#pragma once
// Coefficient importance and truncation (paper Sec. 5; Staadt et al.'s
// coefficient oracles). The bicubic wavelet basis is not orthogonal, so a
// coefficient's effect on the reconstruction is its magnitude times the size
// of its synthesized wavelet at the finest level. That size is estimated per
// class (level and vertex type) as the root-mean-square L2 norm, over the
// fine control points, of the class's wavelets: with random signs s_i on every
// coefficient i of a class, E ||synthesis(s)||^2 = sum_i ||psi_i||^2, so one
// synthesis per class gives the class mean exactly in expectation.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"

namespace isowave {

// The classes of the coarse-to-fine array: 0 for base control points, then
// 1 + 2 (level - 1) for f details and 2 + 2 (level - 1) for e details of
// `level`; 1 + 2 L classes, each a contiguous index range. They follow from
// the counts alone, so a decoder lays them out from a file's counts while the
// hierarchy is still being built. Small and cheap to copy (no allocation).
class CoefficientClasses {
 public:
  explicit CoefficientClasses(const SubdivisionHierarchy& hierarchy);
  // vertex_counts[l]: control points of levels 0..l together (l = 0..levels,
  // ascending); parent_faces[l - 1]: the faces of level l - 1, whose f details
  // open level l. Precondition: 0 <= levels <= SubdivisionHierarchy::kMaxLevels.
  CoefficientClasses(const std::size_t* vertex_counts, const std::size_t* parent_faces, int levels);

  int count() const { return 1 + 2 * levels_; }
  std::size_t base() const { return vertex_counts_[0]; }
  std::size_t fine() const { return vertex_counts_[static_cast<std::size_t>(levels_)]; }
  // [first, second) of class c, 0 <= c < count().
  std::pair<std::size_t, std::size_t> range(int c) const;
  // Class of entry `index` < fine(). O(log levels).
  int of(std::size_t index) const;
  bool operator==(const CoefficientClasses& other) const;

 private:
  int levels_ = 0;
  std::array<std::size_t, SubdivisionHierarchy::kMaxLevels + 1> vertex_counts_{};
  std::array<std::size_t, SubdivisionHierarchy::kMaxLevels> parent_faces_{};
};

// CoefficientClasses(hierarchy).of(index), .count() and .range(class_index).
int coefficient_class(const SubdivisionHierarchy& hierarchy, std::size_t index);
int coefficient_class_count(const SubdivisionHierarchy& hierarchy);
// The entries of a class form one contiguous index range [first, second).
std::pair<std::size_t, std::size_t> coefficient_class_range(const SubdivisionHierarchy& hierarchy, int class_index);

// Per class: root-mean-square fine-level L2 norm of one unit basis function
// (scaling function for class 0, wavelets otherwise). Deterministic (fixed
// random seed). Cost: 1 + 2 L syntheses.
std::vector<double> wavelet_norms(const SubdivisionHierarchy& hierarchy);

// Importance of every entry: weight of its class times its magnitude (world
// units). Base control points get +infinity (always kept). Cost: O(entries).
std::vector<double> importance(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                               const std::vector<double>& class_weights);

// Zeroes every wavelet coefficient except the `keep` most important (ties by
// index); base control points are never dropped. With unit weights this is
// selection by raw magnitude. Cost: O(entries) (a selection, not a sort).
void keep_most_important(const SubdivisionHierarchy& hierarchy, std::vector<Vec3>& coefficients,
                         const std::vector<double>& class_weights, std::size_t keep);

// The importance measures a coefficient limit can keep by (Staadt, Gross and
// Weber, Sec. 2.2, "global oracles"), all over the same decoded coefficients.
enum class Oracle {
  Weighted,   // class weight x magnitude (the file's own ranking; the default)
  Magnitude,  // magnitude alone: the L2-optimal choice for an orthogonal basis only
  Greedy,     // rejection by conditional approximation error (keep_greedy)
};

// The oracle called `name` ("weighted", "magnitude" or "greedy"); else
// Error(InvalidArgument) naming the choices.
Oracle oracle_from_name(const std::string& name);

// Staadt, Gross and Weber's greedy oracle (Sec. 2.2, Eq. 7): starting from
// every non-zero wavelet coefficient, rejects those whose rejection adds the
// least error over the fine control points given what was rejected before,
// until `keep` remain, and zeroes the others in `coefficients` (base control
// points are never rejected). The error of rejecting c_k after the set R is
// |c_k|^2 ||psi_k||^2 + 2 c_k . (S^T S c_R)_k, S the synthesis to the fine
// control points, exactly: ||psi_k||^2 from wavelet_squared_norms()
// (transform/wavelet_transform.h), the cross terms from a synthesis and its
// transpose. The paper rejects one coefficient per update, O(n^2); this rejects in
// batches, each half of what is left to reject but at least
// smallest_batch x keep (> 0; at least one), re-scoring after each: a batch's
// own cross terms are not seen. Returns the kept coefficients, largest
// rejection error (in the last round) first. Cost: wavelet_squared_norms(),
// and about log2(rejected / (smallest_batch x keep)) + 2 syntheses and
// transposed syntheses, O(entries) each.
std::vector<std::uint32_t> keep_greedy(const SubdivisionHierarchy& hierarchy, std::vector<Vec3>& coefficients,
                                       std::size_t keep, double smallest_batch = 1.0 / 64);

// Number of wavelet coefficients kept at `percent` of full resolution, counted
// as the paper does: the total is the fine control point count (base vertices
// plus all coefficients) and the base mesh alone is the smallest choice.
std::size_t coefficients_for_percent(const SubdivisionHierarchy& hierarchy, double percent);
// The same from the fine and base control point counts alone.
std::size_t coefficients_for_percent(std::size_t fine_vertices, std::size_t base_vertices, double percent);

// RMS and maximum of the distances between corresponding points (the
// points' units), over the first `count` of each; precondition: both hold at
// least `count`. Cost: O(count).
struct PointErrors {
  double rms = 0;
  double max = 0;
};
PointErrors point_errors(const std::vector<Vec3>& a, const std::vector<Vec3>& b, std::size_t count);

}  // namespace isowave
