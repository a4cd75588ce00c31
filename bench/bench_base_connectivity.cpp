// The base mesh connectivity coder on mesh files (base meshes written by
// `isowave decode FILE --percent 100 --level 0 -o BASE.ply`): bits per vertex,
// and the canonical ordering, encoding and decoding times (best of three),
// checking that each decodes to the canonical mesh.
//   bench_base_connectivity BASE.ply...
#include <chrono>
#include <cstdio>
#include <string>

#include "base_connectivity.h"
#include "isowave/core/error.h"
#include "isowave/core/mesh_io.h"
#include "isowave/core/mesh_topology.h"

namespace {

using namespace isowave;

template <typename Work>
double best_seconds(Work&& work) {
  double best = 1e30;
  for (int run = 0; run < 3; ++run) {
    const auto start = std::chrono::steady_clock::now();
    work();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

void measure(const std::string& path) {
  const PolygonMesh mesh = read_mesh(path);
  require_manifold(mesh, path);
  detail::CanonicalMesh canonical;
  const double order_s = best_seconds([&] { canonical = detail::canonical_order(mesh); });
  std::string bytes;
  const double encode_s = best_seconds([&] {
    bytes.clear();
    detail::RangeEncoder rc(bytes);
    detail::encode_connectivity(rc, canonical.mesh);
    rc.finish();
  });
  PolygonMesh decoded;
  const double decode_s = best_seconds([&] {
    detail::RangeDecoder rc(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    decoded = detail::decode_connectivity(rc, detail::connectivity_counts(canonical.mesh));
  });
  const bool exact = decoded.face_offsets == canonical.mesh.face_offsets &&
                     decoded.face_vertices == canonical.mesh.face_vertices && decoded.sharp == canonical.mesh.sharp;
  const double v = static_cast<double>(mesh.vertex_count());
  const double per_million = 1e6 / v;
  std::printf("%-28s %8zu %8zu %5.2f %6zu %8zu %6.2f %8.4f %8.4f %8.4f %7.3f %7.3f %7.3f %s\n", path.c_str(),
              mesh.vertex_count(), mesh.face_count(),
              static_cast<double>(mesh.face_vertices.size()) / static_cast<double>(mesh.face_count()), mesh.sharp_count(),
              bytes.size(), 8.0 * static_cast<double>(bytes.size()) / v, order_s, encode_s, decode_s,
              order_s * per_million, encode_s * per_million, decode_s * per_million, exact ? "exact" : "MISMATCH");
}

}  // namespace

int main(int argc, char** argv) {
  std::printf("%-28s %8s %8s %5s %6s %8s %6s %8s %8s %8s %7s %7s %7s\n", "mesh", "verts", "faces", "sides", "sharp",
              "bytes", "b/v", "order_s", "enc_s", "dec_s", "ord/Mv", "enc/Mv", "dec/Mv");
  int status = 0;
  for (int i = 1; i < argc; ++i) {
    try {
      measure(argv[i]);
    } catch (const isowave::Error& error) {
      std::fprintf(stderr, "%s\n", error.what());
      status = 1;
    }
  }
  return status;
}
