// OpenVDB (.vdb) float and double grids, copied into a dense volume over the
// grid's active bounding box.
//
// OpenVDB's readers trust the file: string lengths allocate unchecked, a
// chunk marked "uncompressed" is read into a fixed-size buffer before its
// size is checked, a Blosc chunk's own header is believed, and reads past the
// end leave variables uninitialised. So the file is first walked here,
// mirroring OpenVDB 10's reader (file format 222-224) for float and double
// trees: header, metadata, grid descriptors, transform, topology and every
// value chunk are checked against the bytes that hold them. Only the chosen
// grid is then handed to openvdb::io::Stream, re-packed in memory (file
// metadata and the grid's non-essential metadata dropped) behind a stream
// that throws on any read past the end.
//
// OpenVDB 10's RootNode::readTopology leaks the child it is reading (a
// 32^3 internal node and its subtree, ~300 KB) when that read throws, and the
// child it replaces when two children share an origin. So the walk also
// decompresses every topology chunk as io::readData() will and rejects
// repeated root origins: what is left to throw (leaf value chunks, read by
// readBuffers into a tree the grid owns) leaks nothing.
#include <openvdb/io/Compression.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <istream>
#include <limits>
#include <map>
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
// active voxel count: a few corrupted bytes must not ask for terabytes. (A
// valid file of a few KB with large active tiles may still ask for 8 GiB; fuzz
// builds, whose memory limit is 2 GiB, allow 2^27 samples.)
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
constexpr std::uint64_t kMaxDenseSamples = std::uint64_t{1} << 27;
#else
constexpr std::uint64_t kMaxDenseSamples = std::uint64_t{1} << 31;
#endif

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

// Walks the file-level MetaMap (it is not handed to OpenVDB).
void walk_metadata(Walker& w) {
  const std::uint32_t count = w.u32("metadata count");
  if (count > w.remaining() / 12) w.fail("corrupt metadata count " + std::to_string(count));
  for (std::uint32_t i = 0; i < count; ++i) {
    w.string("metadata name");
    w.string("metadata type");
    w.skip(w.u32("metadata size"), "metadata value");
  }
}

struct GridEntry {
  std::string unique_name;
  std::string name;  // without the uniqueness suffix
  std::string type;  // without _HalfFloat
  bool half = false;
  std::string instance_parent;
  std::uint64_t descriptor_pos = 0;
  std::uint64_t grid_pos = 0, block_pos = 0, end_pos = 0;
};

// Bounded reads over one grid's bytes (OpenVDB writes native little-endian).
class Cursor {
 public:
  Cursor(const std::vector<char>& data, const std::string& path, const std::string& grid)
      : data_(data), path_(path), grid_(grid) {}
  std::size_t pos() const { return pos_; }
  std::size_t remaining() const { return data_.size() - pos_; }
  const std::uint8_t* take(std::size_t n, const char* what) {
    if (n > remaining()) fail(std::string("truncated or corrupt data (") + what + ")");
    const auto* p = reinterpret_cast<const std::uint8_t*>(data_.data() + pos_);
    pos_ += n;
    return p;
  }
  std::string bytes_since(std::size_t begin) const { return std::string(data_.data() + begin, data_.data() + pos_); }
  template <typename T>
  T get(const char* what) {
    T v;
    std::memcpy(&v, take(sizeof(T), what), sizeof(T));
    return v;
  }
  [[noreturn]] void fail(const std::string& what) const { format_error(path_, "grid '" + grid_ + "': " + what); }

 private:
  const std::vector<char>& data_;
  const std::string& path_;
  const std::string& grid_;
  std::size_t pos_ = 0;
};

std::size_t count_on(const std::uint8_t* mask, std::size_t bytes) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < bytes; ++i) n += static_cast<std::size_t>(__builtin_popcount(mask[i]));
  return n;
}

struct TreeFormat {
  std::uint32_t compression = 0;  // per-grid io::COMPRESS_* flags
  std::size_t value_size = 4;     // sizeof(ValueType)
  bool half = false;              // values saved as 16-bit halves
};

// How much of a value chunk the walk checks: its layout, or also that it
// decompresses as io::readData() will (topology chunks: see the top).
enum class ChunkCheck { Layout, Decode };

// Decompresses the compressed chunk at [begin, c.pos()) with OpenVDB's own
// reader; `bytes` is its decompressed size.
void decode_chunk(Cursor& c, std::size_t begin, std::uint64_t bytes, const TreeFormat& f) {
  std::istringstream in(c.bytes_since(begin));
  in.exceptions(std::ios_base::failbit | std::ios_base::badbit);
  std::vector<char> out(std::max<std::size_t>(static_cast<std::size_t>(bytes), 1));  // non-null: decode, not skip
  try {
    if (f.compression & openvdb::io::COMPRESS_BLOSC) {
      openvdb::io::bloscFromStream(in, out.data(), static_cast<std::size_t>(bytes));
    } else {
      openvdb::io::unzipFromStream(in, out.data(), static_cast<std::size_t>(bytes));
    }
  } catch (const std::exception& e) {
    c.fail(std::string("a topology chunk does not decompress (") + e.what() + ")");
  }
}

// One value chunk as io::readData() reads it.
void check_chunk(Cursor& c, std::uint64_t bytes, const TreeFormat& f, ChunkCheck check) {
  if (f.compression & (openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ZIP)) {
    const std::size_t begin = c.pos();
    const auto n = c.get<std::int64_t>("chunk size");
    if (n <= 0) {
      if (n == std::numeric_limits<std::int64_t>::min() || static_cast<std::uint64_t>(-n) != bytes)
        c.fail("corrupt uncompressed chunk size");
      c.take(static_cast<std::size_t>(bytes), "uncompressed chunk");
      return;
    }
    if (static_cast<std::uint64_t>(n) > c.remaining()) c.fail("truncated compressed chunk");
    const std::uint8_t* chunk = c.take(static_cast<std::size_t>(n), "compressed chunk");
    if (f.compression & openvdb::io::COMPRESS_BLOSC) {
      // Blosc header: version, versionlz, flags, typesize, nbytes, blocksize, cbytes.
      std::uint32_t nbytes = 0, cbytes = 0;
      if (n < 16) c.fail("corrupt blosc chunk");
      std::memcpy(&nbytes, chunk + 4, 4);
      std::memcpy(&cbytes, chunk + 12, 4);
      if (nbytes != bytes || cbytes != static_cast<std::uint64_t>(n)) c.fail("corrupt blosc chunk header");
    }
    if (check == ChunkCheck::Decode) decode_chunk(c, begin, bytes, f);
    return;
  }
  c.take(static_cast<std::size_t>(bytes), "values");
}

// io::readCompressedValues() for a node of `count` values with `mask_bytes`-byte masks.
void check_values(Cursor& c, std::size_t count, const std::uint8_t* value_mask, std::size_t mask_bytes,
                  const TreeFormat& f, ChunkCheck check) {
  const auto metadata = c.get<std::int8_t>("value metadata");
  if (metadata == 2 || metadata == 4 || metadata == 5) c.take(f.value_size, "inactive value");
  if (metadata == 5) c.take(f.value_size, "inactive value");
  if (metadata == 3 || metadata == 4 || metadata == 5) c.take(mask_bytes, "selection mask");
  std::size_t stored = count;
  if ((f.compression & openvdb::io::COMPRESS_ACTIVE_MASK) && metadata != 6) stored = count_on(value_mask, mask_bytes);
  if (f.half && stored == 0) return;  // io::HalfReader reads nothing for no values
  check_chunk(c, static_cast<std::uint64_t>(stored) * (f.half ? 2 : f.value_size), f, check);
}

// InternalNode::readTopology(); returns the number of leaves below.
std::uint64_t check_internal_topology(Cursor& c, int log2dim, const TreeFormat& f) {
  const std::size_t values = std::size_t{1} << (3 * log2dim);
  const std::size_t mask_bytes = values / 8;
  const std::uint8_t* child_mask = c.take(mask_bytes, "child mask");
  const std::uint8_t* value_mask = c.take(mask_bytes, "value mask");
  check_values(c, values, value_mask, mask_bytes, f, ChunkCheck::Decode);
  const std::size_t children = count_on(child_mask, mask_bytes);
  if (log2dim == 4) {
    c.take(children * 64, "leaf value masks");  // LeafNode::readTopology(): the value mask
    return children;
  }
  std::uint64_t leaves = 0;
  for (std::size_t i = 0; i < children; ++i) leaves += check_internal_topology(c, log2dim - 1, f);
  return leaves;
}

// The grid's tree (Tree::readTopology() + readBuffers()) for the standard 5-4-3 configuration.
void check_tree(Cursor& c, std::size_t topology_end, std::size_t end, const TreeFormat& f) {
  if (c.get<std::int32_t>("buffer count") != 1) c.fail("corrupt tree (buffer count)");
  c.take(f.value_size, "background");
  const auto tiles = c.get<std::uint32_t>("tile count");
  const auto children = c.get<std::uint32_t>("child count");
  const std::size_t tile_bytes = 12 + f.value_size + 1;
  if (tiles > c.remaining() / tile_bytes || children > c.remaining() / (12 + 8192))
    c.fail("corrupt root node (tile or child count)");
  std::map<std::array<std::int32_t, 3>, std::uint64_t> table;  // leaves below each root entry
  for (std::uint32_t t = 0; t < tiles; ++t) {
    std::array<std::int32_t, 3> key;
    std::memcpy(key.data(), c.take(12, "tile"), 12);
    c.take(f.value_size, "tile value");
    if (c.get<std::uint8_t>("tile state") > 1) c.fail("corrupt root tile");
    if (!table.emplace(key, 0).second) c.fail("corrupt root node (two entries at one origin)");
  }
  for (std::uint32_t n = 0; n < children; ++n) {
    std::array<std::int32_t, 3> key;
    std::memcpy(key.data(), c.take(12, "child origin"), 12);
    for (std::int32_t v : key) {
      if (v % 4096 != 0) c.fail("corrupt root child origin");
    }
    if (!table.emplace(key, check_internal_topology(c, 5, f)).second)
      c.fail("corrupt root node (two entries at one origin)");
  }
  if (c.pos() != topology_end) c.fail("corrupt topology (it does not end where the grid's data blocks start)");
  std::uint64_t leaves = 0;
  for (const auto& entry : table) leaves += entry.second;
  if (leaves > c.remaining() / (64 + 1)) c.fail("truncated or corrupt leaf data");
  for (std::uint64_t l = 0; l < leaves; ++l) {
    const std::uint8_t* mask = c.take(64, "leaf value mask");
    check_values(c, 512, mask, 64, f, ChunkCheck::Layout);
  }
  if (c.pos() != end) c.fail("corrupt data blocks (they do not end where the grid ends)");
}

// Checks a grid (descriptor + data) and appends it to `out` with its
// metadata filtered.
void pack_grid(Walker& w, const GridEntry& g, const std::string& path, std::vector<char>& out) {
  const auto descriptor = w.bytes(g.descriptor_pos, g.grid_pos);
  out.insert(out.end(), descriptor.begin(), descriptor.end());
  const std::vector<char> data = w.bytes(g.grid_pos, g.end_pos);
  Cursor c(data, path, g.name);

  TreeFormat format;
  format.compression = c.get<std::uint32_t>("compression flags");
  format.value_size = g.type == openvdb::DoubleGrid::gridType() ? 8 : 4;
  format.half = g.half;
  put_u32(out, format.compression);

  // Metadata: keep the fixed-size and string entries.
  const auto count = c.get<std::uint32_t>("metadata count");
  if (count > c.remaining() / 12) c.fail("corrupt metadata count");
  std::vector<char> kept;
  std::uint32_t kept_count = 0;
  const auto string = [&](const char* what) {
    const auto n = c.get<std::uint32_t>(what);
    const std::uint8_t* p = c.take(n, what);
    return std::string(reinterpret_cast<const char*>(p), n);
  };
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::size_t start_pos = c.pos();
    const std::string name = string("metadata name");
    const std::string type = string("metadata type");
    const auto bytes = c.get<std::uint32_t>("metadata size");
    const std::uint8_t* value = c.take(bytes, "metadata value");
    std::uint32_t fixed = 0;
    const bool is_fixed = fixed_size_metadata(type, fixed);
    if (is_fixed && bytes != fixed) c.fail("corrupt metadata '" + name + "'");
    if (type == "bool" && value[0] > 1) c.fail("corrupt metadata '" + name + "'");
    if (name == openvdb::GridBase::META_SAVE_HALF_FLOAT) continue;  // written below
    if (is_fixed || type == "string") {
      kept.insert(kept.end(), data.begin() + static_cast<std::ptrdiff_t>(start_pos), data.begin() + static_cast<std::ptrdiff_t>(c.pos()));
      ++kept_count;
    }
  }
  // OpenVDB reads the values as halves when this entry says so, whatever the
  // grid type: it gets the type's _HalfFloat suffix, which the walk follows.
  const auto put_string = [&](const std::string& s) {
    put_u32(kept, static_cast<std::uint32_t>(s.size()));
    kept.insert(kept.end(), s.begin(), s.end());
  };
  put_string(openvdb::GridBase::META_SAVE_HALF_FLOAT);
  put_string("bool");
  put_u32(kept, 1);
  kept.push_back(g.half ? 1 : 0);
  put_u32(out, kept_count + 1);
  out.insert(out.end(), kept.begin(), kept.end());

  // Transform: a registered map type and its fixed-size parameters.
  const std::size_t transform_pos = c.pos();
  const std::string map_type = string("transform type");
  if (!openvdb::math::MapRegistry::isRegistered(map_type)) c.fail("unknown transform type '" + map_type.substr(0, 64) + "'");
  std::ostringstream probe;
  openvdb::math::MapRegistry::createMap(map_type)->write(probe);
  c.take(probe.str().size(), "transform");

  const std::size_t topology_end = static_cast<std::size_t>(g.block_pos - g.grid_pos);
  if (g.instance_parent.empty()) {
    check_tree(c, topology_end, data.size(), format);
  } else if (c.pos() != data.size()) {
    c.fail("corrupt instance grid");
  }
  out.insert(out.end(), data.begin() + static_cast<std::ptrdiff_t>(transform_pos), data.end());
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

// Header: magic, file version, library version, grid offsets flag, UUID.
// Returns the header's end.
std::uint64_t read_file_header(Walker& w) {
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
  return header_end;
}

// The grid descriptors, with their offsets checked against the file.
std::vector<GridEntry> read_grid_descriptors(Walker& w, const InputFile& file) {
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
    if (g.type.size() > half.size() && g.type.compare(g.type.size() - half.size(), half.size(), half) == 0) {
      g.type.resize(g.type.size() - half.size());
      g.half = true;
    }
    g.instance_parent = w.string("grid instance parent");
    const std::int64_t grid_pos = w.i64("grid offsets");
    const std::int64_t block_pos = w.i64("grid offsets");
    const std::int64_t end_pos = w.i64("grid offsets");
    // (OpenVDB leaves the block position of an instance grid at 0.)
    const bool instance = !g.instance_parent.empty();
    if (grid_pos != static_cast<std::int64_t>(w.pos()) || end_pos < grid_pos ||
        (!instance && (block_pos < grid_pos || end_pos < block_pos)) || static_cast<std::uint64_t>(end_pos) > file.size())
      w.fail("truncated or corrupt grid offsets for grid '" + g.name + "'");
    g.grid_pos = static_cast<std::uint64_t>(grid_pos);
    g.block_pos = static_cast<std::uint64_t>(block_pos);
    g.end_pos = static_cast<std::uint64_t>(end_pos);
    grids.push_back(g);
    w.seek(g.end_pos);
  }
  return grids;
}

// options.grid, else the first float or double grid.
const GridEntry& choose_grid(Walker& w, const std::vector<GridEntry>& grids, const VolumeReadOptions& options) {
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
  return *chosen;
}

// A stream of the header, empty file metadata and the chosen grid (after its
// instance parent), for OpenVDB to read.
struct PackedGrids {
  std::vector<char> bytes;
  std::size_t grid_count = 0;
};

PackedGrids repack_grid(Walker& w, const std::vector<GridEntry>& grids, const GridEntry& chosen_grid,
                        std::uint64_t header_end, const std::string& path) {
  const GridEntry* chosen = &chosen_grid;
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
  for (const auto* g : parts) pack_grid(w, *g, path, packed);
  return {std::move(packed), parts.size()};
}

openvdb::GridBase::Ptr read_packed_grid(Walker& w, PackedGrids& packed, const std::string& name) {
  openvdb::GridBase::Ptr grid;
  try {
    MemoryBuffer buffer(packed.bytes);
    std::istream in(&buffer);
    in.exceptions(std::ios_base::failbit | std::ios_base::badbit);
    openvdb::io::Stream stream(in, /*delayLoad=*/false);
    const auto read = stream.getGrids();
    if (!read || read->size() != packed.grid_count || !read->back()) w.fail("corrupt grid '" + name + "'");
    grid = read->back();
  } catch (const Error&) {
    throw;
  } catch (const std::ios_base::failure&) {
    w.fail("truncated or corrupt data in grid '" + name + "'");
  } catch (const openvdb::Exception& e) {
    w.fail("corrupt grid '" + name + "': " + e.what());
  } catch (const std::bad_alloc&) {
    w.fail("corrupt grid '" + name + "' (implausible sizes)");
  } catch (const std::exception& e) {
    w.fail("corrupt grid '" + name + "': " + e.what());
  }
  return grid;
}

Volume densify_grid(Walker& w, const openvdb::GridBase::Ptr& grid, const std::string& path, const std::string& name) {
  Volume volume;
  try {
    if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(grid)) {
      volume = densify(*f, path, name, ScalarType::Float32);
    } else if (auto d = openvdb::gridPtrCast<openvdb::DoubleGrid>(grid)) {
      volume = densify(*d, path, name, ScalarType::Float64);
    } else {
      w.fail("grid '" + name + "' is not a float or double grid");
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {  // e.g. a singular transform
    w.fail("corrupt grid '" + name + "': " + e.what());
  }
  return volume;
}

}  // namespace

Volume read_vdb(const std::string& path, const VolumeReadOptions& options) {
  initialize_openvdb();
  InputFile file(path);
  Walker w(file);
  const std::uint64_t header_end = read_file_header(w);
  walk_metadata(w);
  const std::vector<GridEntry> grids = read_grid_descriptors(w, file);
  const GridEntry& chosen = choose_grid(w, grids, options);
  PackedGrids packed = repack_grid(w, grids, chosen, header_end, path);
  Volume volume = densify_grid(w, read_packed_grid(w, packed, chosen.name), path, chosen.name);
  make_spacing_positive(volume);
  check_geometry(volume, path);
  return volume;
}

}  // namespace isowave::detail
