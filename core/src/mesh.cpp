#include "isowave/core/mesh.h"

#include <algorithm>
#include <cstdint>
#include <unordered_set>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "isowave/core/error.h"

namespace isowave {

std::size_t PolygonMesh::sharp_count() const {
  return static_cast<std::size_t>(std::count_if(sharp.begin(), sharp.end(), [](std::uint8_t s) { return s != 0; }));
}

void PolygonMesh::add_face(const std::uint32_t* vertices, std::size_t count) {
  face_vertices.insert(face_vertices.end(), vertices, vertices + count);
  face_offsets.push_back(static_cast<std::uint32_t>(face_vertices.size()));
}

void PolygonMesh::clear() {
  positions.clear();
  face_offsets.assign(1, 0);
  face_vertices.clear();
  sharp.clear();
}

namespace {

// The smallest i in [0, n) with bad(i), or n: in parallel, yet the same
// answer as a serial scan, so errors always name the first offender.
template <class Predicate>
std::size_t first_where(std::size_t n, const Predicate& bad) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 1 << 16), n,
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t found) {
        for (std::size_t i = r.begin(); i < r.end() && i < found; ++i)
          if (bad(i)) return i;
        return found;
      },
      [](std::size_t a, std::size_t b) { return std::min(a, b); });
}

}  // namespace

void validate_indices(const PolygonMesh& mesh, const std::string& source) {
  const auto fail = [&](const std::string& what) { throw Error(ErrorKind::Format, source + ": " + what); };
  if (mesh.face_offsets.empty() || mesh.face_offsets.front() != 0 ||
      mesh.face_offsets.back() != mesh.face_vertices.size())
    fail("inconsistent face offsets");
  if (!mesh.sharp.empty() && mesh.sharp.size() != mesh.vertex_count())
    fail("sharp flags do not match the vertex count");
  const std::size_t v = first_where(mesh.vertex_count(), [&](std::size_t i) { return !is_finite(mesh.positions[i]); });
  if (v < mesh.vertex_count()) fail("vertex " + std::to_string(v) + " has a non-finite coordinate");
  const std::size_t f = first_where(mesh.face_count(), [&](std::size_t i) {
    return mesh.face_offsets[i + 1] < mesh.face_offsets[i] || mesh.face_size(i) < 3;
  });
  if (f < mesh.face_count()) {
    if (mesh.face_offsets[f + 1] < mesh.face_offsets[f]) fail("inconsistent face offsets");
    fail("face " + std::to_string(f) + " has " + std::to_string(mesh.face_size(f)) + " vertices (at least 3 needed)");
  }
  const std::size_t i = first_where(mesh.face_vertices.size(), [&](std::size_t k) {
    return mesh.face_vertices[k] >= mesh.vertex_count();
  });
  if (i < mesh.face_vertices.size())
    fail("face vertex index " + std::to_string(mesh.face_vertices[i]) + " is out of range (" +
         std::to_string(mesh.vertex_count()) + " vertices)");
}

std::size_t remove_unreferenced_vertices(PolygonMesh& mesh) {
  constexpr std::uint32_t kUnused = ~std::uint32_t{0};
  std::vector<std::uint32_t> new_index(mesh.vertex_count(), kUnused);
  for (std::uint32_t v : mesh.face_vertices) new_index[v] = 0;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < new_index.size(); ++v) {
    if (new_index[v] == kUnused) continue;
    new_index[v] = next;
    mesh.positions[next] = mesh.positions[v];
    if (!mesh.sharp.empty()) mesh.sharp[next] = mesh.sharp[v];
    ++next;
  }
  const std::size_t removed = mesh.vertex_count() - next;
  mesh.positions.resize(next);
  if (!mesh.sharp.empty()) mesh.sharp.resize(next);
  for (std::uint32_t& v : mesh.face_vertices) v = new_index[v];
  return removed;
}

namespace {

std::uint64_t undirected(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t{a} << 32) | b : (std::uint64_t{b} << 32) | a;
}

// A fan around a new vertex at the face's centroid.
void add_centroid_fan(const PolygonMesh& mesh, std::size_t f, PolygonMesh& result) {
  const std::uint32_t* v = mesh.face_begin(f);
  const std::uint32_t n = mesh.face_size(f);
  Vec3 centroid;
  for (std::uint32_t k = 0; k < n; ++k) centroid += mesh.positions[v[k]];
  const std::uint32_t c = static_cast<std::uint32_t>(result.positions.size());
  result.positions.push_back(centroid * (1.0 / double(n)));
  if (!result.sharp.empty()) result.sharp.push_back(0);
  for (std::uint32_t k = 0; k < n; ++k) result.add_face({v[k], v[(k + 1) % n], c});
}

}  // namespace

PolygonMesh triangulate(const PolygonMesh& mesh, QuadSplit split) {
  PolygonMesh result;
  result.positions = mesh.positions;
  result.sharp = mesh.sharp;
  result.face_offsets.reserve(mesh.face_vertices.size());
  result.face_vertices.reserve(3 * mesh.face_vertices.size());
  // ShorterAvoidingEdges: the mesh's edges, sorted, and the diagonals taken.
  std::vector<std::uint64_t> edges;
  std::unordered_set<std::uint64_t> taken;
  if (split == QuadSplit::ShorterAvoidingEdges) {
    edges.reserve(mesh.face_vertices.size());
    for (std::size_t f = 0; f < mesh.face_count(); ++f) {
      const std::uint32_t* v = mesh.face_begin(f);
      for (std::uint32_t k = 0, n = mesh.face_size(f); k < n; ++k) edges.push_back(undirected(v[k], v[(k + 1) % n]));
    }
    std::sort(edges.begin(), edges.end());
  }
  const auto free_diagonal = [&](std::uint32_t a, std::uint32_t b) {
    const std::uint64_t key = undirected(a, b);
    return !std::binary_search(edges.begin(), edges.end(), key) && taken.count(key) == 0;
  };
  for (std::size_t f = 0; f < mesh.face_count(); ++f) {
    const std::uint32_t* v = mesh.face_begin(f);
    const std::uint32_t n = mesh.face_size(f);
    if (n == 3) {
      result.add_face({v[0], v[1], v[2]});
    } else if (n == 4) {
      bool along02 = squared_norm(mesh.positions[v[0]] - mesh.positions[v[2]]) <=
                     squared_norm(mesh.positions[v[1]] - mesh.positions[v[3]]);
      if (split == QuadSplit::ShorterAvoidingEdges) {
        const bool free02 = free_diagonal(v[0], v[2]), free13 = free_diagonal(v[1], v[3]);
        if (!free02 && !free13) {
          add_centroid_fan(mesh, f, result);
          continue;
        }
        along02 = along02 ? free02 : !free13;
        taken.insert(along02 ? undirected(v[0], v[2]) : undirected(v[1], v[3]));
      }
      if (along02) {
        result.add_face({v[0], v[1], v[2]});
        result.add_face({v[0], v[2], v[3]});
      } else {
        result.add_face({v[0], v[1], v[3]});
        result.add_face({v[1], v[2], v[3]});
      }
    } else {
      // A fan from a corner could draw a diagonal that is another face's
      // edge, or slivers along a transition face's straight run of corners.
      add_centroid_fan(mesh, f, result);
    }
  }
  return result;
}

}  // namespace isowave
