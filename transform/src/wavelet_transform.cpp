#include "isowave/transform/wavelet_transform.h"

#include <algorithm>
#include <cassert>


#include "isowave/core/error.h"
#include "isowave/transform/lifting_rules.h"
#include "level_checks.h"

namespace isowave {
namespace {

using lifting::Rule;
using lifting::Step;
using lifting::VertexType;

enum class Direction { Synthesis, Analysis };

// target <- self*target + sum  (synthesis) or (target - sum)/self (analysis).
template <Direction D>
inline Vec3 apply(const Rule& rule, const Vec3& target, const Vec3& weighted_sum) {
  if constexpr (D == Direction::Synthesis) return rule.self * target + weighted_sum;
  else return (target - weighted_sum) * (1.0 / rule.self);
}

// Average of data[indices[begin..end)].
inline Vec3 average(const Vec3* data, const std::uint32_t* indices, std::uint32_t begin, std::uint32_t end) {
  Vec3 sum;
  for (std::uint32_t k = begin; k < end; ++k) sum += data[indices[k]];
  return sum * (1.0 / static_cast<double>(end - begin));
}

// The v steps gather each vertex's f and e neighbours from scattered places
// of arrays of hundreds of megabytes: asking for those of the vertex this
// many ahead hides much of the memory latency (the e and f steps read
// neighbours that lie close together and gain nothing).
constexpr std::uint32_t kPrefetchAhead = 12;

inline void prefetch(const Vec3* data, const std::uint32_t* indices, std::uint32_t begin, std::uint32_t end) {
  for (std::uint32_t k = begin; k < end; ++k) __builtin_prefetch(data + indices[k]);
}

template <Direction D>
void lift_e_vertices(const RefinementStep& s, Vec3* data, const Step& step) {
  const Rule& r = step.smooth;
  const std::uint32_t first = s.first_edge_vertex();
  detail::for_lifting_range(s.parent_edge_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t e = begin; e < end; ++e) {
      if (step.skipped_on_sharp_edges && !s.edge_smooth[e]) continue;
      Vec3 sum;
      if (r.f != 0) sum += (0.5 * r.f) * (data[s.edge_faces[2 * e]] + data[s.edge_faces[2 * e + 1]]);
      if (r.v != 0) sum += (0.5 * r.v) * (data[s.edge_vertices[2 * e]] + data[s.edge_vertices[2 * e + 1]]);
      data[first + e] = apply<D>(r, data[first + e], sum);
    }
  });
}

template <Direction D>
void lift_f_vertices(const RefinementStep& s, Vec3* data, const Step& step) {
  const Rule& r = step.smooth;
  const std::uint32_t first = s.first_face_vertex();
  detail::for_lifting_range(s.parent_face_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t f = begin; f < end; ++f) {
      const std::uint32_t row = s.face_offsets[f], row_end = s.face_offsets[f + 1];
      Vec3 sum;
      if (r.v != 0) sum += r.v * average(data, s.face_vertices.data(), row, row_end);
      if (r.e != 0) sum += r.e * average(data, s.face_edges.data(), row, row_end);
      data[first + f] = apply<D>(r, data[first + f], sum);
    }
  });
}

template <Direction D>
void lift_v_vertices(const RefinementStep& s, Vec3* data, const Step& step) {
  const Rule& r = step.smooth;
  detail::for_lifting_range(s.parent_vertex_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t v = begin; v < end; ++v) {
      if (v + kPrefetchAhead < end) {
        const std::uint32_t ahead = v + kPrefetchAhead;
        if (r.f != 0) prefetch(data, s.vertex_faces.data(), s.vertex_face_offsets[ahead], s.vertex_face_offsets[ahead + 1]);
        if (r.e != 0) prefetch(data, s.vertex_edges.data(), s.vertex_edge_offsets[ahead], s.vertex_edge_offsets[ahead + 1]);
      }
      if (s.vertex_rule[v] != VertexRule::Smooth) continue;
      Vec3 sum;
      if (r.f != 0) sum += r.f * average(data, s.vertex_faces.data(), s.vertex_face_offsets[v], s.vertex_face_offsets[v + 1]);
      if (r.e != 0) sum += r.e * average(data, s.vertex_edges.data(), s.vertex_edge_offsets[v], s.vertex_edge_offsets[v + 1]);
      data[v] = apply<D>(r, data[v], sum);
    }
  });
  const Rule& c = step.crease;
  const auto creases = static_cast<std::uint32_t>(s.crease_vertices.size());
  detail::for_lifting_range(creases, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::uint32_t v = s.crease_vertices[k];
      const Vec3 sum = (0.5 * c.e) * (data[s.crease_edges[2 * k]] + data[s.crease_edges[2 * k + 1]]);
      data[v] = apply<D>(c, data[v], sum);
    }
  });
}

template <Direction D>
void lift(const RefinementStep& s, Vec3* data, const Step& step) {
  switch (step.target) {
    case VertexType::E: lift_e_vertices<D>(s, data, step); break;
    case VertexType::F: lift_f_vertices<D>(s, data, step); break;
    case VertexType::V: lift_v_vertices<D>(s, data, step); break;
  }
}

}  // namespace

void analyze(const SubdivisionHierarchy& hierarchy, std::vector<Vec3>& data) {
  detail::require_size(hierarchy, data, hierarchy.levels());
  for (int level = hierarchy.levels(); level >= 1; --level) {
    const RefinementStep& s = hierarchy.step(level);
    for (auto step = lifting::kSynthesisSteps.rbegin(); step != lifting::kSynthesisSteps.rend(); ++step)
      lift<Direction::Analysis>(s, data.data(), *step);
  }
}

void synthesize(const SubdivisionHierarchy& hierarchy, std::vector<Vec3>& data, int to_level) {
  if (to_level < 0) to_level = hierarchy.levels();
  if (to_level > hierarchy.levels())
    throw Error(ErrorKind::InvalidArgument, "level " + std::to_string(to_level) + " exceeds the hierarchy's " +
                                                std::to_string(hierarchy.levels()) + " levels");
  detail::require_size(hierarchy, data, to_level);
  for (int level = 1; level <= to_level; ++level) {
    const RefinementStep& s = hierarchy.step(level);
    for (const Step& step : lifting::kSynthesisSteps) lift<Direction::Synthesis>(s, data.data(), step);
  }
}

void synthesize_level(const SubdivisionHierarchy& hierarchy, int level, std::vector<Vec3>& data) {
  detail::require_level(hierarchy, level);
  detail::require_size(hierarchy, data, level);
  const RefinementStep& s = hierarchy.step(level);
  for (const Step& step : lifting::kSynthesisSteps) lift<Direction::Synthesis>(s, data.data(), step);
}

void subdivide_level(const SubdivisionHierarchy& hierarchy, int level, std::vector<Vec3>& data) {
  detail::require_level(hierarchy, level);
  detail::require_size(hierarchy, data, level - 1);
  data.resize(std::max(data.size(), hierarchy.vertex_count(level)));
  std::fill(data.begin() + static_cast<std::ptrdiff_t>(hierarchy.vertex_count(level - 1)),
            data.begin() + static_cast<std::ptrdiff_t>(hierarchy.vertex_count(level)), Vec3{});
  synthesize_level(hierarchy, level, data);
}

std::vector<Vec3> subdivide(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& base_points, int to_level) {
  if (to_level < 0) to_level = hierarchy.levels();
  detail::require_size(hierarchy, base_points, 0);
  std::vector<Vec3> data(base_points.begin(), base_points.begin() + static_cast<std::ptrdiff_t>(hierarchy.vertex_count(0)));
  for (int level = 1; level <= to_level; ++level) subdivide_level(hierarchy, level, data);
  data.resize(hierarchy.vertex_count(to_level));
  return data;
}

}  // namespace isowave
