#include "isowave/fit/fold_repair.h"

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <iterator>
#include <limits>
#include <utility>
#include <vector>

#include "isowave/core/huge_page_vector.h"
#include "isowave/fit/trilinear.h"
#include "fitted_field.h"
#include "wrap_kernels.h"
#include "wrap_passes.h"

namespace isowave::wrap {

std::size_t find_folded_faces(const WrapLevelMesh& mesh, const TrilinearGrid& field, Orientation orientation,
                              const std::vector<Vec3>& positions, HugePageVector<std::uint8_t>& folded) {
  const double expected_sign = unfolded_sign(orientation);
  if (folded.capacity() < mesh.face_count()) reserve_fresh_on_huge_pages(folded, mesh.face_count());
  folded.resize(mesh.face_count());
  const std::vector<std::size_t> counts =
      for_blocks<std::size_t>(mesh.face_count(), [&](std::size_t first, std::size_t last, std::size_t& count) {
        for (std::size_t f = first; f < last; ++f) {
          if (f + kPrefetchDistance < last) prefetch_face(mesh, field, positions, f + kPrefetchDistance);
          folded[f] = face_folded(mesh, field, expected_sign, positions, f);
          count += folded[f];
        }
      });
  std::size_t total = 0;
  for (std::size_t count : counts) total += count;
  return total;
}

namespace {

// Sets a flag that other threads may set at the same time (always to 1).
inline void raise_flag(std::uint8_t& flag) { __atomic_store_n(&flag, std::uint8_t{1}, __ATOMIC_RELAXED); }

// The indices of the set flags, ascending (the same for any thread count).
void collect_flagged(const HugePageVector<std::uint8_t>& flags, HugePageVector<std::uint32_t>& list) {
  const std::size_t n = flags.size();
  std::vector<std::size_t> starts = for_blocks<std::size_t>(n, [&](std::size_t first, std::size_t last, std::size_t& count) {
    for (std::size_t i = first; i < last; ++i) count += flags[i] != 0;
  });
  std::size_t total = 0;
  for (std::size_t& start : starts) total += std::exchange(start, total);
  list.resize(total);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, starts.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) {
      std::size_t out = starts[b];
      for (std::size_t i = b * kBlock, last = std::min(n, (b + 1) * kBlock); i < last; ++i)
        if (flags[i]) list[out++] = static_cast<std::uint32_t>(i);
    }
  });
}

void clear_flags(HugePageVector<std::uint8_t>& flags, std::size_t n) {
  if (flags.capacity() < n) reserve_fresh_on_huge_pages(flags, n);
  flags.resize(n);
  for_blocks<char>(n, [&](std::size_t first, std::size_t last, char&) {
    std::fill(flags.begin() + static_cast<std::ptrdiff_t>(first), flags.begin() + static_cast<std::ptrdiff_t>(last), 0);
  });
}

// untangle()'s flags and lists, kept across rounds. face_state per face:
// bit 0 a moved corner, bit 1 folded before the round, bit 2 a corner that
// went back.
struct UntangleState {
  HugePageVector<std::uint8_t> folded, corner, face_state;
  HugePageVector<std::uint32_t> list;  // the corners of folded faces, ascending
};

// Lists the corners of the folded faces.
void list_folded_corners(const WrapLevelMesh& mesh, UntangleState& state) {
  clear_flags(state.corner, mesh.vertex_count);
  for_vertices(mesh.face_count(), [&](std::size_t f) {
    if (!state.folded[f]) return;
    for (std::uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k)
      raise_flag(state.corner[mesh.face_vertices[k]]);
  });
  collect_flagged(state.corner, state.list);
}

// Moves each listed corner to its neighbours' centroid put onto the
// isosurface (Jacobi: new positions from the old ones, computed into `moved`
// and swapped into place, so that `moved` keeps the old ones), and marks the
// faces around the corners that moved (fixed ones, and those without a
// root, did not).
void smooth_listed_corners(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                           double iso, double range, UntangleState& state, std::vector<Vec3>& positions,
                           std::vector<Vec3>& moved) {
  const HugePageVector<std::uint32_t>& list = state.list;
  const std::size_t count = list.size();
  moved.resize(std::max(moved.size(), count));
  for_vertices(count, [&](std::size_t i) {
    // The smoothed point's samples are near the vertex's own.
    if (i + kPrefetchDistance < count) field.prefetch_at(field.grid_point(positions[list[i + kPrefetchDistance]]));
    const std::size_t v = list[i];
    moved[i] = positions[v];
    Vec3 centroid;
    if (mesh.role[v] == WrapRole::Fixed || !relaxation_centroid(mesh, v, positions, centroid)) return;
    const Vec3 smoothed = place(mesh, box, v, centroid);
    Vec3 target;
    if (project_onto_isosurface(mesh, box, field, cell, iso, range, v, smoothed, target)) moved[i] = target;
  });
  clear_flags(state.face_state, mesh.face_count());
  for_vertices(count, [&](std::size_t i) {
    const std::size_t v = list[i];
    std::swap(positions[v], moved[i]);
    if (positions[v] == moved[i]) return;
    for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
      raise_flag(state.face_state[mesh.vertex_faces[k]]);
  });
}

// Checks the faces with a moved corner again, the only ones that can
// change. `folded` takes their new flags at once: a dropped round ends the
// repair, so it is not read again.
void check_moved_faces(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                       const std::vector<Vec3>& positions, UntangleState& state) {
  HugePageVector<std::uint8_t>& face_state = state.face_state;
  HugePageVector<std::uint8_t>& folded = state.folded;
  for_blocks<char>(mesh.face_count(), [&](std::size_t first, std::size_t last, char&) {
    for (std::size_t f = first; f < last; ++f) {
      if (f + kPrefetchDistance < last && face_state[f + kPrefetchDistance])
        prefetch_face(mesh, field, positions, f + kPrefetchDistance);
      if (!face_state[f]) continue;
      face_state[f] = static_cast<std::uint8_t>(1 | (folded[f] << 1));
      folded[f] = face_folded(mesh, field, expected_sign, positions, f);
    }
  });
}

// A vertex with more folded faces around it than before goes back (its old
// position is in `moved`, which keeps it for a dropped round).
void return_worse_corners(const WrapLevelMesh& mesh, UntangleState& state, std::vector<Vec3>& positions,
                          const std::vector<Vec3>& moved) {
  const HugePageVector<std::uint32_t>& list = state.list;
  HugePageVector<std::uint8_t>& face_state = state.face_state;
  HugePageVector<std::uint8_t>& folded = state.folded;
  for_vertices(list.size(), [&](std::size_t i) {
    const std::size_t v = list[i];
    if (positions[v] == moved[i]) return;
    int before = 0, after = 0;
    for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
      const std::uint32_t f = mesh.vertex_faces[k];
      before += __atomic_load_n(&face_state[f], __ATOMIC_RELAXED) >> 1 & 1;
      after += folded[f];
    }
    if (after <= before) return;
    positions[v] = moved[i];
    for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
      __atomic_fetch_or(&face_state[mesh.vertex_faces[k]], std::uint8_t{4}, __ATOMIC_RELAXED);
  });
}

// The number of folded faces after the round, from `folded_before_round`:
// the checked faces' flags (those with a corner that went back checked once
// more) before and after.
std::size_t count_after_round(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                              const std::vector<Vec3>& positions, UntangleState& state,
                              std::size_t folded_before_round) {
  HugePageVector<std::uint8_t>& face_state = state.face_state;
  HugePageVector<std::uint8_t>& folded = state.folded;
  struct Change {
    std::size_t was = 0, now = 0;  // folded faces among the checked ones, before and after
  };
  const std::vector<Change> changes =
      for_blocks<Change>(mesh.face_count(), [&](std::size_t first, std::size_t last, Change& change) {
        for (std::size_t f = first; f < last; ++f) {
          const std::uint8_t face = face_state[f];
          if (!face) continue;
          if (face & 4) folded[f] = face_folded(mesh, field, expected_sign, positions, f);
          change.was += face >> 1 & 1;
          change.now += folded[f];
        }
      });
  Change total;
  for (const Change& change : changes) {
    total.was += change.was;
    total.now += change.now;
  }
  return folded_before_round - total.was + total.now;
}

}  // namespace

// untangle() with a buffer for the moved vertices' positions supplied by the
// caller (the shrink-wrap lends its second position buffer). Each round works
// on lists of the corners of folded faces rather than on whole-level passes,
// and only the faces around the moved ones are checked again.
UntangleStatistics untangle_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                                 double iso, Orientation orientation, int rounds, double max_move_cells,
                                 std::vector<Vec3>& positions, std::vector<Vec3>& moved) {
  assert(positions.size() >= mesh.vertex_count && &positions != &moved);
  const double range = max_move_cells * cell;
  const double expected_sign = unfolded_sign(orientation);
  UntangleStatistics stats;
  UntangleState state;
  stats.folded_before = find_folded_faces(mesh, field, orientation, positions, state.folded);
  stats.folded_after = stats.folded_before;
  for (int round = 0; round < rounds && stats.folded_after > 0; ++round) {
    list_folded_corners(mesh, state);
    smooth_listed_corners(mesh, field, box, cell, iso, range, state, positions, moved);
    check_moved_faces(mesh, field, expected_sign, positions, state);
    return_worse_corners(mesh, state, positions, moved);
    const std::size_t folded_now = count_after_round(mesh, field, expected_sign, positions, state, stats.folded_after);
    if (folded_now >= stats.folded_after) {  // a round that does not help is dropped
      for_vertices(state.list.size(), [&](std::size_t i) { positions[state.list[i]] = moved[i]; });
      break;
    }
    stats.folded_after = folded_now;
    ++stats.rounds;
  }
  return stats;
}

namespace {

// The unfold's cost of the faces around v with v at `at` (the others where
// `positions` has them): kFoldedFaceCost per folded face (face_folded_at)
// plus, for each, how far its normal turns past the field gradient (minus
// the cosine of their angle, 0 to 1). The second part lets a vertex make a
// fold shallower where no single move removes one of its faces, which a
// later move then can.
constexpr double kFoldedFaceCost = 10.0;

// Added to `cost`; returns as soon as the sum reaches `enough` (a trial place
// that cannot win).
double unfold_cost(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                   const std::vector<Vec3>& positions, std::uint32_t v, const Vec3& at, double cost = 0,
                   double enough = std::numeric_limits<double>::infinity()) {
  const auto position = [&](std::uint32_t u) -> const Vec3& { return u == v ? at : positions[u]; };
  for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
    Vec3 newell, gradient;
    face_normal_and_gradient(mesh, field, mesh.vertex_faces[k], position, newell, gradient);
    const double agreement = expected_sign * dot(newell, gradient);
    if (agreement > 0) continue;  // as face_folded_at()
    const double lengths = norm(newell) * norm(gradient);
    cost += kFoldedFaceCost + (lengths > 0 ? -agreement / lengths : 1.0);
    if (cost >= enough) return cost;
  }
  return cost;
}

// The unfold's move of one vertex (see unfold()): the cheapest of its
// trial places, or false to stay.
bool unfold_vertex(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell, double iso,
                   double expected_sign, double range, const std::vector<Vec3>& positions, std::uint32_t v,
                   Vec3& moved_to) {
  const Vec3 p = positions[v];
  const double stay = unfold_cost(mesh, field, expected_sign, positions, v, p);
  if (stay < kFoldedFaceCost) return false;  // no folded face around v
  double best = stay;
  const auto consider = [&](const Vec3& trial) {
    Vec3 target;
    if (!project_onto_isosurface(mesh, box, field, cell, iso, range, v, place(mesh, box, v, trial), target)) return;
    // Moves are charged (squared, in cells) so that of two places nearly as
    // good the nearer wins: each move is detail the wavelets must code.
    const double move_cost = squared_norm(target - p) / (cell * cell);
    if (move_cost >= best - 1e-9) return;
    const double cost = unfold_cost(mesh, field, expected_sign, positions, v, target, move_cost, best - 1e-9);
    if (cost < best - 1e-9) {
      best = cost;
      moved_to = target;
    }
  };
  // The places: the neighbours' centroid and p mirrored through it, and
  // toward each neighbour half-way and nine tenths of the way.
  Vec3 centroid;
  if (relaxation_centroid(mesh, v, positions, centroid)) {
    consider(centroid);
    consider(2.0 * centroid - p);
  }
  const std::uint32_t b0 = mesh.boundary_neighbours[2 * v], b1 = mesh.boundary_neighbours[2 * v + 1];
  if (mesh.role[v] == WrapRole::Boundary && b0 != kNone && b1 != kNone) {  // along its boundary curve only
    consider(0.5 * (p + positions[b0]));
    consider(0.5 * (p + positions[b1]));
  } else {
    for (std::uint32_t k = mesh.neighbour_offsets[v]; k < mesh.neighbour_offsets[v + 1]; ++k) {
      const Vec3& q = positions[mesh.neighbours[k]];
      consider(0.5 * (p + q));
      consider(q + 0.1 * (p - q));
    }
    for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
      const std::uint32_t f = mesh.vertex_faces[k];
      Vec3 face_centroid;
      for (std::uint32_t j = mesh.face_offsets[f]; j < mesh.face_offsets[f + 1]; ++j)
        face_centroid += positions[mesh.face_vertices[j]];
      consider((1.0 / double(mesh.face_offsets[f + 1] - mesh.face_offsets[f])) * face_centroid);
    }
  }
  return best < stay;
}

// unfold()'s lists, kept across rounds.
struct UnfoldState {
  static constexpr std::uint16_t kNoColor = 0xffff;
  HugePageVector<std::uint32_t> faces;  // the folded ones, ascending
  std::vector<std::uint16_t> color;     // per vertex; kNoColor between rounds
  // A corner that found no better place is tried again only once a vertex
  // of its faces has moved: `stale` marks the others.
  std::vector<std::uint8_t> stale;
  std::vector<std::uint32_t> corners, by_color, color_first, changed, merged;
  std::vector<std::uint8_t> used, moved;
};

// The movable corners of the folded faces that may move, ascending, grouped
// by greedy colours in that order (by_color, the colour c's in
// by_color[color_first[c] .. color_first[c + 1])): two corners that share a
// face differ, so the corners of one colour move at once without reading
// one another's places, and the result is the same for any thread count.
// Returns the number of colours.
std::uint16_t colour_movable_corners(const WrapLevelMesh& mesh, UnfoldState& s) {
  constexpr std::uint16_t kNoColor = UnfoldState::kNoColor;
  s.corners.clear();
  for (const std::uint32_t f : s.faces)
    for (std::uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k)
      if (mesh.role[mesh.face_vertices[k]] != WrapRole::Fixed && !s.stale[mesh.face_vertices[k]])
        s.corners.push_back(mesh.face_vertices[k]);
  std::sort(s.corners.begin(), s.corners.end());
  s.corners.erase(std::unique(s.corners.begin(), s.corners.end()), s.corners.end());
  std::uint16_t colors = 0;
  for (const std::uint32_t v : s.corners) {
    s.used.assign(std::size_t{colors} + 1, 0);
    for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k) {
      const std::uint32_t f = mesh.vertex_faces[k];
      for (std::uint32_t j = mesh.face_offsets[f]; j < mesh.face_offsets[f + 1]; ++j)
        if (s.color[mesh.face_vertices[j]] != kNoColor) s.used[s.color[mesh.face_vertices[j]]] = 1;
    }
    std::uint16_t c = 0;
    while (s.used[c]) ++c;
    s.color[v] = c;
    colors = std::max<std::uint16_t>(colors, static_cast<std::uint16_t>(c + 1));
  }
  s.color_first.assign(std::size_t{colors} + 1, 0);
  for (const std::uint32_t v : s.corners) ++s.color_first[s.color[v] + 1];
  for (std::uint16_t c = 0; c < colors; ++c) s.color_first[c + 1] += s.color_first[c];
  s.by_color.resize(s.corners.size());
  {
    std::vector<std::uint32_t> next(s.color_first.begin(), s.color_first.end() - 1);
    for (const std::uint32_t v : s.corners) s.by_color[next[s.color[v]]++] = v;
  }
  for (const std::uint32_t v : s.corners) s.color[v] = kNoColor;
  return colors;
}

// After the moves: the corners that did not move marked stale, the faces
// around the moved ones (the only ones that can change) checked again and
// the folded list updated. Adds the moves to `moves`; false if none.
bool update_after_moves(const WrapLevelMesh& mesh, const TrilinearGrid& field, double expected_sign,
                        const std::vector<Vec3>& positions, HugePageVector<std::uint8_t>& folded, UnfoldState& s,
                        std::size_t& moves) {
  s.changed.clear();
  for (std::size_t i = 0; i < s.by_color.size(); ++i) {
    if (!s.moved[i]) {
      s.stale[s.by_color[i]] = 1;
      continue;
    }
    ++moves;
    const std::uint32_t v = s.by_color[i];
    for (std::uint32_t k = mesh.vertex_face_offsets[v]; k < mesh.vertex_face_offsets[v + 1]; ++k)
      s.changed.push_back(mesh.vertex_faces[k]);
  }
  if (s.changed.empty()) return false;
  std::sort(s.changed.begin(), s.changed.end());
  s.changed.erase(std::unique(s.changed.begin(), s.changed.end()), s.changed.end());
  for_vertices(s.changed.size(), [&](std::size_t i) {
    folded[s.changed[i]] = face_folded(mesh, field, expected_sign, positions, s.changed[i]);
  });
  for (const std::uint32_t f : s.changed)
    for (std::uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k) s.stale[mesh.face_vertices[k]] = 0;
  s.merged.clear();
  std::set_union(s.faces.begin(), s.faces.end(), s.changed.begin(), s.changed.end(), std::back_inserter(s.merged));
  s.faces.clear();
  for (const std::uint32_t f : s.merged)
    if (folded[f]) s.faces.push_back(f);
  return true;
}

}  // namespace

// After the first scan every round works on lists: the folded faces, their
// corners, and the faces around the corners that moved.
UnfoldStatistics unfold_with(const WrapLevelMesh& mesh, const TrilinearGrid& field, const Box& box, double cell,
                             double iso, Orientation orientation, int rounds, double max_move_cells,
                             std::vector<Vec3>& positions) {
  assert(positions.size() >= mesh.vertex_count);
  const double range = max_move_cells * cell;
  const double expected_sign = unfolded_sign(orientation);
  UnfoldStatistics stats;
  HugePageVector<std::uint8_t> folded;
  stats.folded_before = stats.folded_after = find_folded_faces(mesh, field, orientation, positions, folded);
  if (stats.folded_before == 0 || rounds == 0) return stats;
  UnfoldState s;
  collect_flagged(folded, s.faces);
  s.color.assign(mesh.vertex_count, UnfoldState::kNoColor);
  s.stale.assign(mesh.vertex_count, 0);
  for (int round = 0; round < rounds && !s.faces.empty(); ++round) {
    const std::uint16_t colors = colour_movable_corners(mesh, s);
    s.moved.assign(s.by_color.size(), 0);
    for (std::uint16_t c = 0; c < colors; ++c)
      for_vertices(s.color_first[c + 1] - s.color_first[c], [&](std::size_t i) {
        const std::size_t at = s.color_first[c] + i;
        Vec3 target;
        if (!unfold_vertex(mesh, field, box, cell, iso, expected_sign, range, positions, s.by_color[at], target)) return;
        positions[s.by_color[at]] = target;
        s.moved[at] = 1;
      });
    if (!update_after_moves(mesh, field, expected_sign, positions, folded, s, stats.moved)) break;
    ++stats.rounds;
    stats.folded_after = s.faces.size();
  }
  return stats;
}

}  // namespace isowave::wrap

namespace isowave {

UntangleStatistics untangle(const WrapLevelMesh& mesh, const Volume& field, double iso, Orientation orientation,
                            int rounds, double max_move_cells, std::vector<Vec3>& positions) {
  std::vector<Vec3> moved;
  const detail::FittedField fitted(field, iso);
  return wrap::untangle_with(mesh, fitted.grid(), wrap::Box(field), field.cell_size(), iso, orientation, rounds,
                             max_move_cells, positions, moved);
}

UnfoldStatistics unfold(const WrapLevelMesh& mesh, const Volume& field, double iso, Orientation orientation,
                        int rounds, double max_move_cells, std::vector<Vec3>& positions) {
  const detail::FittedField fitted(field, iso);
  return wrap::unfold_with(mesh, fitted.grid(), wrap::Box(field), field.cell_size(), iso, orientation, rounds,
                           max_move_cells, positions);
}

std::size_t count_folded_faces(const WrapLevelMesh& mesh, const std::vector<Vec3>& positions, const Volume& field,
                               Orientation orientation) {
  HugePageVector<std::uint8_t> folded;
  return wrap::find_folded_faces(mesh, TrilinearGrid(field), orientation, positions, folded);
}

std::size_t take_back_folding_moves(const WrapLevelMesh& mesh, const Volume& field, Orientation orientation,
                                    const std::vector<Vec3>& before, std::vector<Vec3>& positions) {
  const TrilinearGrid grid(field);
  HugePageVector<std::uint8_t> folded_before, folded_now;
  wrap::find_folded_faces(mesh, grid, orientation, before, folded_before);
  std::size_t taken_back = 0;
  for (;;) {
    wrap::find_folded_faces(mesh, grid, orientation, positions, folded_now);
    std::size_t taken_this_round = 0;
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      if (!folded_now[f] || folded_before[f]) continue;
      for (std::uint32_t k = mesh.face_offsets[f]; k < mesh.face_offsets[f + 1]; ++k) {
        const std::uint32_t v = mesh.face_vertices[k];
        if (positions[v] == before[v]) continue;
        positions[v] = before[v];
        ++taken_this_round;
      }
    }
    if (taken_this_round == 0) return taken_back;
    taken_back += taken_this_round;
  }
}

}  // namespace isowave
