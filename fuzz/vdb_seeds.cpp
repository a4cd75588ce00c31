// Writes the .vdb seeds into the directory argv[1] (run by make_seeds.py):
// one small grid per compression, a double grid, an instance, and the shapes
// of finding 4 (a topology chunk that does not decompress, two root children
// at one origin, a half grid whose half flag is renamed).
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace {

openvdb::FloatGrid::Ptr density() {
  auto grid = openvdb::FloatGrid::create(-1.0f);
  grid->setName("density");
  grid->setTransform(openvdb::math::Transform::createLinearTransform(0.5));
  for (int x = 0; x < 3; ++x) grid->tree().setValue(openvdb::Coord(x, x % 2, 1), 0.5f * x);
  grid->tree().setValueOff(openvdb::Coord(5, 5, 5), 3.0f);
  return grid;
}

std::string write(const std::string& path, const openvdb::GridPtrVec& grids, std::uint32_t compression) {
  openvdb::io::File file(path);
  file.setCompression(compression);
  file.write(grids);
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void save(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  openvdb::initialize();
  const std::string dir = argv[1];
  write(dir + "/blosc_mask.vdb", {density()}, openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
  auto half = density();
  half->setSaveFloatAsHalf(true);
  std::string half_bytes = write(dir + "/zip_half.vdb", {half}, openvdb::io::COMPRESS_ZIP);
  // The campaign's leak: the half flag's metadata entry renamed (OpenVDB then
  // reads the halves as floats).
  const auto flag = half_bytes.find(openvdb::GridBase::META_SAVE_HALF_FLOAT);
  if (flag == std::string::npos) return 1;
  half_bytes[flag] = 'X';
  save(dir + "/half_flag_renamed.vdb", half_bytes);
  auto d = openvdb::DoubleGrid::create(0.25);
  d->setName("d");
  d->tree().setValue(openvdb::Coord(-3, 2, 9), 1.5);
  d->tree().addTile(1, openvdb::Coord(8, 0, 8), 2.0, true);
  auto instance = density()->copyGrid();
  instance->setName("instance");
  write(dir + "/mask_double_instance.vdb", {density(), d, instance}, openvdb::io::COMPRESS_ACTIVE_MASK);

  // Finding 4: the first zip chunk (the 32^3 node's values) gets an invalid
  // deflate block type, so it does not decompress.
  std::string zip = write(dir + "/corrupt_topology_chunk.vdb", {density()}, openvdb::io::COMPRESS_ZIP);
  for (std::size_t i = 0; i + 10 <= zip.size(); ++i) {
    std::int64_t n = 0;
    std::memcpy(&n, &zip[i], 8);
    const unsigned header = static_cast<unsigned char>(zip[i + 8]) * 256u + static_cast<unsigned char>(zip[i + 9]);
    if (n > 2 && static_cast<std::size_t>(n) <= zip.size() - i - 8 && zip[i + 8] == 0x78 && header % 31 == 0) {
      zip[i + 10] = static_cast<char>(zip[i + 10] | 0x06);
      break;
    }
  }
  save(dir + "/corrupt_topology_chunk.vdb", zip);

  // Finding 4: two root children at origin 0 (the first holds only a tile).
  auto twice = density();
  twice->tree().clear();
  twice->tree().addTile(1, openvdb::Coord(8, 8, 8), 1.0f, true);
  twice->tree().setValue(openvdb::Coord(4101, 3, 2), 1.0f);
  std::string bytes = write(dir + "/repeated_root_origin.vdb", {twice}, openvdb::io::COMPRESS_ACTIVE_MASK);
  const std::int32_t second[3] = {4096, 0, 0}, first[3] = {0, 0, 0};
  const std::string pattern(reinterpret_cast<const char*>(second), 12);
  const auto at = bytes.find(pattern);
  if (at == std::string::npos) return 1;
  std::memcpy(&bytes[at], first, 12);
  save(dir + "/repeated_root_origin.vdb", bytes);
  return 0;
}
