#include "isowave/fit/signed_distance.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "isowave/fit/trilinear.h"
#include "root_search.h"

namespace isowave {
namespace {

// Closest-point index per node; its top bit marks the node as queued, so the
// propagation loop touches one array fewer per update.
constexpr std::uint32_t kQueuedBit = 0x80000000u;
constexpr std::uint32_t kNoPoint = 0x7fffffffu;
// Propagation prefetch distances in queue places.
constexpr std::size_t kPrefetchNodesAhead = 48, kPrefetchPointsAhead = 20;
// Per-node flag bits: the sample's side; an end of a grid edge the surface
// mesh crosses (kKeptEdge); the cell whose lowest corner is this node
// carries the surface mesh (kKeptCell) or has corners on both sides
// (kCrossCell); seed; and the sign repair's flip, visited and open marks.
constexpr std::uint8_t kInside = 1, kKeptEdge = 2, kKeptCell = 4, kSeed = 8, kFlip = 16, kVisited = 32, kOpen = 64,
                         kCrossCell = 128;

struct Point3f {
  float x, y, z;
};

// First-in-first-out queue of node indices in a ring buffer that doubles when
// full: the queued flag bounds it by the node count, but the frontier is
// usually far smaller, so it starts small.
class NodeQueue {
 public:
  explicit NodeQueue(std::size_t initial) : ring_(std::max<std::size_t>(initial, 1024)) {}
  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  std::size_t capacity_bytes() const { return ring_.capacity() * sizeof(std::uint32_t); }
  void push(std::uint32_t node) {
    if (size_ == ring_.size()) grow();
    std::size_t tail = head_ + size_;
    if (tail >= ring_.size()) tail -= ring_.size();
    ring_[tail] = node;
    ++size_;
  }
  // The node `ahead` places behind the front (precondition: ahead < size()).
  std::uint32_t peek(std::size_t ahead) const {
    std::size_t at = head_ + ahead;
    if (at >= ring_.size()) at -= ring_.size();
    return ring_[at];
  }
  std::uint32_t pop() {
    const std::uint32_t node = ring_[head_];
    if (++head_ == ring_.size()) head_ = 0;
    --size_;
    return node;
  }

 private:
  void grow() {
    std::vector<std::uint32_t> bigger(ring_.size() * 2);
    for (std::size_t k = 0; k < size_; ++k) bigger[k] = ring_[(head_ + k) % ring_.size()];
    ring_.swap(bigger);
    head_ = 0;
  }
  std::vector<std::uint32_t> ring_;
  std::size_t head_ = 0, size_ = 0;
};

bool is_inside(float value, float iso) { return std::isfinite(value) && value >= iso; }

// Central-difference gradient at a node (one-sided at the box faces and next
// to non-finite samples; 0 along an axis with no usable neighbour).
Vec3 node_gradient(const Volume& v, std::size_t i, std::size_t j, std::size_t k) {
  const std::size_t n = v.index(i, j, k);
  const std::size_t stride[3] = {1, v.dims[0], v.dims[0] * v.dims[1]};
  const std::size_t coord[3] = {i, j, k};
  const double spacing[3] = {v.spacing.x, v.spacing.y, v.spacing.z};
  double g[3];
  for (int a = 0; a < 3; ++a) {
    const bool has_low = coord[a] > 0 && std::isfinite(v.values[n - stride[a]]);
    const bool has_high = coord[a] + 1 < v.dims[a] && std::isfinite(v.values[n + stride[a]]);
    const double low = has_low ? v.values[n - stride[a]] : v.values[n];
    const double high = has_high ? v.values[n + stride[a]] : v.values[n];
    const int span = int(has_low) + int(has_high);
    g[a] = span == 0 ? 0.0 : (high - low) / (span * spacing[a]);
  }
  return {g[0], g[1], g[2]};
}

// Gives the regions enclosed by dropped components the sign of their
// surroundings. Start points: nodes on a dropped component (a grid edge
// across the isovalue, and none that the mesh crosses; every enclosed region
// has one, and which nodes start does not change the result). From each, a
// flood over same-side 6-neighbours; the region is enclosed if the flood ends
// without reaching an end of a grid edge the surface mesh crosses, the box
// faces, an earlier unenclosed region or the size limit. Enclosed regions
// are flipped. Judged by the mesh's edges rather than by the seeds (the
// corners of the cells it passes through), a speck that shares cells with
// the kept surface is enclosed too, and the attraction no longer lands on
// it.
// Sequential and in index order, so deterministic; cost proportional to the
// regions explored.
void flip_enclosed_regions(const Volume& field, const std::vector<std::uint32_t>& starts,
                           HugePageVector<std::uint8_t>& flags, SignedDistanceStatistics& stats) {
  const std::size_t nx = field.dims[0], ny = field.dims[1], nz = field.dims[2], slice = nx * ny;
  constexpr std::size_t kLimit = std::size_t{1} << 22;
  std::vector<std::uint32_t> region;
  const auto on_box = [&](std::size_t n) {
    const std::size_t k = n / slice, j = (n - k * slice) / nx, i = n - k * slice - j * nx;
    return i == 0 || j == 0 || k == 0 || i + 1 == nx || j + 1 == ny || k + 1 == nz;
  };
  const auto neighbours = [&](std::size_t n, auto&& visit) {
    const std::size_t k = n / slice, j = (n - k * slice) / nx, i = n - k * slice - j * nx;
    if (i > 0) visit(n - 1);
    if (i + 1 < nx) visit(n + 1);
    if (j > 0) visit(n - nx);
    if (j + 1 < ny) visit(n + nx);
    if (k > 0) visit(n - slice);
    if (k + 1 < nz) visit(n + slice);
  };
  stats.unseeded_crossing_nodes = starts.size();
  for (const std::uint32_t start : starts) {
    if (flags[start] & (kKeptEdge | kVisited)) continue;
    const std::uint8_t side = flags[start] & kInside;
    region.clear();
    region.push_back(static_cast<std::uint32_t>(start));
    flags[start] |= kVisited;
    bool enclosed = !on_box(start);
    for (std::size_t head = 0; head < region.size() && enclosed; ++head) {
      neighbours(region[head], [&](std::size_t m) {
        if (!enclosed || (flags[m] & kInside) != side) return;
        if (flags[m] & kVisited && !(flags[m] & kOpen)) return;  // already in this region
        if (flags[m] & (kKeptEdge | kOpen) || on_box(m) || region.size() >= kLimit) {
          enclosed = false;
          return;
        }
        flags[m] |= kVisited;
        region.push_back(static_cast<std::uint32_t>(m));
      });
    }
    if (!enclosed) {  // later floods reaching these nodes stop at once
      for (std::uint32_t n : region) flags[n] |= kOpen;
      continue;
    }
    for (std::uint32_t n : region) flags[n] |= kFlip;
    stats.flipped_nodes += region.size();
  }
}

// The grid's sizes, shared by every step below.
struct GridShape {
  std::size_t nx, ny, nz, slice;
  explicit GridShape(const Volume& field)
      : nx(field.dims[0]), ny(field.dims[1]), nz(field.dims[2]), slice(field.dims[0] * field.dims[1]) {}
};

void check_arguments(const Volume& field, const SignedDistanceOptions& options) {
  const GridShape g(field);
  if (g.nx < 2 || g.ny < 2 || g.nz < 2)
    throw Error(ErrorKind::InvalidArgument, "signed distance needs at least 2 samples along each axis");
  if (field.values.size() != field.sample_count())
    throw Error(ErrorKind::InvalidArgument, "volume sample count does not match its dimensions");
  for (int a = 0; a < 3; ++a)
    if (!(field.spacing[a] > 0) || !std::isfinite(field.spacing[a]))
      throw Error(ErrorKind::InvalidArgument, "volume spacing must be positive and finite");
  if (!std::isfinite(options.iso)) throw Error(ErrorKind::InvalidArgument, "isovalue must be finite");
  if (!std::isfinite(options.band_cells) || options.band_cells < 0)
    throw Error(ErrorKind::InvalidArgument, "narrow band width must be a finite number of cells >= 0");
  if (field.sample_count() >= kNoPoint)
    throw Error(ErrorKind::Unsupported, "volumes with 2^31 or more samples are not supported");
}

// Inside/outside per node (kInside); the later steps add the cell, seed and
// sign-repair bits.
HugePageVector<std::uint8_t> classify_nodes(const Volume& field, float iso) {
  const GridShape g(field);
  HugePageVector<std::uint8_t> flags;
  reserve_on_huge_pages(flags, field.sample_count());
  flags.resize(field.sample_count());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.nz), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t n = r.begin() * g.slice; n < r.end() * g.slice; ++n)
      flags[n] = is_inside(field.values[n], iso) ? kInside : 0;
  });
  return flags;
}

// Cells the surface mesh passes through (kKeptCell) and the ends of the grid
// edges it crosses (kKeptEdge): every vertex lies on a grid edge (or, for a
// loop-centre vertex, inside a cell); mark each cell around it. Throws
// Error(InvalidArgument) for a non-finite vertex.
void mark_surface_cells(const Volume& field, const PolygonMesh& surface, HugePageVector<std::uint8_t>& flags) {
  const GridShape g(field);
  const std::size_t cells[3] = {g.nx - 1, g.ny - 1, g.nz - 1};
  for (const Vec3& p : surface.positions) {
    if (!is_finite(p)) throw Error(ErrorKind::InvalidArgument, "surface mesh has a non-finite vertex");
    // The cells around it, and the ends of its grid edge (the node it lies
    // on; for a loop-centre vertex the corners of its cell).
    std::size_t low[3], high[3], first[3], last[3];
    for (int a = 0; a < 3; ++a) {
      const double gc = (p[a] - field.origin[a]) / field.spacing[a];
      const double nearest = std::round(gc);
      if (std::abs(gc - nearest) < 1e-6) {
        const double m = std::clamp(nearest, 0.0, double(cells[a]));
        low[a] = m >= 1 ? std::size_t(m) - 1 : 0;
        high[a] = std::min(std::size_t(m), cells[a] - 1);
        first[a] = last[a] = std::size_t(m);
      } else {
        low[a] = high[a] = std::size_t(std::clamp(std::floor(gc), 0.0, double(cells[a] - 1)));
        first[a] = low[a];
        last[a] = low[a] + 1;
      }
    }
    for (std::size_t k = low[2]; k <= high[2]; ++k)
      for (std::size_t j = low[1]; j <= high[1]; ++j)
        for (std::size_t i = low[0]; i <= high[0]; ++i) flags[i + g.nx * j + g.slice * k] |= kKeptCell;
    for (std::size_t k = first[2]; k <= last[2]; ++k)
      for (std::size_t j = first[1]; j <= last[1]; ++j)
        for (std::size_t i = first[0]; i <= last[0]; ++i) flags[i + g.nx * j + g.slice * k] |= kKeptEdge;
  }
}

// Cells with corners on both sides (kCrossCell; each cell writes only its
// lowest corner's flag and reads sample values, so slices run in parallel).
void mark_crossing_cells(const Volume& field, float iso, HugePageVector<std::uint8_t>& flags) {
  const GridShape g(field);
  const std::size_t nx = g.nx, slice = g.slice;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.nz - 1), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k)
      for (std::size_t j = 0; j + 1 < g.ny; ++j) {
        const std::size_t row = nx * j + slice * k;
        bool low_face[4];
        const auto face_sides = [&](std::size_t i, bool* out) {
          out[0] = is_inside(field.values[row + i], iso);
          out[1] = is_inside(field.values[row + i + nx], iso);
          out[2] = is_inside(field.values[row + i + slice], iso);
          out[3] = is_inside(field.values[row + i + nx + slice], iso);
        };
        face_sides(0, low_face);
        for (std::size_t i = 0; i + 1 < nx; ++i) {
          bool high_face[4];
          face_sides(i + 1, high_face);
          const bool first = low_face[0];
          bool mixed = false;
          for (int c = 0; c < 4; ++c) mixed |= (low_face[c] != first) | (high_face[c] != first);
          if (mixed) flags[row + i] |= kCrossCell;
          std::copy(high_face, high_face + 4, low_face);
        }
      }
  });
}

// One z-slice's seeds: nodes with their estimated closest surface points.
struct SliceSeeds {
  std::vector<std::uint32_t> nodes;
  std::vector<Point3f> points;
  std::vector<std::uint32_t> orphans;  // on cells of dropped components only
  std::size_t projected = 0;
};

// Finds the seeds (see signed_distance.h, step 1). A node lies in a cell
// containing the surface exactly when one of its up to 26 neighbours is on
// the other side; with a surface mesh, when one of its up to 8 cells is
// marked, and candidate points must lie in cells the mesh passes through.
// Reads `flags` only, so slices run in parallel.
class SeedFinder {
 public:
  SeedFinder(const Volume& field, const SignedDistanceOptions& options, const HugePageVector<std::uint8_t>& flags)
      : field_(field),
        options_(options),
        flags_(flags),
        g_(field),
        iso_(static_cast<float>(options.iso)),
        masked_(options.surface != nullptr),
        cell_(field.cell_size()),
        max_spacing_(std::max({field.spacing.x, field.spacing.y, field.spacing.z})),
        search_range_(std::sqrt(3.0) * max_spacing_),
        box_low_(volume_box_min(field)),
        box_high_(volume_box_max(field)),
        grid_(field) {}

  // Per slice, concatenated in slice order so that the queue order (and
  // hence the result) does not depend on the thread count.
  std::vector<SliceSeeds> find_all() const {
    std::vector<SliceSeeds> slices(g_.nz);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g_.nz, 1), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t k = r.begin(); k < r.end(); ++k) seed_slice(k, slices[k]);
    });
    return slices;
  }

 private:
  void seed_slice(std::size_t k, SliceSeeds& out) const {
    const std::size_t nx = g_.nx, slice = g_.slice;
    // Per row: the cell bits of the (up to) 4 cells at each x index around
    // the row, then each node ORs its two x positions (8 cells in all).
    std::vector<std::uint8_t> row(nx);
    constexpr std::uint8_t kCellBits = kCrossCell | kKeptCell;
    for (std::size_t j = 0; j < g_.ny; ++j) {
      const std::uint8_t* here = flags_.data() + nx * j + slice * k;
      const std::uint8_t* below = j > 0 ? here - nx : nullptr;
      const std::uint8_t* behind = k > 0 ? here - slice : nullptr;
      const std::uint8_t* below_behind = j > 0 && k > 0 ? here - nx - slice : nullptr;
      bool any = false;
      for (std::size_t i = 0; i < nx; ++i) {
        std::uint8_t bits = here[i];
        if (below) bits |= below[i];
        if (behind) bits |= behind[i];
        if (below_behind) bits |= below_behind[i];
        row[i] = bits & kCellBits;
        any |= row[i] != 0;
      }
      if (!any) continue;
      for (std::size_t i = 0; i < nx; ++i) {
        const std::uint8_t cell_bits = row[i] | (i > 0 ? row[i - 1] : 0);
        if (!cell_bits) continue;
        const std::size_t n = i + nx * j + slice * k;
        bool crossing = (cell_bits & kCrossCell) != 0;
        const bool kept = (cell_bits & kKeptCell) != 0;
        if (masked_ && crossing && !(flags_[n] & kKeptEdge) && has_crossing_edge(n))
          out.orphans.push_back(static_cast<std::uint32_t>(n));
        if (masked_) crossing = kept;
        if (!crossing) continue;
        const float value = field_.values[n];
        if (!std::isfinite(value)) continue;  // no usable estimate; reached from neighbours
        const Vec3 x = field_.world(double(i), double(j), double(k));
        Vec3 point = x;
        bool projected = true;
        if (value != iso_ && !estimate_closest_point(n, {i, j, k}, x, value, point, projected))
          continue;  // reached from neighbours
        out.nodes.push_back(static_cast<std::uint32_t>(n));
        out.points.push_back({float(point.x), float(point.y), float(point.z)});
        out.projected += projected ? 1 : 0;
      }
    }
  }

  // The nearest of the candidates for node n at x (value off the isovalue):
  // the crossings on the node's own grid edges (linear interpolation of value
  // and isovalue, exactly where extraction puts its vertices) and the root of
  // the trilinear field along the gradient line, which is the foot point on
  // flat stretches. False when there is none.
  bool estimate_closest_point(std::size_t n, const std::array<std::size_t, 3>& coord, const Vec3& x, float value,
                              Vec3& point, bool& projected) const {
    double best = std::numeric_limits<double>::infinity();
    projected = false;
    const std::size_t stride[3] = {1, g_.nx, g_.slice};
    for (int a = 0; a < 3; ++a) {
      for (int direction = -1; direction <= 1; direction += 2) {
        if (direction < 0 ? coord[a] == 0 : coord[a] + 1 == field_.dims[a]) continue;
        const std::size_t m = direction < 0 ? n - stride[a] : n + stride[a];
        if ((flags_[m] & kInside) == (flags_[n] & kInside) || !std::isfinite(field_.values[m])) continue;
        if (masked_ && !edge_in_kept_cell(n, a, direction)) continue;  // a dropped component's crossing
        const double fraction = (double(iso_) - value) / (double(field_.values[m]) - value);
        const double along = std::clamp(fraction, 0.0, 1.0) * field_.spacing[a];
        if (along < best) {
          best = along;
          point = x;
          if (a == 0) point.x += direction * along;
          else if (a == 1) point.y += direction * along;
          else point.z += direction * along;
        }
      }
    }
    const Vec3 gradient = node_gradient(field_, coord[0], coord[1], coord[2]);
    const double g_norm = norm(gradient);
    if (g_norm > 0) {
      const Vec3 u = gradient * (1.0 / g_norm);
      double t = 0;
      if (root_along_gradient(x, u, double(value) - options_.iso, g_norm, std::isfinite(best), t) &&
          std::abs(t) < best && (!masked_ || point_in_kept_cell(x + t * u))) {
        best = std::abs(t);
        point = x + t * u;
        projected = true;
      }
    }
    return std::isfinite(best);
  }

  // The root t of the trilinear field minus the isovalue along x + t u (u the
  // unit gradient, `residual` the node's value minus the isovalue), within
  // the search range and the box. Newton steps from the first-order estimate
  // usually land within the tolerance in one or two samples; the bracketed
  // search runs only where Newton failed near the surface and no edge
  // crossing gives a candidate (`have_edge_candidate`): elsewhere it costs
  // more than the rest of the seeding and gains little.
  bool root_along_gradient(const Vec3& x, const Vec3& u, double residual, double g_norm, bool have_edge_candidate,
                           double& t) const {
    const double first_order = -residual / g_norm;
    // Stay inside the box: the interpolation clamps outside it.
    double reach = search_range_;
    for (int a = 0; a < 3; ++a) {
      const double toward = first_order > 0 ? u[a] : -u[a];
      if (toward > 0) reach = std::min(reach, (box_high_[a] - x[a]) / toward);
      else if (toward < 0) reach = std::min(reach, (box_low_[a] - x[a]) / toward);
    }
    const Vec3 xg = grid_.grid_point(x), ug = grid_.grid_direction(u);
    const auto h = [&](double s) { return grid_.value_at(xg + s * ug) - options_.iso; };
    bool found = false;
    if (reach > 0 && std::abs(first_order) <= reach) {
      t = first_order;
      for (int step = 0; step < 6 && !found; ++step) {
        const TrilinearSample sample = grid_.sample_at(xg + t * ug);
        const double slope = dot(sample.gradient, u);
        if (!(slope > 0) || !std::isfinite(sample.value)) break;
        const double correction = (sample.value - options_.iso) / slope;
        t -= correction;
        found = std::abs(correction) <= 2e-3 * cell_;
      }
      found = found && std::abs(t) <= reach && std::isfinite(t);
    }
    if (!found && reach > 0 && std::abs(first_order) <= reach && !have_edge_candidate)
      found = detail::find_root_along_line(h, residual, first_order, reach, 0.25 * max_spacing_, 2e-3 * cell_, t);
    return found;
  }

  bool cell_kept(std::size_t i, std::size_t j, std::size_t k) const {
    return (flags_[i + g_.nx * j + g_.slice * k] & kKeptCell) != 0;
  }
  bool point_in_kept_cell(const Vec3& p) const {
    std::size_t c[3];
    for (int a = 0; a < 3; ++a) {
      const double gc = std::floor((p[a] - field_.origin[a]) / field_.spacing[a]);
      c[a] = static_cast<std::size_t>(std::clamp(gc, 0.0, double(field_.dims[a] - 2)));
    }
    return cell_kept(c[0], c[1], c[2]);
  }
  // The grid edge from node n one step along `axis` in `direction`: any of
  // the up to 4 cells around it.
  bool edge_in_kept_cell(std::size_t n, int axis, int direction) const {
    const std::size_t k = n / g_.slice, j = (n - k * g_.slice) / g_.nx, i = n - k * g_.slice - j * g_.nx;
    std::size_t low[3] = {i, j, k}, high[3] = {i, j, k};
    for (int a = 0; a < 3; ++a) {
      if (a == axis) {
        if (direction < 0) low[a] = high[a] = low[a] - 1;
        continue;
      }
      if (low[a] > 0) --low[a];
      if (high[a] + 1 >= field_.dims[a]) --high[a];
    }
    for (std::size_t kk = low[2]; kk <= high[2]; ++kk)
      for (std::size_t jj = low[1]; jj <= high[1]; ++jj)
        for (std::size_t ii = low[0]; ii <= high[0]; ++ii)
          if (cell_kept(ii, jj, kk)) return true;
    return false;
  }
  // A grid edge from node n to a finite sample on the other side.
  bool has_crossing_edge(std::size_t n) const {
    if (!std::isfinite(field_.values[n])) return false;
    const std::size_t k = n / g_.slice, j = (n - k * g_.slice) / g_.nx, i = n - k * g_.slice - j * g_.nx;
    const std::size_t coord[3] = {i, j, k}, stride[3] = {1, g_.nx, g_.slice};
    for (int a = 0; a < 3; ++a) {
      if (coord[a] > 0 && (flags_[n - stride[a]] & kInside) != (flags_[n] & kInside) &&
          std::isfinite(field_.values[n - stride[a]]))
        return true;
      if (coord[a] + 1 < field_.dims[a] && (flags_[n + stride[a]] & kInside) != (flags_[n] & kInside) &&
          std::isfinite(field_.values[n + stride[a]]))
        return true;
    }
    return false;
  }

  const Volume& field_;
  const SignedDistanceOptions& options_;
  const HugePageVector<std::uint8_t>& flags_;
  const GridShape g_;
  const float iso_;
  const bool masked_;
  const double cell_, max_spacing_, search_range_;
  const Vec3 box_low_, box_high_;
  const TrilinearGrid grid_;
};

// The propagation's state: per node the squared distance and the closest
// point's index (kQueuedBit while queued), the points, the FIFO queue.
struct Propagation {
  std::vector<float> squared;
  HugePageVector<std::uint32_t> closest;
  std::vector<Point3f> points;
  NodeQueue queue;
  std::vector<std::uint32_t> orphans;  // start nodes of flip_enclosed_regions
  explicit Propagation(std::size_t seeds) : queue(seeds + seeds / 2) {}
};

// Queues the seeds in slice order and collects the orphans, releasing the
// slices' buffers as it goes.
void queue_seeds(const Volume& field, std::vector<SliceSeeds>& slices, HugePageVector<std::uint8_t>& flags,
                 Propagation& state) {
  const GridShape g(field);
  const std::size_t node_count = field.sample_count();
  // Random access at every update: huge pages, faulted in on all threads
  // (the result keeps `squared`).
  reserve_fresh_on_huge_pages(state.squared, node_count);
  state.squared.assign(node_count, std::numeric_limits<float>::infinity());
  reserve_on_huge_pages(state.closest, node_count);
  state.closest.assign(node_count, kNoPoint);
  for (SliceSeeds& s : slices) {
    for (std::size_t q = 0; q < s.nodes.size(); ++q) {
      const std::uint32_t n = s.nodes[q];
      const std::size_t k = n / g.slice, j = (n - k * g.slice) / g.nx, i = n - k * g.slice - j * g.nx;
      const Vec3 x = field.world(double(i), double(j), double(k));
      const Point3f& p = s.points[q];
      const double dx = x.x - p.x, dy = x.y - p.y, dz = x.z - p.z;
      state.squared[n] = static_cast<float>(dx * dx + dy * dy + dz * dz);
      state.closest[n] = static_cast<std::uint32_t>(state.points.size()) | kQueuedBit;
      state.points.push_back(p);
      flags[n] |= kSeed;
      state.queue.push(n);
    }
    state.orphans.insert(state.orphans.end(), s.orphans.begin(), s.orphans.end());
    SliceSeeds().orphans.swap(s.orphans);
    SliceSeeds().nodes.swap(s.nodes);
    SliceSeeds().points.swap(s.points);
  }
  std::vector<SliceSeeds>().swap(slices);
}

// Breadth-first propagation of closest points (float arithmetic: a node's
// position is exact to ~1e-7 relative, far below the accuracy sought); a
// node takes a neighbour's closest point when it is nearer and within the
// band. Frees the points; fills the propagation's statistics.
void propagate(const Volume& field, float band_squared, Propagation& state, SignedDistanceStatistics& stats,
               ProgressSink& progress) {
  const GridShape g(field);
  const std::size_t nx = g.nx, ny = g.ny, nz = g.nz, slice = g.slice, node_count = field.sample_count();
  std::vector<float>& squared = state.squared;
  HugePageVector<std::uint32_t>& closest = state.closest;
  const std::vector<Point3f>& points = state.points;
  NodeQueue& queue = state.queue;
  const float ox = float(field.origin.x), oy = float(field.origin.y), oz = float(field.origin.z);
  const float hx = float(field.spacing.x), hy = float(field.spacing.y), hz = float(field.spacing.z);
  std::size_t pops = 0, updates = 0, peak_queue = queue.size();
  const double inverse_slice = 1.0 / double(slice), inverse_nx = 1.0 / double(nx);
  std::size_t peak_queue_bytes = queue.capacity_bytes();
  const std::size_t report_every = std::size_t{1} << 22;
  while (!queue.empty()) {
    // The queue says which nodes come next: fetch their cache lines (the
    // node's and its y and z neighbours' distance and closest point; for a
    // nearer one its closest point's coordinates) while this one is worked on.
    if (queue.size() > kPrefetchNodesAhead) {
      const std::uint32_t q = queue.peek(kPrefetchNodesAhead);
      __builtin_prefetch(&squared[q]);
      __builtin_prefetch(&closest[q]);
      for (const std::size_t offset : {nx, slice}) {
        if (q >= offset) {
          __builtin_prefetch(&squared[q - offset]);
          __builtin_prefetch(&closest[q - offset]);
        }
        if (q + offset < node_count) {
          __builtin_prefetch(&squared[q + offset]);
          __builtin_prefetch(&closest[q + offset]);
        }
      }
    }
    if (queue.size() > kPrefetchPointsAhead)
      __builtin_prefetch(&points[closest[queue.peek(kPrefetchPointsAhead)] & ~kQueuedBit]);
    const std::uint32_t n = queue.pop();
    const std::uint32_t c = closest[n] & ~kQueuedBit;
    closest[n] = c;
    ++pops;
    if ((pops & (report_every - 1)) == 0) progress.update(0.2 + 0.7 * std::min(1.0, double(pops) / (3.0 * node_count)));
    const Point3f p = points[c];
    // Division by multiplication with the reciprocal, corrected by one step.
    std::size_t k = static_cast<std::size_t>(double(n) * inverse_slice);
    if (k * slice > n) --k;
    else if ((k + 1) * slice <= n) ++k;
    const std::size_t rest = n - k * slice;
    std::size_t j = static_cast<std::size_t>(double(rest) * inverse_nx);
    if (j * nx > rest) --j;
    else if ((j + 1) * nx <= rest) ++j;
    const std::size_t i = rest - j * nx;
    const float x = ox + hx * float(i), y = oy + hy * float(j), z = oz + hz * float(k);
    const auto offer = [&](std::size_t m, float mx, float my, float mz) {
      const float dx = mx - p.x, dy = my - p.y, dz = mz - p.z;
      const float d = dx * dx + dy * dy + dz * dz;
      if (d < squared[m] && d <= band_squared) {
        squared[m] = d;
        ++updates;
        if (!(closest[m] & kQueuedBit)) queue.push(static_cast<std::uint32_t>(m));
        closest[m] = c | kQueuedBit;
      }
    };
    if (i > 0) offer(n - 1, x - hx, y, z);
    if (i + 1 < nx) offer(n + 1, x + hx, y, z);
    if (j > 0) offer(n - nx, x, y - hy, z);
    if (j + 1 < ny) offer(n + nx, x, y + hy, z);
    if (k > 0) offer(n - slice, x, y, z - hz);
    if (k + 1 < nz) offer(n + slice, x, y, z + hz);
    peak_queue = std::max(peak_queue, queue.size());
  }
  peak_queue_bytes = std::max(peak_queue_bytes, queue.capacity_bytes());
  stats.queue_pops = pops;
  stats.updates = updates;
  stats.peak_queue = peak_queue;
  stats.peak_bytes = node_count * (sizeof(float) + sizeof(std::uint32_t) + 1) + points.size() * sizeof(Point3f) +
                     peak_queue_bytes;
  std::vector<Point3f>().swap(state.points);
}

// Signed distances in place of the squared ones: the node's side (flipped
// where kFlip), the distance capped at `far`; a node never reached gets far.
void apply_signs(const Volume& field, const HugePageVector<std::uint8_t>& flags, float far, bool flip,
                 Propagation& state, SignedDistanceStatistics& stats) {
  const GridShape g(field);
  const float outside_sign = flip ? -1.0f : 1.0f;
  std::vector<std::size_t> reached_per_slice(g.nz, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.nz), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      std::size_t reached = 0;
      for (std::size_t n = k * g.slice; n < (k + 1) * g.slice; ++n) {
        const bool inside = ((flags[n] & kInside) != 0) != ((flags[n] & kFlip) != 0);
        const float sign = inside ? -outside_sign : outside_sign;
        if (state.closest[n] != kNoPoint) {
          state.squared[n] = sign * std::min(std::sqrt(state.squared[n]), far);
          ++reached;
        } else {
          state.squared[n] = sign * far;
        }
      }
      reached_per_slice[k] = reached;
    }
  });
  for (std::size_t r : reached_per_slice) stats.reached_nodes += r;
}

}  // namespace

SignedDistanceField compute_signed_distance(const Volume& field, const SignedDistanceOptions& options,
                                            ProgressSink& progress) {
  check_arguments(field, options);
  progress.begin_stage("signed distance");
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  auto phase_start = Clock::now();
  const float iso = static_cast<float>(options.iso);
  const double cell = field.cell_size();
  const Vec3 box_extent = volume_box_max(field) - volume_box_min(field);
  const bool banded = options.band_cells > 0;
  const double far_value = banded ? options.band_cells * cell : norm(box_extent) + cell;
  const float band_squared =
      banded ? static_cast<float>(far_value * far_value) : std::numeric_limits<float>::infinity();

  HugePageVector<std::uint8_t> flags = classify_nodes(field, iso);
  if (options.surface) mark_surface_cells(field, *options.surface, flags);
  mark_crossing_cells(field, iso, flags);
  std::vector<SliceSeeds> slices = SeedFinder(field, options, flags).find_all();
  progress.update(0.2);

  SignedDistanceStatistics stats;
  stats.nodes = field.sample_count();
  for (const SliceSeeds& s : slices) {
    stats.seed_nodes += s.nodes.size();
    stats.projected_seeds += s.projected;
  }
  stats.first_order_seeds = stats.seed_nodes - stats.projected_seeds;
  if (stats.seed_nodes >= kNoPoint) throw Error(ErrorKind::Unsupported, "too many seed nodes");
  Propagation state(stats.seed_nodes);
  state.points.reserve(stats.seed_nodes);
  queue_seeds(field, slices, flags, state);
  stats.seconds_seeding = seconds_since(phase_start);

  phase_start = Clock::now();
  propagate(field, band_squared, state, stats, progress);
  stats.seconds_propagation = seconds_since(phase_start);

  phase_start = Clock::now();
  if (options.surface) flip_enclosed_regions(field, state.orphans, flags, stats);
  apply_signs(field, flags, static_cast<float>(far_value), options.flip, state, stats);
  stats.seconds_finishing = seconds_since(phase_start);

  SignedDistanceField result;
  result.distance.dims = field.dims;
  result.distance.spacing = field.spacing;
  result.distance.origin = field.origin;
  result.distance.source_type = ScalarType::Float32;
  result.distance.values = std::move(state.squared);
  result.iso = options.iso;
  result.flip = options.flip;
  result.band_cells = options.band_cells;
  result.far_value = far_value;
  result.statistics = stats;
  progress.update(1.0);
  progress.end_stage();
  return result;
}

std::size_t mirror_enclosed_samples(const Volume& field, const SignedDistanceField& distance, float* out) {
  assert(distance.distance.dims == field.dims && distance.distance.values.size() == field.values.size());
  const float iso = static_cast<float>(distance.iso);
  const float below = std::nextafter(iso, -std::numeric_limits<float>::infinity());
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, field.values.size(), 1 << 16), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t changed) {
        for (std::size_t n = r.begin(); n < r.end(); ++n) {
          const float f = field.values[n];
          out[n] = f;
          if (!std::isfinite(f)) continue;
          // Inside by the distance field: negative (positive with flip), as
          // compute_signed_distance() signs it.
          const bool inside = std::signbit(distance.distance.values[n]) != distance.flip;
          if (inside == is_inside(f, iso)) continue;
          const float mirrored = static_cast<float>(2.0 * distance.iso - double(f));
          out[n] = inside ? std::max(mirrored, iso) : std::min(mirrored, below);
          ++changed;
        }
        return changed;
      },
      std::plus<>());
}

std::size_t fill_non_finite_samples(const Volume& field, double iso, float* out) {
  struct Scan {
    std::size_t non_finite = 0;
    float lowest = std::numeric_limits<float>::infinity();
  };
  const std::vector<float>& values = field.values;
  const Scan scan = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, values.size(), 1 << 16), Scan{},
      [&](const tbb::blocked_range<std::size_t>& r, Scan partial) {
        for (std::size_t n = r.begin(); n < r.end(); ++n) {
          if (std::isfinite(values[n])) partial.lowest = std::min(partial.lowest, values[n]);
          else ++partial.non_finite;
        }
        return partial;
      },
      [](Scan a, const Scan& b) {
        a.non_finite += b.non_finite;
        a.lowest = std::min(a.lowest, b.lowest);
        return a;
      });
  if (scan.non_finite == 0) return 0;
  // The highest float below iso, and the value of samples with no inside
  // neighbour.
  float below = static_cast<float>(iso);
  if (double(below) >= iso) below = std::nextafter(below, -std::numeric_limits<float>::infinity());
  below = std::max(below, std::numeric_limits<float>::lowest());  // finite even for an iso beyond float's range
  const float outside = std::min(scan.lowest, below);
  const std::size_t stride[3] = {1, field.dims[0], field.dims[0] * field.dims[1]};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, field.dims[2]), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k)
      for (std::size_t j = 0; j < field.dims[1]; ++j)
        for (std::size_t i = 0; i < field.dims[0]; ++i) {
          const std::size_t n = field.index(i, j, k);
          if (std::isfinite(values[n])) continue;
          // Inside neighbours as `out` has them: read only at finite
          // samples, which this loop never writes.
          const std::size_t coordinate[3] = {i, j, k};
          double sum = 0;
          int inside = 0;
          for (int a = 0; a < 3; ++a) {
            if (coordinate[a] > 0 && std::isfinite(values[n - stride[a]]) && out[n - stride[a]] >= iso)
              sum += out[n - stride[a]], ++inside;
            if (coordinate[a] + 1 < field.dims[a] && std::isfinite(values[n + stride[a]]) && out[n + stride[a]] >= iso)
              sum += out[n + stride[a]], ++inside;
          }
          if (inside == 0) {
            out[n] = outside;
            continue;
          }
          const double mirrored = 2.0 * iso - sum / inside;
          out[n] = static_cast<float>(std::clamp(mirrored, double(std::numeric_limits<float>::lowest()), double(below)));
        }
  });
  return scan.non_finite;
}

}  // namespace isowave
