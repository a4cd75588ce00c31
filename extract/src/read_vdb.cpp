// OpenVDB (.vdb) float and double grids, copied into a dense volume over the
// grid's active bounding box.
//
// OpenVDB's readers trust the file (string lengths, counts, unchecked reads
// past the end), so the file is first walked here: header, metadata and grid
// descriptors are checked against the file size, and only the chosen grid is
// handed to openvdb::io::Stream, re-packed in memory with the file metadata
// and the grid's non-essential metadata dropped, through a stream that throws
// on any read past the end.
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <istream>
#include <mutex>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "volume_io_internal.h"

namespace isowave::detail {
namespace {

constexpr std::uint32_t kMinFileVersion = 222;  // per-grid compression flags (OpenVDB >= 2.0)
constexpr std::uint32_t kMaxFileVersion = openvdb::OPENVDB_FILE_VERSION;
// Dense copies are limited to 2^31 samples and, beyond 2^24, to 64 times the
// active voxel count: a few corrupted bytes must not ask for terabytes.
constexpr std::uint64_t kMaxDenseSamples = std::uint64_t{1} << 31;

void initialize_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// Bounded little-endian reads from the file, with positions.
class Walker {
 public:
  explicit Walker(InputFile& file) : file_(file) {}
  std::uint64_t pos() const { return pos_; }
  void seek(std::uint64_t p) {
    if (p > file_.size()) fail("truncated (an offset points past the end of the file)");
    file_.seek(p);
    pos_ = p;
  }
  std::uint64_t remaining() const { return file_.size() - pos_; }
  void read(void* out, std::size_t n, const char* what) {
    if (n > remaining()) fail(std::string("truncated (") + what + ")");
    file_.read_exact(out, n, what);
    pos_ += n;
  }
  std::uint32_t u32(const char* what) {
    std::uint8_t b[4];
    read(b, 4, what);
    return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
  }
  std::int64_t i64(const char* what) {
    std::uint8_t b[8];
    read(b, 8, what);
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= std::uint64_t(b[i]) << (8 * i);
    return static_cast<std::int64_t>(v);
  }
  std::string string(const char* what) {
    const std::uint32_t n = u32(what);
    if (n > remaining()) fail(std::string("truncated or corrupt string length (") + what + ")");
    std::string s(n, '\0');
    read(s.data(), n, what);
    return s;
  }
  void skip(std::uint64_t n, const char* what) {
    if (n > remaining()) fail(std::string("truncated (") + what + ")");
    seek(pos_ + n);
  }
  std::vector<char> bytes(std::uint64_t begin, std::uint64_t end) {
    if (begin > end || end > file_.size()) fail("truncated (grid data)");
    std::vector<char> out(static_cast<std::size_t>(end - begin));
    seek(begin);
    read(out.data(), out.size(), "grid data");
    return out;
  }
  [[noreturn]] void fail(const std::string& what) const { format_error(file_.path(), what); }

 private:
  InputFile& file_;
  std::uint64_t pos_ = 0;
};

void put_u32(std::vector<char>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

// Metadata types whose serialized size is fixed (checked against the file).
bool fixed_size_metadata(const std::string& type, std::uint32_t& size) {
  static const char* const kTypes[] = {"bool",  "int32", "int64", "float", "double", "vec2i", "vec2s", "vec2d",
                                       "vec3i", "vec3s", "vec3d", "vec4i", "vec4s", "vec4d", "mat4s", "mat4d"};
  if (std::find(std::begin(kTypes), std::end(kTypes), type) == std::end(kTypes)) return false;
  if (!openvdb::Metadata::isRegisteredType(type)) return false;
  size = openvdb::Metadata::createMetadata(type)->size();
  return true;
}

// Walks a MetaMap; when `keep` is given, appends a MetaMap holding only the
// fixed-size and string entries (readers for the other types are not safe).
void walk_metadata(Walker& w, std::vector<char>* keep) {
  const std::uint32_t count = w.u32("metadata count");
  if (count > w.remaining() / 12) w.fail("corrupt metadata count " + std::to_string(count));
  std::vector<char> entries;
  std::uint32_t kept = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint64_t start = w.pos();
    const std::string name = w.string("metadata name");
    const std::string type = w.string("metadata type");
    const std::uint32_t bytes = w.u32("metadata size");
    std::uint32_t fixed = 0;
    const bool is_fixed = fixed_size_metadata(type, fixed);
    if (is_fixed && bytes != fixed) w.fail("corrupt metadata '" + name + "' (" + type + " of " + std::to_string(bytes) + " bytes)");
    w.skip(bytes, "metadata value");
    if (keep && (is_fixed || type == "string")) {
      const auto entry = w.bytes(start, w.pos());
      entries.insert(entries.end(), entry.begin(), entry.end());
      ++kept;
    }
  }
  if (keep) {
    put_u32(*keep, kept);
    keep->insert(keep->end(), entries.begin(), entries.end());
  }
}

struct GridEntry {
  std::string unique_name;
  std::string name;  // without the uniqueness suffix
  std::string type;  // without _HalfFloat
  std::string instance_parent;
  std::uint64_t descriptor_pos = 0;
  std::uint64_t grid_pos = 0, end_pos = 0;
};

// Appends a grid (descriptor + data, its metadata filtered) to `out`.
void pack_grid(Walker& w, const GridEntry& g, std::vector<char>& out) {
  const auto descriptor = w.bytes(g.descriptor_pos, g.grid_pos);
  out.insert(out.end(), descriptor.begin(), descriptor.end());
  w.seek(g.grid_pos);
  put_u32(out, w.u32("grid compression flags"));
  walk_metadata(w, &out);
  const std::uint64_t transform_pos = w.pos();
  const std::string map_type = w.string("transform type");
  if (!openvdb::math::MapRegistry::isRegistered(map_type)) w.fail("unknown transform type '" + map_type.substr(0, 64) + "'");
  std::ostringstream probe;
  openvdb::math::MapRegistry::createMap(map_type)->write(probe);
  w.skip(probe.str().size(), "transform");
  if (w.pos() > g.end_pos) w.fail("corrupt grid '" + g.name + "' (its transform runs past the grid's end)");
  const auto rest = w.bytes(transform_pos, g.end_pos);
  out.insert(out.end(), rest.begin(), rest.end());
}

class MemoryBuffer : public std::streambuf {
 public:
  explicit MemoryBuffer(std::vector<char>& data) { setg(data.data(), data.data(), data.data() + data.size()); }

 protected:
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    if (!(which & std::ios_base::in)) return pos_type(off_type(-1));
    off_type base = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? gptr() - eback() : egptr() - eback();
    const off_type target = base + off;
    if (target < 0 || target > egptr() - eback()) return pos_type(off_type(-1));
    setg(eback(), eback() + target, egptr());
    return pos_type(target);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }
};

template <typename GridT>
Volume densify(const GridT& grid, const std::string& path, const std::string& name, ScalarType type) {
  const openvdb::CoordBBox bbox = grid.evalActiveVoxelBoundingBox();
  if (bbox.empty()) format_error(path, "grid '" + name + "' has no active voxels");
  Volume volume;
  volume.source_type = type;
  for (int a = 0; a < 3; ++a)
    volume.dims[a] = static_cast<std::size_t>(std::int64_t(bbox.max()[a]) - std::int64_t(bbox.min()[a]) + 1);
  const long double samples_estimate = static_cast<long double>(volume.dims[0]) * volume.dims[1] * volume.dims[2];
  const std::uint64_t samples =
      samples_estimate > kMaxDenseSamples ? kMaxDenseSamples + 1 : std::uint64_t(volume.dims[0]) * volume.dims[1] * volume.dims[2];
  const std::uint64_t active = grid.activeVoxelCount();
  if (samples > kMaxDenseSamples || (samples > (std::uint64_t{1} << 24) && samples / 64 > active))
    format_error(path, "grid '" + name + "': the active bounding box (" + std::to_string(volume.dims[0]) + " x " +
                           std::to_string(volume.dims[1]) + " x " + std::to_string(volume.dims[2]) +
                           ") is too large for a dense copy");

  const auto& transform = grid.transform();
  if (!transform.isLinear()) format_error(path, "grid '" + name + "' has a non-linear (frustum) transform");
  const openvdb::Mat4d m = transform.baseMap()->getAffineMap()->getMat4();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      if (r != c && std::abs(m(r, c)) > 1e-9 * (std::abs(m(r, r)) + std::abs(m(c, c))))
        format_error(path, "grid '" + name + "' has a rotated or sheared transform (only axis-aligned scaling is supported)");
    }
  }
  volume.spacing = {m(0, 0), m(1, 1), m(2, 2)};
  const openvdb::Vec3d origin = transform.indexToWorld(bbox.min());
  volume.origin = {origin.x(), origin.y(), origin.z()};

  const float background = static_cast<float>(grid.background());
  volume.values.assign(volume.sample_count(), background);
  const openvdb::Coord lo = bbox.min();
  const auto index = [&](const openvdb::Coord& c) {
    return volume.index(static_cast<std::size_t>(c.x() - lo.x()), static_cast<std::size_t>(c.y() - lo.y()),
                        static_cast<std::size_t>(c.z() - lo.z()));
  };
  for (auto it = grid.cbeginValueOn(); it; ++it) {
    const float value = static_cast<float>(*it);
    if (it.isVoxelValue()) {
      volume.values[index(it.getCoord())] = value;
    } else {
      openvdb::CoordBBox tile;
      it.getBoundingBox(tile);
      tile.intersect(bbox);
      for (int z = tile.min().z(); z <= tile.max().z(); ++z)
        for (int y = tile.min().y(); y <= tile.max().y(); ++y) {
          const std::size_t row = index(openvdb::Coord(tile.min().x(), y, z));
          std::fill_n(volume.values.begin() + static_cast<std::ptrdiff_t>(row), tile.max().x() - tile.min().x() + 1, value);
        }
    }
  }
  return volume;
}

}  // namespace

Volume read_vdb(const std::string& path, const VolumeReadOptions& options) {
  initialize_openvdb();
  InputFile file(path);
  Walker w(file);

  // Header: magic, file version, library version, grid offsets flag, UUID.
  const std::int64_t magic = w.i64("header");
  if (magic != openvdb::OPENVDB_MAGIC) w.fail("not an OpenVDB file (bad magic number)");
  const std::uint32_t version = w.u32("header");
  if (version < kMinFileVersion || version > kMaxFileVersion)
    w.fail("unsupported OpenVDB file version " + std::to_string(version) + " (supported: " +
           std::to_string(kMinFileVersion) + " to " + std::to_string(kMaxFileVersion) + ")");
  w.u32("header");
  w.u32("header");
  char has_offsets = 0;
  w.read(&has_offsets, 1, "header");
  if (!has_offsets) w.fail("unsupported: a VDB stream without grid offsets");
  w.skip(36, "header UUID");
  const std::uint64_t header_end = w.pos();

  walk_metadata(w, nullptr);
  const std::int64_t grid_count = static_cast<std::int32_t>(w.u32("grid count"));
  if (grid_count < 0 || static_cast<std::uint64_t>(grid_count) > w.remaining() / 36)
    w.fail("corrupt grid count " + std::to_string(grid_count));

  std::vector<GridEntry> grids;
  for (std::int64_t i = 0; i < grid_count; ++i) {
    GridEntry g;
    g.descriptor_pos = w.pos();
    g.unique_name = w.string("grid name");
    g.name = g.unique_name.substr(0, g.unique_name.find('\x1e'));
    g.type = w.string("grid type");
    const std::string half = "_HalfFloat";
    if (g.type.size() > half.size() && g.type.compare(g.type.size() - half.size(), half.size(), half) == 0)
      g.type.resize(g.type.size() - half.size());
    g.instance_parent = w.string("grid instance parent");
    const std::int64_t grid_pos = w.i64("grid offsets");
    const std::int64_t block_pos = w.i64("grid offsets");
    const std::int64_t end_pos = w.i64("grid offsets");
    if (grid_pos != static_cast<std::int64_t>(w.pos()) || block_pos < grid_pos || end_pos < block_pos ||
        static_cast<std::uint64_t>(end_pos) > file.size())
      w.fail("truncated or corrupt grid offsets for grid '" + g.name + "'");
    g.grid_pos = static_cast<std::uint64_t>(grid_pos);
    g.end_pos = static_cast<std::uint64_t>(end_pos);
    grids.push_back(g);
    w.seek(g.end_pos);
  }

  const std::string float_type = openvdb::FloatGrid::gridType();
  const std::string double_type = openvdb::DoubleGrid::gridType();
  const GridEntry* chosen = nullptr;
  std::string available;
  for (const auto& g : grids) {
    available += (available.empty() ? "" : ", ") + g.name + " (" + g.type + ")";
    const bool scalar = g.type == float_type || g.type == double_type;
    if (!chosen && (options.grid.empty() ? scalar : (g.name == options.grid || g.unique_name == options.grid))) chosen = &g;
  }
  if (!chosen) {
    if (options.grid.empty()) w.fail("missing field: no float or double grid (grids: " + (available.empty() ? "none" : available) + ")");
    w.fail("missing grid '" + options.grid + "' (grids: " + (available.empty() ? "none" : available) + ")");
  }
  if (chosen->type != float_type && chosen->type != double_type)
    w.fail("grid '" + chosen->name + "' has type " + chosen->type + " (only float and double grids are supported)");

  // Re-pack: header, empty file metadata, the chosen grid (after its instance parent).
  std::vector<char> packed = w.bytes(0, header_end);
  put_u32(packed, 0);
  std::vector<const GridEntry*> parts;
  if (!chosen->instance_parent.empty()) {
    const auto parent = std::find_if(grids.begin(), grids.end(),
                                     [&](const GridEntry& g) { return g.unique_name == chosen->instance_parent; });
    if (parent == grids.end() || parent->type != chosen->type || !parent->instance_parent.empty())
      w.fail("grid '" + chosen->name + "' is an instance of a missing or unsupported grid");
    parts.push_back(&*parent);
  }
  parts.push_back(chosen);
  put_u32(packed, static_cast<std::uint32_t>(parts.size()));
  for (const auto* g : parts) pack_grid(w, *g, packed);

  openvdb::GridBase::Ptr grid;
  try {
    MemoryBuffer buffer(packed);
    std::istream in(&buffer);
    in.exceptions(std::ios_base::failbit | std::ios_base::badbit);
    openvdb::io::Stream stream(in, /*delayLoad=*/false);
    const auto read = stream.getGrids();
    if (!read || read->size() != parts.size() || !read->back()) w.fail("corrupt grid '" + chosen->name + "'");
    grid = read->back();
  } catch (const Error&) {
    throw;
  } catch (const std::ios_base::failure&) {
    w.fail("truncated or corrupt data in grid '" + chosen->name + "'");
  } catch (const openvdb::Exception& e) {
    w.fail("corrupt grid '" + chosen->name + "': " + e.what());
  } catch (const std::bad_alloc&) {
    w.fail("corrupt grid '" + chosen->name + "' (implausible sizes)");
  } catch (const std::exception& e) {
    w.fail("corrupt grid '" + chosen->name + "': " + e.what());
  }

  Volume volume;
  if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(grid)) {
    volume = densify(*f, path, chosen->name, ScalarType::Float32);
  } else if (auto d = openvdb::gridPtrCast<openvdb::DoubleGrid>(grid)) {
    volume = densify(*d, path, chosen->name, ScalarType::Float64);
  } else {
    w.fail("grid '" + chosen->name + "' is not a float or double grid");
  }
  make_spacing_positive(volume);
  check_geometry(volume, path);
  return volume;
}

}  // namespace isowave::detail
