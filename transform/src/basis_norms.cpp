// Exact squared norms of the wavelets (wavelet_transform.h,
// wavelet_squared_norms()): each coefficient's unit vector followed through the
// lifting steps of its level and the finer ones, over only the entries it
// reaches. The formulas are wavelet_transform.cpp's, gather for gather, so
// the result is a dense synthesis' to rounding.
#include <algorithm>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "isowave/transform/lifting_rules.h"
#include "isowave/transform/wavelet_transform.h"

namespace isowave {
namespace {

using lifting::Rule;
using lifting::Step;
using lifting::VertexType;

// One thread's sparse vector over the coarse-to-fine array: values (zero
// wherever not touched), the entries touched and one step's targets, each
// listed once.
struct SparseVector {
  std::vector<double> value;
  std::vector<std::uint32_t> touched, targets;
  std::vector<std::uint32_t> mark, target_mark;  // == stamp, target_stamp: listed
  std::uint32_t stamp = 0, target_stamp = 0;

  explicit SparseVector(std::size_t n) : value(n, 0.0), mark(n, 0), target_mark(n, 0) {}
  void touch(std::uint32_t i) {
    if (mark[i] != stamp) {
      mark[i] = stamp;
      touched.push_back(i);
    }
  }
  void target(std::uint32_t i) {
    if (target_mark[i] != target_stamp) {
      target_mark[i] = target_stamp;
      targets.push_back(i);
    }
  }
};

double average(const std::vector<double>& x, const std::vector<std::uint32_t>& indices, std::uint32_t begin,
               std::uint32_t end) {
  double sum = 0;
  for (std::uint32_t k = begin; k < end; ++k) sum += x[indices[k]];
  return sum * (1.0 / static_cast<double>(end - begin));
}

// The entries of `type` one step of that target type may change: those
// touched, and the neighbours the step gathers from a touched entry.
void step_targets(const RefinementStep& s, VertexType type, SparseVector& v) {
  v.targets.clear();
  if (++v.target_stamp == 0) {  // wrapped: every mark is stale again
    std::fill(v.target_mark.begin(), v.target_mark.end(), 0);
    v.target_stamp = 1;
  }
  const std::uint32_t first_face = s.first_face_vertex(), first_edge = s.first_edge_vertex();
  for (const std::uint32_t t : v.touched) {
    if (t < first_face) {  // a v vertex
      if (type == VertexType::V) v.target(t);
      if (type == VertexType::E)
        for (std::uint32_t k = s.vertex_edge_offsets[t]; k < s.vertex_edge_offsets[t + 1]; ++k) v.target(s.vertex_edges[k]);
      if (type == VertexType::F)
        for (std::uint32_t k = s.vertex_face_offsets[t]; k < s.vertex_face_offsets[t + 1]; ++k) v.target(s.vertex_faces[k]);
    } else if (t < first_edge) {  // an f vertex
      const std::uint32_t f = t - first_face;
      if (type == VertexType::F) v.target(t);
      if (type == VertexType::E)
        for (std::uint32_t k = s.face_offsets[f]; k < s.face_offsets[f + 1]; ++k) v.target(s.face_edges[k]);
      if (type == VertexType::V)
        for (std::uint32_t k = s.face_offsets[f]; k < s.face_offsets[f + 1]; ++k) v.target(s.face_vertices[k]);
    } else {  // an e vertex
      const std::uint32_t e = t - first_edge;
      if (type == VertexType::E) v.target(t);
      if (type == VertexType::F) {
        v.target(s.edge_faces[2 * e]);
        v.target(s.edge_faces[2 * e + 1]);
      }
      if (type == VertexType::V) {
        v.target(s.edge_vertices[2 * e]);
        v.target(s.edge_vertices[2 * e + 1]);
      }
    }
  }
}

// One synthesis step (wavelet_transform.cpp's lift_*): every target it may
// change, from the sources it gathers; `crease` maps a v vertex to its row
// of crease_edges (-1: none). A target never gathers its own type, so the
// order of the targets does not matter.
void apply_step(const RefinementStep& s, const Step& step, const std::vector<std::int32_t>& crease, SparseVector& v) {
  step_targets(s, step.target, v);
  std::vector<double>& x = v.value;
  const Rule& r = step.smooth;
  const std::uint32_t first_face = s.first_face_vertex(), first_edge = s.first_edge_vertex();
  for (const std::uint32_t t : v.targets) {
    double self = r.self, sum = 0;
    if (step.target == VertexType::E) {
      const std::uint32_t e = t - first_edge;
      if (step.skipped_on_sharp_edges && !s.edge_smooth[e]) continue;
      if (r.f != 0) sum += (0.5 * r.f) * (x[s.edge_faces[2 * e]] + x[s.edge_faces[2 * e + 1]]);
      if (r.v != 0) sum += (0.5 * r.v) * (x[s.edge_vertices[2 * e]] + x[s.edge_vertices[2 * e + 1]]);
    } else if (step.target == VertexType::F) {
      const std::uint32_t f = t - first_face;
      if (r.v != 0) sum += r.v * average(x, s.face_vertices, s.face_offsets[f], s.face_offsets[f + 1]);
      if (r.e != 0) sum += r.e * average(x, s.face_edges, s.face_offsets[f], s.face_offsets[f + 1]);
    } else if (s.vertex_rule[t] == VertexRule::Smooth) {
      if (r.f != 0) sum += r.f * average(x, s.vertex_faces, s.vertex_face_offsets[t], s.vertex_face_offsets[t + 1]);
      if (r.e != 0) sum += r.e * average(x, s.vertex_edges, s.vertex_edge_offsets[t], s.vertex_edge_offsets[t + 1]);
    } else if (crease[t] >= 0) {
      const auto k = static_cast<std::size_t>(crease[t]);
      self = step.crease.self;
      sum = (0.5 * step.crease.e) * (x[s.crease_edges[2 * k]] + x[s.crease_edges[2 * k + 1]]);
    } else {
      continue;  // a sharp vertex never moves
    }
    const double next = self * x[t] + sum;
    if (next != x[t]) {
      x[t] = next;
      v.touch(t);
    }
  }
}

// Per level l >= 1, per parent v vertex: its row in step(l).crease_edges, or -1.
std::vector<std::vector<std::int32_t>> crease_rows(const SubdivisionHierarchy& h) {
  std::vector<std::vector<std::int32_t>> rows(static_cast<std::size_t>(h.levels()) + 1);
  for (int level = 1; level <= h.levels(); ++level) {
    const RefinementStep& s = h.step(level);
    std::vector<std::int32_t>& row = rows[static_cast<std::size_t>(level)];
    row.assign(s.parent_vertex_count, -1);
    for (std::size_t k = 0; k < s.crease_vertices.size(); ++k) row[s.crease_vertices[k]] = static_cast<std::int32_t>(k);
  }
  return rows;
}

}  // namespace

std::vector<double> wavelet_squared_norms(const SubdivisionHierarchy& hierarchy) {
  const std::size_t fine = hierarchy.fine_vertex_count();
  std::vector<double> norms(fine, 0.0);
  const std::vector<std::vector<std::int32_t>> crease = crease_rows(hierarchy);
  tbb::enumerable_thread_specific<SparseVector> scratch([fine] { return SparseVector(fine); });
  for (int level = 1; level <= hierarchy.levels(); ++level) {
    const auto first = static_cast<std::uint32_t>(hierarchy.vertex_count(level - 1));
    const auto end = static_cast<std::uint32_t>(hierarchy.vertex_count(level));
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(first, end, 256), [&](const auto& range) {
      SparseVector& v = scratch.local();
      for (std::uint32_t i = range.begin(); i < range.end(); ++i) {
        if (++v.stamp == 0) {  // wrapped: every mark is stale again
          std::fill(v.mark.begin(), v.mark.end(), 0);
          v.stamp = 1;
        }
        v.touched.clear();
        v.value[i] = 1.0;
        v.touch(i);
        for (int m = level; m <= hierarchy.levels(); ++m)
          for (const Step& step : lifting::kSynthesisSteps)
            apply_step(hierarchy.step(m), step, crease[static_cast<std::size_t>(m)], v);
        double sum = 0;
        for (const std::uint32_t t : v.touched) {
          sum += v.value[t] * v.value[t];
          v.value[t] = 0.0;
        }
        norms[i] = sum;
      }
    });
  }
  return norms;
}

}  // namespace isowave
