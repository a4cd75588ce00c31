// Manifold marching cubes (see isosurface.h for the rules and why they give a
// 2-manifold).
//
// Cell numbering: corner c = dx + 2 dy + 4 dz. Edges 0-3 run along x (at
// (dy, dz) = 00, 10, 01, 11), 4-7 along y (at (dx, dz) = 00, 10, 01, 11),
// 8-11 along z (at (dx, dy) = 00, 10, 01, 11). Face 2 a + s is the face
// normal to axis a on side s (0: low, 1: high).
//
// All case analysis happens once, in a table indexed by the cell's 8 inside
// bits and the decisions of its ambiguous faces (256 x 64 entries): the hot
// loop only classifies samples, places edge vertices and copies triangles.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/extract/isosurface.h"
#include "contour_rules.h"

namespace isowave {
namespace {

constexpr int kEdgeCorners[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                     {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

int edge_between(int a, int b) {
  for (int e = 0; e < 12; ++e)
    if ((kEdgeCorners[e][0] == a && kEdgeCorners[e][1] == b) || (kEdgeCorners[e][0] == b && kEdgeCorners[e][1] == a))
      return e;
  assert(false);
  return -1;
}

// Corners of each face in counter-clockwise order seen from outside the cell
// (right-handed about the outward normal), and the edge from corner i to i+1.
struct FaceTable {
  std::array<std::array<int, 4>, 6> corners;
  std::array<std::array<int, 4>, 6> edges;
  FaceTable() {
    for (int face = 0; face < 6; ++face) {
      const int axis = face / 2, side = face % 2;
      // (axis, b, c) cyclic; for the low side swap so u x v = -axis.
      const int b = (axis + 1) % 3, c = (axis + 2) % 3;
      const int u = side ? b : c, v = side ? c : b;
      const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int i = 0; i < 4; ++i) corners[face][i] = (side << axis) | (uv[i][0] << u) | (uv[i][1] << v);
      for (int i = 0; i < 4; ++i) edges[face][i] = edge_between(corners[face][i], corners[face][(i + 1) % 4]);
    }
  }
};

const FaceTable& face_table() {
  static const FaceTable table;
  return table;
}

constexpr int kMaxCentroids = 4;
constexpr std::uint8_t kCentroidCode = 12;  // codes 12.. name the cell's centroid vertices

struct CellEntry {
  std::uint8_t triangle_count = 0;
  std::uint8_t centroid_count = 0;
  std::array<std::uint8_t, 36> triangles{};                   // vertex codes: edge 0-11 or 12 + centroid
  std::array<std::uint16_t, kMaxCentroids> centroid_edges{};  // bit e: loop passes edge e
};

struct CaseTable {
  std::array<std::uint8_t, 256> ambiguous_faces{};  // bit f: face f has four crossings
  std::vector<CellEntry> entries;                   // [case * 64 + decisions]

  CaseTable() : entries(256 * 64) {
    const FaceTable& faces = face_table();
    // Faces each edge lies on, to find loop vertices sharing a face.
    std::array<std::uint8_t, 12> edge_faces{};
    for (int face = 0; face < 6; ++face)
      for (int e : faces.edges[face]) edge_faces[e] |= static_cast<std::uint8_t>(1u << face);

    for (int cube = 0; cube < 256; ++cube) {
      const auto inside = [cube](int corner) { return (cube >> corner) & 1; };
      for (int face = 0; face < 6; ++face) {
        int crossings = 0;
        for (int i = 0; i < 4; ++i)
          crossings += inside(faces.corners[face][i]) != inside(faces.corners[face][(i + 1) % 4]);
        if (crossings == 4) ambiguous_faces[cube] |= static_cast<std::uint8_t>(1u << face);
      }
      for (int decisions = 0; decisions < 64; ++decisions) {
        if ((decisions & ~ambiguous_faces[cube]) != 0) continue;  // never looked up
        std::array<int, 12> next;
        next.fill(-1);
        for (int face = 0; face < 6; ++face) {
          const auto& corner = faces.corners[face];
          const auto& edge = faces.edges[face];
          int positions[4], count = 0;
          for (int i = 0; i < 4; ++i)
            if (inside(corner[i]) != inside(corner[(i + 1) % 4])) positions[count++] = i;
          const bool connected = (decisions >> face) & 1;
          for (int p = 0; p < count; ++p) {
            const int i = positions[p];
            // Only segments leaving an "entering" crossing (outside -> inside
            // counter-clockwise); the segment ends at an exiting crossing:
            // the next one counter-clockwise, or the previous one when the
            // two inside corners of an ambiguous face are connected.
            if (inside(corner[i])) continue;
            const int partner =
                (count == 4 && connected) ? positions[(p + count - 1) % count] : positions[(p + 1) % count];
            next[edge[i]] = edge[partner];
          }
        }
        CellEntry& entry = entries[cube * 64 + decisions];
        std::array<bool, 12> visited{};
        for (int start = 0; start < 12; ++start) {
          if (next[start] < 0 || visited[start]) continue;
          std::vector<int> loop;
          for (int e = start; !visited[e]; e = next[e]) {
            assert(next[e] >= 0);
            visited[e] = true;
            loop.push_back(e);
          }
          const int n = static_cast<int>(loop.size());
          assert(n >= 3);
          // No diagonal may join two vertices on a common cube face: it
          // would lie on that face, where the neighbouring cell could use it
          // too. A fan from an apex with no such partner when one exists,
          // else any triangulation of allowed diagonals (dynamic programming
          // over sub-polygons), else a fan around a centroid vertex.
          const auto allowed = [&](int a, int b) {
            const int gap = std::abs(a - b);
            return gap == 1 || gap == n - 1 || !(edge_faces[loop[a]] & edge_faces[loop[b]]);
          };
          const auto add = [&entry](int a, int b, int c) {
            std::uint8_t* t = &entry.triangles[3 * entry.triangle_count++];
            t[0] = static_cast<std::uint8_t>(a);
            t[1] = static_cast<std::uint8_t>(b);
            t[2] = static_cast<std::uint8_t>(c);
          };
          int apex = -1;
          for (int a = 0; a < n && apex < 0; ++a) {
            bool ok = true;
            for (int d = 2; d <= n - 2; ++d) ok = ok && allowed(a, (a + d) % n);
            if (ok) apex = a;
          }
          // split[i][j]: a vertex k that triangulates the sub-polygon i..j
          // with triangle (i, k, j), or -1 if none (j = i + 1 needs none).
          std::vector<std::vector<int>> split(static_cast<std::size_t>(n),
                                              std::vector<int>(static_cast<std::size_t>(n), -1));
          const auto solvable = [&](int i, int j) { return j == i + 1 || split[i][j] >= 0; };
          for (int length = 2; length < n; ++length)
            for (int i = 0; i + length < n; ++i) {
              const int j = i + length;
              for (int k = i + 1; k < j && split[i][j] < 0; ++k)
                if (allowed(i, k) && allowed(k, j) && solvable(i, k) && solvable(k, j)) split[i][j] = k;
            }
          if (apex >= 0) {
            for (int d = 1; d + 1 < n; ++d) add(loop[apex], loop[(apex + d) % n], loop[(apex + d + 1) % n]);
          } else if (split[0][n - 1] >= 0) {
            std::vector<std::pair<int, int>> pending{{0, n - 1}};
            while (!pending.empty()) {
              const auto [i, j] = pending.back();
              pending.pop_back();
              if (j == i + 1) continue;
              const int k = split[i][j];
              add(loop[i], loop[k], loop[j]);
              pending.push_back({i, k});
              pending.push_back({k, j});
            }
          } else {
            assert(entry.centroid_count < kMaxCentroids);
            const std::uint8_t centre = static_cast<std::uint8_t>(kCentroidCode + entry.centroid_count);
            std::uint16_t mask = 0;
            for (int e : loop) mask |= static_cast<std::uint16_t>(1u << e);
            entry.centroid_edges[entry.centroid_count++] = mask;
            for (int d = 0; d < n; ++d) add(centre, loop[d], loop[(d + 1) % n]);
          }
        }
      }
    }
  }
};

const CaseTable& case_table() {
  static const CaseTable table;
  return table;
}

constexpr std::uint32_t kGhost = 0x80000000u;  // vertex owned by the next slab
constexpr std::size_t kLayersPerSlab = 8;      // fixed: the output must not depend on threads

struct SlabOutput {
  std::vector<Vec3> positions;
  std::vector<std::uint32_t> triangles;  // local ids, kGhost set for the next slab's vertices
  std::vector<std::uint32_t> sharp;      // local ids of sharp vertices
  std::size_t centroids = 0;
};

class Contourer {
 public:
  Contourer(const Volume& volume, double iso, bool reverse)
      : volume_(volume),
        iso_(iso),
        reverse_(reverse),
        nx_(volume.dims[0]),
        ny_(volume.dims[1]),
        nz_(volume.dims[2]),
        plane_(nx_ * ny_),
        values_(volume.values.data()),
        table_(case_table()) {}

  void run_slab(std::size_t k_begin, std::size_t k_end, SlabOutput& out) const {
    SlabState state(plane_);
    std::uint32_t owned = 0, ghost = 0;
    classify(k_begin, state.inside_low.data());
    make_level_vertices(k_begin, state.inside_low.data(), state.x_low.data(), state.y_low.data(), out, owned, ghost,
                        true);
    for (std::size_t k = k_begin; k < k_end; ++k) {
      classify(k + 1, state.inside_high.data());
      make_z_vertices(k, state.inside_low.data(), state.inside_high.data(), state.z.data(), out, owned);
      const bool own_high = k + 1 < k_end || k + 1 == nz_ - 1;
      make_level_vertices(k + 1, state.inside_high.data(), state.x_high.data(), state.y_high.data(), out, owned, ghost,
                          own_high);
      make_cells(k, state, out, owned);
      std::swap(state.inside_low, state.inside_high);
      std::swap(state.x_low, state.x_high);
      std::swap(state.y_low, state.y_high);
    }
  }

 private:
  struct SlabState {
    explicit SlabState(std::size_t plane)
        : inside_low(plane), inside_high(plane), x_low(plane), y_low(plane), x_high(plane), y_high(plane), z(plane) {}
    std::vector<std::uint8_t> inside_low, inside_high;
    // Vertex id of each crossed edge starting at sample (i, j) of the plane.
    std::vector<std::uint32_t> x_low, y_low, x_high, y_high, z;
  };

  bool inside(float value) const { return contour_rules::is_inside(value, iso_); }

  void classify(std::size_t k, std::uint8_t* inside_flags) const {
    const float* slice = values_ + k * plane_;
    for (std::size_t n = 0; n < plane_; ++n) inside_flags[n] = inside(slice[n]) ? 1 : 0;
  }

  // World position of the crossing on the edge from sample index a along axis.
  Vec3 edge_point(std::size_t i, std::size_t j, std::size_t k, int axis) const {
    const std::size_t a = i + nx_ * (j + ny_ * k);
    const std::size_t b = a + (axis == 0 ? 1 : axis == 1 ? nx_ : plane_);
    const double t = contour_rules::crossing_fraction(values_[a], values_[b], iso_);
    double index[3] = {static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)};
    index[axis] += t;
    return volume_.world(index[0], index[1], index[2]);
  }

  bool on_box_edge(std::size_t i, std::size_t j, std::size_t k, int axis) const {
    const bool at_x = i == 0 || i == nx_ - 1, at_y = j == 0 || j == ny_ - 1, at_z = k == 0 || k == nz_ - 1;
    return axis == 0 ? at_y && at_z : axis == 1 ? at_x && at_z : at_x && at_y;
  }

  std::uint32_t new_vertex(std::size_t i, std::size_t j, std::size_t k, int axis, SlabOutput& out,
                           std::uint32_t& owned) const {
    out.positions.push_back(edge_point(i, j, k, axis));
    if (on_box_edge(i, j, k, axis)) out.sharp.push_back(owned);
    return owned++;
  }

  // x- and y-edges of plane k, in the same order whether owned or ghost (the
  // next slab numbers its first plane's vertices in this order).
  void make_level_vertices(std::size_t k, const std::uint8_t* in, std::uint32_t* x_ids, std::uint32_t* y_ids,
                           SlabOutput& out, std::uint32_t& owned, std::uint32_t& ghost, bool own) const {
    for (std::size_t j = 0; j < ny_; ++j) {
      const std::uint8_t* row = in + nx_ * j;
      for (std::size_t i = 0; i < nx_; ++i) {
        const std::size_t n = i + nx_ * j;
        if (i + 1 < nx_ && row[i] != row[i + 1]) x_ids[n] = own ? new_vertex(i, j, k, 0, out, owned) : kGhost | ghost++;
        if (j + 1 < ny_ && row[i] != row[i + nx_])
          y_ids[n] = own ? new_vertex(i, j, k, 1, out, owned) : kGhost | ghost++;
      }
    }
  }

  void make_z_vertices(std::size_t k, const std::uint8_t* low, const std::uint8_t* high, std::uint32_t* z_ids,
                       SlabOutput& out, std::uint32_t& owned) const {
    for (std::size_t j = 0; j < ny_; ++j)
      for (std::size_t i = 0; i < nx_; ++i) {
        const std::size_t n = i + nx_ * j;
        if (low[n] != high[n]) z_ids[n] = new_vertex(i, j, k, 2, out, owned);
      }
  }

  // Asymptotic decider for face `face` of the cell at (i, j, k): are its two
  // inside corners connected? Uses only the face's four samples and
  // commutative products, so both cells sharing the face agree exactly.
  bool inside_corners_connected(std::size_t base, int face, const std::size_t* corner_offset, int cube) const {
    const auto& corner = face_table().corners[face];
    double f[4];
    for (int q = 0; q < 4; ++q) f[q] = static_cast<double>(values_[base + corner_offset[corner[q]]]) - iso_;
    return contour_rules::inside_corners_joined(f[0], f[1], f[2], f[3], (cube >> corner[0]) & 1);
  }

  void make_cells(std::size_t k, SlabState& s, SlabOutput& out, std::uint32_t& owned) const {
    const std::uint8_t* low = s.inside_low.data();
    const std::uint8_t* high = s.inside_high.data();
    const std::size_t corner_offset[8] = {0, 1, nx_, nx_ + 1, plane_, plane_ + 1, plane_ + nx_, plane_ + nx_ + 1};
    std::uint32_t ids[12 + kMaxCentroids];
    for (std::size_t j = 0; j + 1 < ny_; ++j) {
      const std::size_t row = nx_ * j;
      for (std::size_t i = 0; i + 1 < nx_; ++i) {
        const std::size_t n = row + i;
        const int cube = low[n] | (low[n + 1] << 1) | (low[n + nx_] << 2) | (low[n + nx_ + 1] << 3) | (high[n] << 4) |
                         (high[n + 1] << 5) | (high[n + nx_] << 6) | (high[n + nx_ + 1] << 7);
        if (cube == 0 || cube == 255) continue;
        int decisions = 0;
        const std::uint8_t ambiguous = table_.ambiguous_faces[cube];
        if (ambiguous) {
          const std::size_t base = n + plane_ * k;
          for (int face = 0; face < 6; ++face)
            if (((ambiguous >> face) & 1) && inside_corners_connected(base, face, corner_offset, cube))
              decisions |= 1 << face;
        }
        const CellEntry& entry = table_.entries[cube * 64 + decisions];
        ids[0] = s.x_low[n];
        ids[1] = s.x_low[n + nx_];
        ids[2] = s.x_high[n];
        ids[3] = s.x_high[n + nx_];
        ids[4] = s.y_low[n];
        ids[5] = s.y_low[n + 1];
        ids[6] = s.y_high[n];
        ids[7] = s.y_high[n + 1];
        ids[8] = s.z[n];
        ids[9] = s.z[n + 1];
        ids[10] = s.z[n + nx_];
        ids[11] = s.z[n + nx_ + 1];
        for (int c = 0; c < entry.centroid_count; ++c)
          ids[12 + c] = make_centroid(i, j, k, entry.centroid_edges[c], out, owned);
        const std::size_t first = out.triangles.size();
        out.triangles.resize(first + 3 * entry.triangle_count);
        std::uint32_t* t = out.triangles.data() + first;
        for (int v = 0; v < 3 * entry.triangle_count; v += 3) {
          t[v] = ids[entry.triangles[v]];
          t[v + 1] = ids[entry.triangles[v + (reverse_ ? 2 : 1)]];
          t[v + 2] = ids[entry.triangles[v + (reverse_ ? 1 : 2)]];
        }
      }
    }
  }

  std::uint32_t make_centroid(std::size_t i, std::size_t j, std::size_t k, std::uint16_t edges, SlabOutput& out,
                              std::uint32_t& owned) const {
    // Edge e starts at corner kEdgeCorners[e][0]; its axis is e / 4.
    Vec3 sum;
    int count = 0;
    for (int e = 0; e < 12; ++e) {
      if (!((edges >> e) & 1)) continue;
      const int corner = kEdgeCorners[e][0];
      sum += edge_point(i + (corner & 1), j + ((corner >> 1) & 1), k + ((corner >> 2) & 1), e / 4);
      ++count;
    }
    out.positions.push_back(sum * (1.0 / count));
    ++out.centroids;
    return owned++;
  }

  const Volume& volume_;
  double iso_;
  bool reverse_;
  std::size_t nx_, ny_, nz_, plane_;
  const float* values_;
  const CaseTable& table_;
};

}  // namespace

PolygonMesh contour_volume(const Volume& volume, double iso, bool flip, std::size_t* centroid_vertices) {
  if (!std::isfinite(iso)) throw Error(ErrorKind::InvalidArgument, "the isovalue must be finite");
  const auto& dims = volume.dims;
  if (dims[0] < 2 || dims[1] < 2 || dims[2] < 2)
    throw Error(ErrorKind::InvalidArgument, "contouring needs at least 2 samples along each axis (the volume has " +
                                                std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                                                std::to_string(dims[2]) + ")");
  assert(volume.values.size() == volume.sample_count());
  // A mirrored grid (negative spacing along an odd number of axes) mirrors
  // the triangles; undo that so normals still point toward lower values.
  const bool mirrored = ((volume.spacing.x < 0) != (volume.spacing.y < 0)) != (volume.spacing.z < 0);
  const Contourer contourer(volume, iso, flip != mirrored);

  const std::size_t layers = dims[2] - 1;
  const std::size_t slab_count = (layers + kLayersPerSlab - 1) / kLayersPerSlab;
  std::vector<SlabOutput> slabs(slab_count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slab_count, 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t s = range.begin(); s != range.end(); ++s) {
                        contourer.run_slab(s * kLayersPerSlab, std::min(layers, (s + 1) * kLayersPerSlab), slabs[s]);
                        slabs[s].positions.shrink_to_fit();
                        slabs[s].triangles.shrink_to_fit();
                      }
                    });

  // Global numbering: each slab's vertices follow the previous slabs'.
  std::vector<std::size_t> vertex_base(slab_count + 1, 0), triangle_base(slab_count + 1, 0);
  for (std::size_t s = 0; s < slab_count; ++s) {
    vertex_base[s + 1] = vertex_base[s] + slabs[s].positions.size();
    triangle_base[s + 1] = triangle_base[s] + slabs[s].triangles.size() / 3;
  }
  const std::size_t vertex_count = vertex_base[slab_count], triangle_count = triangle_base[slab_count];
  if (vertex_count >= kGhost || 3 * triangle_count >= std::numeric_limits<std::uint32_t>::max())
    throw Error(ErrorKind::Unsupported, "the isosurface has " + std::to_string(vertex_count) + " vertices and " +
                                            std::to_string(triangle_count) +
                                            " triangles, more than 32-bit indices can address");
  std::size_t sharp_total = 0, centroid_total = 0;
  for (const SlabOutput& slab : slabs) {
    sharp_total += slab.sharp.size();
    centroid_total += slab.centroids;
  }
  if (centroid_vertices) *centroid_vertices = centroid_total;

  PolygonMesh mesh;
  mesh.positions.resize(vertex_count);
  mesh.face_vertices.resize(3 * triangle_count);
  mesh.face_offsets.resize(triangle_count + 1);
  if (sharp_total) mesh.sharp.assign(vertex_count, 0);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, slab_count, 1), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t s = range.begin(); s != range.end(); ++s) {
          SlabOutput& slab = slabs[s];
          const auto base = static_cast<std::uint32_t>(vertex_base[s]);
          const auto next_base = static_cast<std::uint32_t>(vertex_base[s + 1]);
          std::copy(slab.positions.begin(), slab.positions.end(), mesh.positions.begin() + vertex_base[s]);
          std::uint32_t* faces = mesh.face_vertices.data() + 3 * triangle_base[s];
          for (std::size_t c = 0; c < slab.triangles.size(); ++c) {
            const std::uint32_t id = slab.triangles[c];
            faces[c] = (id & kGhost) ? next_base + (id & ~kGhost) : base + id;
          }
          for (std::size_t t = triangle_base[s]; t < triangle_base[s + 1]; ++t)
            mesh.face_offsets[t + 1] = static_cast<std::uint32_t>(3 * (t + 1));
          for (std::uint32_t v : slab.sharp) mesh.sharp[base + v] = 1;
          slab = SlabOutput();  // release the slab's memory as soon as it is copied
        }
      });
  return mesh;
}

}  // namespace isowave
