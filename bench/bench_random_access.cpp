// Random access in a version 2.2 file (issue #48, item 5): the file's own
// coefficients re-encoded at several group sizes (tree nodes per group), and
// for each the file's size against 2.1's (the cost of the groups) and a
// region decode (decode --roi with nothing kept outside): the bytes it reads
// against the file's and its base mesh's (BASE and BPTS), the groups it
// decodes, and its time (best of 3: read_isw with the region, then
// region_mesh()). First the file as given: its region decode (best of 3),
// the decode's peak patch, and its mesh against region_mesh() of the
// complete decode (faces equal; the largest distance of a vertex inside the
// region, in units of the region box's diagonal). The target (miranda, a box
// of 5% of the volume): bytes read <= 10% of the file plus the base mesh,
// decode <= 0.2 s, inside within 1e-6 of the box.
//
// usage: bench_random_access FILE.isw --roi X0,Y0,Z0,X1,Y1,Z1 [--group-nodes N,N,...]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "isowave/codec/isw_format.h"
#include "isowave/codec/region.h"
#include "isowave/core/error.h"

using namespace isowave;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::vector<std::size_t> numbers(const std::string& text) {
  std::vector<std::size_t> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) out.push_back(std::stoul(item));
  return out;
}

std::uint64_t base_mesh_bytes(const IswDecoded& d) {
  std::uint64_t bytes = 0;
  for (const IswSectionInfo& s : d.sections)
    if (s.tag == "BASE" || s.tag == "BPTS") bytes += s.bytes;
  return bytes;
}

// The file as given: a region decode's time and its mesh against the complete decode's.
void compare_with_complete(const std::string& path, const IswDecoded& complete, const RegionOfInterest& region) {
  IswDecodeOptions read;
  read.region = region;
  double decode_best = 1e9, mesh_best = 1e9;
  IswDecoded part;
  PolygonMesh mesh;
  for (int k = 0; k < 3; ++k) {
    const auto start = Clock::now();
    part = read_isw(path, read);
    decode_best = std::min(decode_best, seconds_since(start));
    const auto mesh_start = Clock::now();
    mesh = region_mesh(part, region, 0);
    mesh_best = std::min(mesh_best, seconds_since(mesh_start));
  }
  const PolygonMesh whole = region_mesh(complete, region, 0);
  const bool same_faces = whole.face_vertices == mesh.face_vertices && whole.positions.size() == mesh.positions.size();
  double largest = 0;
  std::size_t inside = 0;
  for (std::size_t v = 0; same_faces && v < whole.positions.size(); ++v)
    if (region.contains(whole.positions[v])) {
      ++inside;
      largest = std::max(largest, norm(mesh.positions[v] - whole.positions[v]));
    }
  const double diagonal = region.shape == RegionOfInterest::Shape::Box ? norm(region.high - region.low) : 2 * region.radius;
  std::printf("as given: region decode %.3f s + mesh %.3f s, read %llu of %llu bytes, %zu of %zu groups; patch of %zu "
              "base faces (%zu fine control points) of %zu; mesh %zu vertices, %zu faces; faces %s the complete "
              "decode's, %zu vertices inside, largest distance there %.3g of the box's diagonal\n",
              decode_best, mesh_best, static_cast<unsigned long long>(part.file_bytes_read),
              static_cast<unsigned long long>(part.file_bytes), part.stream.groups_decoded, part.stream.groups,
              part.patch && part.patch->patch ? part.patch->patch->faces().size() : 0,
              part.patch && part.patch->patch ? part.patch->patch->hierarchy().fine_vertex_count() : 0,
              part.base.face_count(),
              mesh.positions.size(), mesh.face_count(), same_faces ? "equal" : "DIFFER FROM", inside,
              largest / diagonal);
}

int run(int argc, char** argv) {
  if (argc < 4 || std::strcmp(argv[2], "--roi") != 0) {
    std::fprintf(stderr, "usage: bench_random_access FILE.isw --roi X0,Y0,Z0,X1,Y1,Z1 [--group-nodes N,N,...]\n");
    return 2;
  }
  const RegionOfInterest region = parse_region(argv[3], false, "--roi");
  std::vector<std::size_t> sizes{2048, 4096, 8192, 16384};
  if (argc >= 6 && std::strcmp(argv[4], "--group-nodes") == 0) sizes = numbers(argv[5]);
  const IswDecoded source = read_isw(argv[1]);
  compare_with_complete(argv[1], source, region);
  IswEncodeOptions options;
  options.step = source.step;
  options.frame_step = source.stream.frame_step;
  options.tangential_factor = source.stream.tangential_factor;
  options.class_weights = source.class_weights;
  options.minor_version = 1;
  const std::string reference = encode_isw(*source.hierarchy, source.coefficients, source.metadata, options);
  std::printf("%s: %zu fine control points; 2.1 re-encoded: %zu bytes\n", argv[1],
              source.hierarchy->fine_vertex_count(), reference.size());
  std::printf("%8s %7s %10s %7s %10s %7s %9s %8s %8s %8s\n", "nodes", "groups", "bytes", "vs 2.1", "read", "read %",
              "(-base) %", "decoded", "decode s", "mesh s");
  const std::string path = "/tmp/bench_random_access.isw";
  for (const std::size_t nodes : sizes) {
    options.minor_version = 2;
    options.group_nodes = nodes;
    const std::string bytes = encode_isw(*source.hierarchy, source.coefficients, source.metadata, options);
    write_isw(path, bytes, true);
    double decode_best = 1e9, mesh_best = 1e9;
    IswDecoded part;
    IswDecodeOptions read;
    read.region = region;
    read.order = IswOrder::Index;
    for (int k = 0; k < 3; ++k) {
      const auto start = Clock::now();
      part = read_isw(path, read);
      decode_best = std::min(decode_best, seconds_since(start));
      const auto mesh_start = Clock::now();
      const PolygonMesh mesh = region_mesh(part, region, 0);
      mesh_best = std::min(mesh_best, seconds_since(mesh_start));
    }
    const double file = static_cast<double>(bytes.size());
    const double read_bytes = static_cast<double>(part.file_bytes_read);
    std::printf("%8zu %7zu %10zu %+6.2f%% %10llu %6.2f%% %8.2f%% %4zu/%-4zu %8.3f %8.3f\n", nodes, part.stream.groups,
                bytes.size(), 100.0 * (file / static_cast<double>(reference.size()) - 1),
                static_cast<unsigned long long>(part.file_bytes_read), 100.0 * read_bytes / file,
                100.0 * (read_bytes - static_cast<double>(base_mesh_bytes(part))) / file, part.stream.groups_decoded,
                part.stream.groups, decode_best, mesh_best);
    std::printf("         decode phases (last run): read %.3f, headers %.3f, hierarchy %.3f (waited %.3f), planes %.3f, "
                "to world %.3f, rank %.3f s\n",
                part.seconds.read, part.seconds.headers, part.seconds.hierarchy, part.seconds.hierarchy_wait,
                part.seconds.chunks, part.seconds.dequantize, part.seconds.rank);
  }
  std::remove(path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) try {
  return run(argc, argv);
} catch (const std::exception& error) {
  std::fprintf(stderr, "bench_random_access: %s\n", error.what());
  return 1;
}
