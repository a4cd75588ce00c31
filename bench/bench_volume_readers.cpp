// The scientific-format readers against the raw reader on the same samples,
// measured in one run (issue 36: "Reading an uncompressed HDF5 or NetCDF
// dataset takes at most 1.5x the raw reader's time").
//
//   bench_volume_readers [VOLUME] [--repeat R] [--dir DIR]
//
// VOLUME (default ../shared/data/volumes/miranda_256x256x256.nrrd) is loaded
// once and its float32 samples written into DIR (default /tmp) as raw, .npy,
// HDF5 (contiguous, and chunked 32^3 + deflate), NetCDF-4 (contiguous) and
// NetCDF classic (big-endian, as the format stores it). Each file is then
// read with read_volume() R times (default 5, after one warm-up read, so
// every file is in the page cache) and the best time is printed with its
// ratio to raw; every read must return the source's samples exactly.
#include <hdf5.h>
#include <netcdf.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "isowave/core/error.h"
#include "isowave/extract/volume_io.h"

namespace {

using Clock = std::chrono::steady_clock;

bool write_raw(const std::string& path, const isowave::Volume& v) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(v.values.data()), static_cast<std::streamsize>(v.values.size() * 4));
  return out.good();
}

bool write_npy(const std::string& path, const isowave::Volume& v) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(v.dims[2]) + ", " +
                       std::to_string(v.dims[1]) + ", " + std::to_string(v.dims[0]) + "), }";
  while ((10 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  const unsigned char prefix[10] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0, static_cast<unsigned char>(header.size()),
                                    static_cast<unsigned char>(header.size() >> 8)};
  out.write(reinterpret_cast<const char*>(prefix), 10);
  out << header;
  out.write(reinterpret_cast<const char*>(v.values.data()), static_cast<std::streamsize>(v.values.size() * 4));
  return out.good();
}

bool write_hdf5(const std::string& path, const isowave::Volume& v, bool deflate) {
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t dims[3] = {v.dims[2], v.dims[1], v.dims[0]};
  const hid_t space = H5Screate_simple(3, dims, nullptr);
  const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
  if (deflate) {
    const hsize_t chunk[3] = {std::min<hsize_t>(32, dims[0]), std::min<hsize_t>(32, dims[1]), std::min<hsize_t>(32, dims[2])};
    H5Pset_chunk(create, 3, chunk);
    H5Pset_deflate(create, 4);
  }
  const hid_t dataset = H5Dcreate2(file, "/field", H5T_IEEE_F32LE, space, H5P_DEFAULT, create, H5P_DEFAULT);
  const bool ok = dataset >= 0 && H5Dwrite(dataset, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.values.data()) >= 0;
  H5Dclose(dataset), H5Pclose(create), H5Sclose(space);
  return H5Fclose(file) >= 0 && ok;
}

bool write_netcdf(const std::string& path, const isowave::Volume& v, int format) {
  int file = -1, dims[3], var = -1;
  if (nc_create(path.c_str(), NC_CLOBBER | format, &file) != NC_NOERR) return false;
  bool ok = nc_def_dim(file, "z", v.dims[2], &dims[0]) == NC_NOERR && nc_def_dim(file, "y", v.dims[1], &dims[1]) == NC_NOERR &&
            nc_def_dim(file, "x", v.dims[0], &dims[2]) == NC_NOERR &&
            nc_def_var(file, "field", NC_FLOAT, 3, dims, &var) == NC_NOERR;
  if (ok && format == NC_NETCDF4) ok = nc_def_var_chunking(file, var, NC_CONTIGUOUS, nullptr) == NC_NOERR;
  ok = ok && nc_enddef(file) == NC_NOERR && nc_put_var_float(file, var, v.values.data()) == NC_NOERR;
  return nc_close(file) == NC_NOERR && ok;
}

// The best of `repeat` reads (after a warm-up), in seconds; exits on a read
// that differs from `reference`.
double time_read(const std::string& input, const isowave::VolumeReadOptions& options, const isowave::Volume& reference,
                 int repeat) {
  double best = 1e30;
  for (int r = -1; r < repeat; ++r) {
    const auto start = Clock::now();
    const isowave::Volume v = isowave::read_volume(input, options);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    if (r >= 0) best = std::min(best, seconds);
    if (v.dims != reference.dims ||
        std::memcmp(v.values.data(), reference.values.data(), v.values.size() * sizeof(float)) != 0) {
      std::fprintf(stderr, "bench_volume_readers: %s does not read back the source samples\n", input.c_str());
      std::exit(1);
    }
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  std::string volume_path = ISOWAVE_SHARED_DATA_DIR "/volumes/miranda_256x256x256.nrrd";
  std::string dir = "/tmp";
  int repeat = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
    else if (arg == "--dir" && i + 1 < argc) dir = argv[++i];
    else volume_path = arg;
  }
  try {
    std::FILE* probe = std::fopen(volume_path.c_str(), "rb");
    if (!probe && volume_path.rfind("builtin:", 0) != 0) {
      std::printf("bench_volume_readers: %s is absent (../shared/data missing?); skipped\n", volume_path.c_str());
      return 0;
    }
    if (probe) std::fclose(probe);
    isowave::Volume source = isowave::read_volume(volume_path);
    if (source.source_type != isowave::ScalarType::Float32)
      std::printf("note: %s holds %s samples; the copies hold them as float32\n", volume_path.c_str(),
                  isowave::to_string(source.source_type));
    std::printf("%s: %zu x %zu x %zu float32 (%.1f MB), best of %d reads each\n", volume_path.c_str(), source.dims[0],
                source.dims[1], source.dims[2], source.values.size() * 4 / 1e6, repeat);

    const std::string base = dir + "/bench_volume_readers_" + std::to_string(::getpid());
    struct Copy {
      const char* label;
      std::string file;
      bool written;
    };
    const std::vector<Copy> copies = {
        {"raw", base + ".raw", write_raw(base + ".raw", source)},
        {"npy", base + ".npy", write_npy(base + ".npy", source)},
        {"hdf5 contiguous", base + ".h5", write_hdf5(base + ".h5", source, false)},
        {"netcdf-4 contiguous", base + "_4.nc", write_netcdf(base + "_4.nc", source, NC_NETCDF4)},
        {"netcdf classic (big-endian)", base + "_3.nc", write_netcdf(base + "_3.nc", source, 0)},
        {"hdf5 chunked 32^3 + deflate", base + "_z.h5", write_hdf5(base + "_z.h5", source, true)},
    };
    isowave::VolumeReadOptions raw_options;
    raw_options.dims = source.dims;
    raw_options.type = isowave::ScalarType::Float32;
    double raw_seconds = 0;
    std::printf("%-30s %10s %8s\n", "format", "read ms", "/ raw");
    for (const Copy& c : copies) {
      if (!c.written) {
        std::fprintf(stderr, "bench_volume_readers: cannot write %s\n", c.file.c_str());
        return 1;
      }
      const bool is_raw = c.file.size() > 4 && c.file.compare(c.file.size() - 4, 4, ".raw") == 0;
      const double seconds = time_read(c.file, is_raw ? raw_options : isowave::VolumeReadOptions{}, source, repeat);
      if (is_raw) raw_seconds = seconds;
      std::printf("%-30s %10.2f %8.2f\n", c.label, seconds * 1e3, seconds / raw_seconds);
    }
    std::printf("target: uncompressed HDF5 and NetCDF <= 1.50 x raw\n");
    for (const Copy& c : copies) std::remove(c.file.c_str());
  } catch (const isowave::Error& e) {
    std::fprintf(stderr, "bench_volume_readers: %s\n", e.what());
    return 1;
  }
  return 0;
}
