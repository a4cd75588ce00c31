#include "plane_groups.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <zlib.h>

#include "isowave/core/morton.h"

namespace isowave::detail {

namespace {

constexpr std::size_t kFaceGrain = 1 << 14;

// Sums of centroid integers need more than 64 bits (GCC and Clang's extension).
__extension__ typedef __int128 Wide;
__extension__ typedef unsigned __int128 UnsignedWide;

// floor(a / b) for b > 0.
Wide floor_divide(Wide a, Wide b) {
  const Wide q = a / b;
  return q * b > a ? q - 1 : q;
}

int bit_length(UnsignedWide v) {
  int bits = 0;
  for (; v != 0; v >>= 1) ++bits;
  return bits;
}

// A LEB128 value; Error(Format) through `reader` where the payload ends first.
std::uint64_t get_varint(PayloadReader& reader) {
  std::uint64_t v = 0;
  if (!read_varint(reader, v)) reader.fail("is truncated");
  return v;
}

}  // namespace

FaceOrder morton_face_order(const PolygonMesh& base, const std::vector<QuantizedVector>& base_q) {
  const std::size_t faces = base.face_count();
  // Centroids in integers (in parallel), and their range per axis.
  std::vector<std::array<Wide, 3>> centroid(faces);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces, kFaceGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f < r.end(); ++f) {
      const std::uint32_t first = base.face_offsets[f], end = base.face_offsets[f + 1];
      for (std::size_t a = 0; a < 3; ++a) {
        Wide sum = 0;
        for (std::uint32_t k = first; k < end; ++k) sum += base_q[base.face_vertices[k]][a];
        centroid[f][a] = floor_divide(sum, static_cast<Wide>(std::max<std::uint32_t>(end - first, 1)));
      }
    }
  });
  std::array<Wide, 3> low{}, high{};
  for (std::size_t f = 0; f < faces; ++f)
    for (std::size_t a = 0; a < 3; ++a) {
      low[a] = f == 0 ? centroid[f][a] : std::min(low[a], centroid[f][a]);
      high[a] = f == 0 ? centroid[f][a] : std::max(high[a], centroid[f][a]);
    }
  // One shift for all axes keeps the cells cubes (in the integers' units).
  int bits = 0;
  for (std::size_t a = 0; a < 3; ++a) bits = std::max(bits, bit_length(static_cast<UnsignedWide>(high[a] - low[a])));
  const int shift = std::max(0, bits - 21);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(faces);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces, kFaceGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f < r.end(); ++f) {
      std::uint32_t cell[3];
      for (std::size_t a = 0; a < 3; ++a) cell[a] = static_cast<std::uint32_t>((centroid[f][a] - low[a]) >> shift);
      keyed[f] = {morton_code(cell[0], cell[1], cell[2]), static_cast<std::uint32_t>(f)};
    }
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());  // distinct pairs: the same order on any thread count
  FaceOrder order;
  order.faces.resize(faces);
  order.keys.resize(faces);
  for (std::size_t k = 0; k < faces; ++k) {
    order.keys[k] = keyed[k].first;
    order.faces[k] = keyed[k].second;
  }
  return order;
}

std::vector<std::uint32_t> root_faces(const SubdivisionHierarchy& hierarchy, const CoefficientTree& tree) {
  const PolygonMesh& base = hierarchy.base();
  std::vector<std::uint32_t> owner(tree.roots_end, 0);
  std::vector<std::uint8_t> seen(base.vertex_count(), 0);
  for (std::size_t f = 0; f < base.face_count(); ++f)
    for (std::uint32_t k = base.face_offsets[f]; k < base.face_offsets[f + 1]; ++k) {
      const std::uint32_t v = base.face_vertices[k];
      if (!seen[v]) owner[v] = static_cast<std::uint32_t>(f);
      seen[v] = 1;
    }
  if (hierarchy.levels() == 0) return owner;
  const RefinementStep& s = hierarchy.step(1);
  for (std::uint32_t f = 0; f < s.parent_face_count; ++f) owner[s.first_face_vertex() + f] = f;
  for (std::uint32_t e = 0; e < s.parent_edge_count; ++e)
    owner[s.first_edge_vertex() + e] = std::min(s.edge_faces[2 * e], s.edge_faces[2 * e + 1]) - s.first_face_vertex();
  return owner;
}

namespace {

// cut_face_runs()' walk over the octree cells of the sorted keys.
struct RunCutter {
  const FaceOrder& order;
  std::vector<std::uint64_t> before;  // nodes of the faces before position k
  std::size_t target;
  std::vector<std::uint32_t> runs;
  std::uint64_t run_nodes = 0;
  std::uint32_t run_faces = 0;

  // Faces [a, b), whose keys agree above bit 3 s.
  void cell(std::size_t a, std::size_t b, int s) {
    const std::uint64_t nodes = before[b] - before[a];
    if (nodes <= target || s == 0 || order.keys[a] == order.keys[b - 1]) return join(b - a, nodes);
    for (std::size_t first = a; first < b;) {
      const std::uint64_t child = order.keys[first] >> (3 * (s - 1));
      std::size_t last = first + 1;
      while (last < b && order.keys[last] >> (3 * (s - 1)) == child) ++last;
      cell(first, last, s - 1);
      first = last;
    }
  }
  void join(std::size_t faces, std::uint64_t nodes) {
    if (run_faces > 0 && run_nodes + nodes > target) close();
    run_faces += static_cast<std::uint32_t>(faces);
    run_nodes += nodes;
  }
  void close() {
    if (run_faces > 0) runs.push_back(run_faces);
    run_faces = 0;
    run_nodes = 0;
  }
};

}  // namespace

std::vector<std::uint32_t> cut_face_runs(const CoefficientTree& tree, const std::vector<std::uint32_t>& root_face,
                                         const FaceOrder& order, std::size_t target) {
  // Subtree sizes (children have larger indices than their parents), summed per owner.
  std::vector<std::uint32_t> size(tree.nodes, 1);
  for (std::size_t i = tree.nodes; i-- > tree.roots_end;) size[tree.parent[i]] += size[i];
  const std::size_t faces = order.faces.size();
  std::vector<std::uint64_t> face_nodes(faces, 0);
  for (std::size_t r = 0; r < tree.roots_end && faces > 0; ++r) face_nodes[root_face[r]] += size[r];
  RunCutter cutter{order, std::vector<std::uint64_t>(faces + 1, 0), std::max<std::size_t>(target, 1), {}};
  for (std::size_t k = 0; k < faces; ++k) cutter.before[k + 1] = cutter.before[k] + face_nodes[order.faces[k]];
  if (faces > 0) cutter.cell(0, faces, 21);
  cutter.close();
  return cutter.runs;
}

std::vector<std::uint32_t> face_groups(const std::vector<std::uint32_t>& face_order,
                                       const std::vector<std::uint32_t>& runs) {
  std::vector<std::uint32_t> group(face_order.size(), 0);
  std::size_t k = 0;
  for (std::size_t g = 0; g < runs.size(); ++g)
    for (std::uint32_t n = 0; n < runs[g]; ++n) group[face_order[k++]] = static_cast<std::uint32_t>(g);
  return group;
}

std::vector<std::uint32_t> root_groups(const std::vector<std::uint32_t>& root_face,
                                       const std::vector<std::uint32_t>& face_group) {
  std::vector<std::uint32_t> group(root_face.size(), 0);
  if (face_group.empty()) return group;
  for (std::size_t r = 0; r < root_face.size(); ++r) group[r] = face_group[root_face[r]];
  return group;
}

void put_group_index(std::string& out, const GroupIndex& index) {
  std::string payload;
  put_varint(payload, index.runs.size());
  for (const std::uint32_t run : index.runs) put_varint(payload, run);
  for (const float r : index.reach) payload.append(reinterpret_cast<const char*>(&r), 4);
  put_u32(payload, index.table_crc);
  for (const std::uint32_t crc : index.group_crc) put_u32(payload, crc);
  put_section(out, "GIDX", payload);
}

std::string with_crcs(std::string_view payload, std::uint32_t table_crc, const std::vector<std::uint32_t>& groups) {
  const std::size_t tail = 4 * (groups.size() + 1);
  assert(payload.size() >= tail);
  std::string out(payload.substr(0, payload.size() - tail));
  put_u32(out, table_crc);
  for (const std::uint32_t crc : groups) put_u32(out, crc);
  return out;
}

GroupIndex read_group_index(PayloadReader& reader, std::size_t base_faces) {
  GroupIndex index;
  const std::uint64_t groups = get_varint(reader);
  // Every group takes at least 9 bytes (a run, a reach, a CRC).
  if (groups < 1 || groups > reader.remaining() / 9) reader.fail("has an impossible group count");
  index.runs.resize(static_cast<std::size_t>(groups));
  std::uint64_t faces = 0;
  for (std::uint32_t& run : index.runs) {
    const std::uint64_t v = get_varint(reader);
    if (v < 1 || v > base_faces) reader.fail("holds an invalid run of faces");
    run = static_cast<std::uint32_t>(v);
    faces += v;
  }
  if (faces != base_faces) reader.fail("has runs that do not cover the base faces");
  index.reach.resize(index.runs.size());
  for (float& r : index.reach) {
    r = reader.read<float>();
    if (!(r >= 0) || !std::isfinite(r)) reader.fail("holds an invalid reach");
  }
  index.table_crc = reader.read<std::uint32_t>();
  index.group_crc.resize(index.runs.size());
  for (std::uint32_t& crc : index.group_crc) crc = reader.read<std::uint32_t>();
  if (reader.remaining() != 0) reader.fail("has bytes after its groups");
  return index;
}

void face_box(const PolygonMesh& base, const std::vector<Vec3>& frame_base, std::size_t f, double reach, Vec3& lo,
              Vec3& hi) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  lo = {inf, inf, inf};
  hi = {-inf, -inf, -inf};
  for (std::uint32_t k = base.face_offsets[f]; k < base.face_offsets[f + 1]; ++k) {
    lo = component_min(lo, frame_base[base.face_vertices[k]]);
    hi = component_max(hi, frame_base[base.face_vertices[k]]);
  }
  lo -= Vec3{reach, reach, reach};
  hi += Vec3{reach, reach, reach};
}

void set_group_reach(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& frame_base,
                     const std::vector<Vec3>& fine, const std::vector<std::uint32_t>& face_group, GroupIndex& index) {
  std::vector<double> reach(index.count(), 0.0);
  for (std::size_t f = 0; f < face_group.size(); ++f) {
    Vec3 lo, hi;
    face_box(hierarchy.base(), frame_base, f, 0, lo, hi);
    double& r = reach[face_group[f]];
    for_each_fine_point(hierarchy, f, [&](std::size_t v) {
      for (int a = 0; a < 3; ++a) r = std::max({r, lo[a] - fine[v][a], fine[v][a] - hi[a]});
      return true;
    });
  }
  // Rounded up, with room for the rounding of face_box()'s arithmetic.
  index.reach.resize(index.count());
  for (std::size_t g = 0; g < index.count(); ++g) {
    const double r = reach[g] * (1 + 1e-6) + 1e-9;
    index.reach[g] = std::isfinite(r) ? std::nextafter(static_cast<float>(r), std::numeric_limits<float>::infinity())
                                      : std::numeric_limits<float>::max();
  }
}

std::uint32_t bytes_crc(std::string_view bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  for (std::size_t offset = 0; offset < bytes.size(); offset += 1u << 30) {
    const std::size_t n = std::min<std::size_t>(bytes.size() - offset, 1u << 30);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + offset), static_cast<uInt>(n));
  }
  return static_cast<std::uint32_t>(crc);
}

std::vector<std::uint32_t> group_crcs(const std::vector<std::string_view>& packets, std::size_t groups) {
  std::vector<uLong> crc(groups, crc32(0L, Z_NULL, 0));
  for (std::size_t j = 0; j < packets.size(); ++j) {
    uLong& c = crc[j % groups];
    c = crc32(c, reinterpret_cast<const Bytef*>(packets[j].data()), static_cast<uInt>(packets[j].size()));
  }
  return std::vector<std::uint32_t>(crc.begin(), crc.end());
}

}  // namespace isowave::detail
