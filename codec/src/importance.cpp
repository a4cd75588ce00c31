#include "isowave/codec/importance.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {

CoefficientClasses::CoefficientClasses(const SubdivisionHierarchy& hierarchy) : levels_(hierarchy.levels()) {
  for (int l = 0; l <= levels_; ++l) vertex_counts_[static_cast<std::size_t>(l)] = hierarchy.vertex_count(l);
  for (int l = 1; l <= levels_; ++l) parent_faces_[static_cast<std::size_t>(l - 1)] = hierarchy.step(l).parent_face_count;
}

CoefficientClasses::CoefficientClasses(const std::size_t* vertex_counts, const std::size_t* parent_faces, int levels)
    : levels_(levels) {
  assert(levels >= 0 && levels <= SubdivisionHierarchy::kMaxLevels);
  std::copy(vertex_counts, vertex_counts + levels + 1, vertex_counts_.begin());
  std::copy(parent_faces, parent_faces + levels, parent_faces_.begin());
}

std::pair<std::size_t, std::size_t> CoefficientClasses::range(int c) const {
  assert(c >= 0 && c < count());
  if (c == 0) return {0, vertex_counts_[0]};
  const auto level = static_cast<std::size_t>(1 + (c - 1) / 2);
  const std::size_t first_face = vertex_counts_[level - 1], first_edge = first_face + parent_faces_[level - 1];
  return (c - 1) % 2 == 0 ? std::make_pair(first_face, first_edge) : std::make_pair(first_edge, vertex_counts_[level]);
}

int CoefficientClasses::of(std::size_t index) const {
  const auto end = vertex_counts_.begin() + levels_ + 1;
  const auto level = static_cast<std::size_t>(std::upper_bound(vertex_counts_.begin(), end, index) - vertex_counts_.begin());
  if (level == 0) return 0;
  const bool is_edge = index >= vertex_counts_[level - 1] + parent_faces_[level - 1];
  return 1 + 2 * static_cast<int>(level - 1) + (is_edge ? 1 : 0);
}

bool CoefficientClasses::operator==(const CoefficientClasses& other) const {
  return levels_ == other.levels_ && vertex_counts_ == other.vertex_counts_ && parent_faces_ == other.parent_faces_;
}

int coefficient_class(const SubdivisionHierarchy& hierarchy, std::size_t index) {
  return CoefficientClasses(hierarchy).of(index);
}

int coefficient_class_count(const SubdivisionHierarchy& hierarchy) { return 1 + 2 * hierarchy.levels(); }

std::pair<std::size_t, std::size_t> coefficient_class_range(const SubdivisionHierarchy& hierarchy, int class_index) {
  return CoefficientClasses(hierarchy).range(class_index);
}

std::vector<double> wavelet_norms(const SubdivisionHierarchy& hierarchy) {
  // Synthesis acts on x, y and z alike and independently, so three classes
  // share one synthesis, one per component: each class sees exactly the
  // arithmetic of a synthesis of its own (the same norms, a third of the cost).
  const int classes = coefficient_class_count(hierarchy);
  std::vector<double> norms(static_cast<std::size_t>(classes), 1.0);
  std::vector<Vec3> data;
  std::mt19937 rng(12345);
  for (int group = 0; group < classes; group += 3) {
    const int group_end = std::min(classes, group + 3);
    // Fresh pages for each synthesis would cost more than the fill.
    if (data.empty()) reserve_fresh_on_huge_pages(data, hierarchy.fine_vertex_count());
    data.assign(hierarchy.fine_vertex_count(), Vec3{});
    for (int c = group; c < group_end; ++c) {
      const auto [first, last] = coefficient_class_range(hierarchy, c);
      double Vec3::*component = c == group ? &Vec3::x : (c == group + 1 ? &Vec3::y : &Vec3::z);
      for (std::size_t i = first; i < last; ++i) data[i].*component = (rng() & 1) ? 1.0 : -1.0;
    }
    synthesize(hierarchy, data);
    // Sums in point order, as one synthesis per class would add them.
    double sums[3] = {0, 0, 0};
    for (const Vec3& p : data) {
      sums[0] += p.x * p.x;
      sums[1] += p.y * p.y;
      sums[2] += p.z * p.z;
    }
    for (int c = group; c < group_end; ++c) {
      const auto [first, last] = coefficient_class_range(hierarchy, c);
      if (last > first)
        norms[static_cast<std::size_t>(c)] = std::sqrt(sums[c - group] / static_cast<double>(last - first));
    }
  }
  return norms;
}

std::vector<double> importance(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& coefficients,
                               const std::vector<double>& class_weights) {
  std::vector<double> result(hierarchy.fine_vertex_count());
  for (int c = 0; c < coefficient_class_count(hierarchy); ++c) {
    const auto [first, last] = coefficient_class_range(hierarchy, c);
    for (std::size_t i = first; i < last; ++i)
      result[i] = c == 0 ? std::numeric_limits<double>::infinity()
                         : class_weights[static_cast<std::size_t>(c)] * norm(coefficients[i]);
  }
  return result;
}

void keep_most_important(const SubdivisionHierarchy& hierarchy, std::vector<Vec3>& coefficients,
                         const std::vector<double>& class_weights, std::size_t keep) {
  const std::size_t base = hierarchy.vertex_count(0);
  const std::size_t total = hierarchy.fine_vertex_count() - base;
  if (keep >= total) return;
  const std::vector<double> weight = importance(hierarchy, coefficients, class_weights);
  std::vector<std::uint32_t> order(total);
  std::iota(order.begin(), order.end(), static_cast<std::uint32_t>(base));
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return weight[a] > weight[b] || (weight[a] == weight[b] && a < b); });
  for (std::size_t k = keep; k < total; ++k) coefficients[order[k]] = Vec3{};
}

Oracle oracle_from_name(const std::string& name) {
  if (name == "weighted") return Oracle::Weighted;
  if (name == "magnitude") return Oracle::Magnitude;
  if (name == "greedy") return Oracle::Greedy;
  throw Error(ErrorKind::InvalidArgument, "the oracle must be weighted, magnitude or greedy, got '" + name + "'");
}

std::size_t coefficients_for_percent(const SubdivisionHierarchy& hierarchy, double percent) {
  return coefficients_for_percent(hierarchy.fine_vertex_count(), hierarchy.vertex_count(0), percent);
}

std::size_t coefficients_for_percent(std::size_t fine_vertices, std::size_t base_vertices, double percent) {
  if (!(percent >= 0 && percent <= 100))
    throw Error(ErrorKind::InvalidArgument, "percent must be in 0..100, got " + std::to_string(percent));
  const double total = static_cast<double>(fine_vertices);
  const double wanted = std::round(total * percent / 100.0) - static_cast<double>(base_vertices);
  return wanted <= 0 ? 0 : std::min(static_cast<std::size_t>(wanted), fine_vertices - base_vertices);
}

PointErrors point_errors(const std::vector<Vec3>& a, const std::vector<Vec3>& b, std::size_t count) {
  PointErrors e;
  if (count == 0) return e;
  double sum = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const double d = norm(a[i] - b[i]);
    sum += d * d;
    e.max = std::max(e.max, d);
  }
  e.rms = std::sqrt(sum / static_cast<double>(count));
  return e;
}

}  // namespace isowave
