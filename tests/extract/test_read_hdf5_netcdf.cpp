// The HDF5 and NetCDF readers against files written here with the reference
// C libraries (libhdf5, libnetcdf): every numeric type, both byte orders
// (HDF5), chunked + deflated storage, dataset paths and variable@time
// selections, the errors for unknown names, and truncation / corruption
// sweeps (restricted where the libraries themselves fail: docs/CLI.md).
#include <gtest/gtest.h>
#include <hdf5.h>
#include <netcdf.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/extract/volume_io.h"
#include "volume_io_test_support.h"

namespace isowave {
namespace {

using namespace volume_io_test;

// Reads `input` and expects kDims samples `s` (of its type) on the unit grid.
void expect_unit_grid_volume(const std::string& input, const Samples& s, const std::string& label) {
  const Volume v = read_volume(input);
  expect_geometry(v, kDims, {1, 1, 1}, {0, 0, 0}, label);
  expect_values(v, s.expected, label);
  EXPECT_EQ(v.source_type, s.type) << label;
}

// ---------------------------------------------------------------------------
// HDF5 writing

// The HDF5 type of `type` in the given byte order; half floats are built
// from IEEE single precision (sign 15, exponent 10..14 biased by 15,
// mantissa 0..9).
hid_t hdf5_type(ScalarType type, bool big_endian) {
  switch (type) {
    case ScalarType::UInt8: return H5Tcopy(big_endian ? H5T_STD_U8BE : H5T_STD_U8LE);
    case ScalarType::Int8: return H5Tcopy(big_endian ? H5T_STD_I8BE : H5T_STD_I8LE);
    case ScalarType::UInt16: return H5Tcopy(big_endian ? H5T_STD_U16BE : H5T_STD_U16LE);
    case ScalarType::Int16: return H5Tcopy(big_endian ? H5T_STD_I16BE : H5T_STD_I16LE);
    case ScalarType::UInt32: return H5Tcopy(big_endian ? H5T_STD_U32BE : H5T_STD_U32LE);
    case ScalarType::Int32: return H5Tcopy(big_endian ? H5T_STD_I32BE : H5T_STD_I32LE);
    case ScalarType::Int64: return H5Tcopy(big_endian ? H5T_STD_I64BE : H5T_STD_I64LE);
    case ScalarType::UInt64: return H5Tcopy(big_endian ? H5T_STD_U64BE : H5T_STD_U64LE);
    case ScalarType::Float32: return H5Tcopy(big_endian ? H5T_IEEE_F32BE : H5T_IEEE_F32LE);
    case ScalarType::Float64: return H5Tcopy(big_endian ? H5T_IEEE_F64BE : H5T_IEEE_F64LE);
    case ScalarType::Float16: {
      const hid_t t = H5Tcopy(big_endian ? H5T_IEEE_F32BE : H5T_IEEE_F32LE);
      H5Tset_fields(t, 15, 10, 5, 0, 10);
      H5Tset_size(t, 2);
      H5Tset_ebias(t, 15);
      return t;
    }
  }
  return -1;
}

struct Hdf5Dataset {
  std::string name;                  // absolute, groups created as needed
  std::vector<hsize_t> dims;         // slowest first
  ScalarType type = ScalarType::Float32;
  Bytes little;                      // the samples, little-endian
  bool big_endian = false;           // stored big-endian
  bool deflate = false;              // chunked (2 x 2 x 3) + shuffle + deflate
};

void write_hdf5(const std::string& path, const std::vector<Hdf5Dataset>& datasets) {
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(file, 0) << path;
  const hid_t link = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(link, 1);
  for (const Hdf5Dataset& d : datasets) {
    const hid_t space = H5Screate_simple(static_cast<int>(d.dims.size()), d.dims.data(), nullptr);
    const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
    if (d.deflate) {
      std::vector<hsize_t> chunk(d.dims.size(), 2);
      chunk.back() = 3;
      H5Pset_chunk(create, static_cast<int>(chunk.size()), chunk.data());
      H5Pset_shuffle(create);
      H5Pset_deflate(create, 6);
    }
    const hid_t file_type = hdf5_type(d.type, d.big_endian);
    const hid_t memory_type = hdf5_type(d.type, false);
    const hid_t dataset = H5Dcreate2(file, d.name.c_str(), file_type, space, link, create, H5P_DEFAULT);
    ASSERT_GE(dataset, 0) << d.name;
    EXPECT_GE(H5Dwrite(dataset, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.little.data()), 0) << d.name;
    H5Dclose(dataset), H5Tclose(memory_type), H5Tclose(file_type), H5Pclose(create), H5Sclose(space);
  }
  H5Pclose(link);
  H5Fclose(file);
}

Hdf5Dataset volume_dataset(const std::string& name, const Samples& s) {
  return {name, {kDims[2], kDims[1], kDims[0]}, s.type, s.little};
}

TEST(ReadHdf5, EveryTypeBothByteOrdersContiguousAndDeflated) {
  TempDir dir;
  const std::string path = dir.file("types.h5");
  for (const ScalarType type : kEveryType) {
    const Samples s = make_samples(type, 60, 21, /*nonfinite=*/true);
    for (const bool big_endian : {false, true})
      for (const bool deflate : {false, true}) {
        Hdf5Dataset d = volume_dataset("/fields/step 0/rho", s);
        d.big_endian = big_endian, d.deflate = deflate;
        write_hdf5(path, {d});
        const std::string label = std::string(to_string(type)) + (big_endian ? " BE" : " LE") + (deflate ? " deflate" : "");
        expect_unit_grid_volume(path + ":/fields/step 0/rho", s, label);
      }
  }
}

// HDF5 extents are slowest first: a (z, y, x) dataset d[k][j][i] is sample (i, j, k).
TEST(ReadHdf5, LastExtentIsX) {
  TempDir dir;
  const std::string path = dir.file("axes.hdf5");
  Bytes data;
  for (std::size_t k = 0; k < 3; ++k)
    for (std::size_t j = 0; j < 4; ++j)
      for (std::size_t i = 0; i < 5; ++i) {
        const float v = float(100 * k + 10 * j + i);
        const auto* b = reinterpret_cast<const std::uint8_t*>(&v);
        data.insert(data.end(), b, b + 4);
      }
  write_hdf5(path, {{"/v", {3, 4, 5}, ScalarType::Float32, data, false, true}});
  const Volume v = read_volume(path);  // the only dataset, no name needed
  ASSERT_EQ(v.dims, kDims);
  for (std::size_t k = 0; k < 3; ++k)
    for (std::size_t j = 0; j < 4; ++j)
      for (std::size_t i = 0; i < 5; ++i) ASSERT_EQ(v.at(i, j, k), float(100 * k + 10 * j + i));
}

TEST(ReadHdf5, DatasetChoiceAndErrors) {
  TempDir dir;
  const std::string path = dir.file("choice.h5");
  const Samples a = make_samples(ScalarType::Float32, 60, 1), b = make_samples(ScalarType::Int16, 60, 2);
  const Samples flat = make_samples(ScalarType::Float64, 20, 3);
  // One 3-D dataset among a 2-D one: chosen without a name, by path or by --field.
  write_hdf5(path, {volume_dataset("/a", a), {"/group/flat", {4, 5}, ScalarType::Float64, flat.little}});
  expect_values(read_volume(path), a.expected, "only candidate");
  VolumeReadOptions by_field;
  by_field.field = "/a";
  expect_values(read_volume(path, by_field), a.expected, "--field");
  expect_values(read_volume(path + ":a"), a.expected, "relative name");
  expect_error(path + ":/group/flat", {}, "only 3-D", "2-D dataset", path);
  expect_error(path + ":/nope", {}, "3-D numeric datasets: /a", "unknown dataset", path);
  expect_error(path + ":/group/flat/deeper", {}, "no dataset", "path through a dataset", path);
  try {
    read_volume(path + ":/a", by_field);
    ADD_FAILURE() << "a dataset named twice must be refused";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument) << e.what();
  }
  // Two candidates: the error lists both.
  write_hdf5(path, {volume_dataset("/a", a), volume_dataset("/group/b", b)});
  expect_error(path, {}, "/a, /group/b", "two candidates");
  expect_values(read_volume(path + ":/group/b"), b.expected, "second by name");
  // Not HDF5 at all.
  write_file(path, std::string("\x89HDF\r\n\x1a\n but not really"));
  expect_error(path, {}, "HDF5", "not HDF5");
}

// Types that would take libhdf5's soft conversions (padding bits, non-IEEE
// floats) are refused: corrupt ones crash the library (docs/CLI.md).
TEST(ReadHdf5, NonStandardTypeLayoutsAreRefused) {
  TempDir dir;
  const std::string path = dir.file("layouts.h5");
  const std::vector<float> values(60, 1.0f);
  for (const bool padded_integer : {true, false}) {
    const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hid_t type = H5Tcopy(padded_integer ? H5T_STD_U16LE : H5T_IEEE_F32LE);
    if (padded_integer) H5Tset_precision(type, 12);
    else H5Tset_ebias(type, 100);  // not IEEE's 127
    const hsize_t dims[3] = {3, 4, 5};
    const hid_t space = H5Screate_simple(3, dims, nullptr);
    const hid_t dataset = H5Dcreate2(file, "v", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    EXPECT_GE(H5Dwrite(dataset, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    H5Dclose(dataset), H5Sclose(space), H5Tclose(type), H5Fclose(file);
    expect_error(path + ":/v", {}, "IEEE floats", padded_integer ? "12-bit integer" : "float biased by 100", path);
  }
}

TEST(ReadHdf5, DeclaredExtentsBeyondTheFileAreRefusedBeforeAllocating) {
  TempDir dir;
  const std::string path = dir.file("huge.h5");
  // Chunked with no chunk written: every sample is the fill value, the file is tiny.
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t dims[3] = {4096, 4096, 4096}, chunk[3] = {64, 64, 64};
  const hid_t space = H5Screate_simple(3, dims, nullptr);
  const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(create, 3, chunk);
  const hid_t dataset = H5Dcreate2(file, "big", H5T_NATIVE_FLOAT, space, H5P_DEFAULT, create, H5P_DEFAULT);
  H5Dclose(dataset), H5Pclose(create), H5Sclose(space), H5Fclose(file);
  expect_error(path, {}, "more than a", "unwritten 256 GB dataset");
}

// The byte range of `data` inside the file at `path` (a test failure if absent).
ByteRange find_bytes(const std::string& path, const Bytes& data) {
  const Bytes file = read_file(path);
  const auto at = std::search(file.begin(), file.end(), data.begin(), data.end());
  EXPECT_NE(at, file.end()) << path;
  const auto begin = static_cast<std::size_t>(at - file.begin());
  return {begin, begin + data.size()};
}

// Every prefix, and random corruption anywhere in a contiguous file. Not in
// a deflated one: libhdf5 1.10.8 reads past its own buffer in H5Dread
// (H5VM_memcpyvv, AddressSanitizer heap-buffer-overflow) on some corrupt
// chunks, reproduced with a plain C program and no isowave code.
TEST(ReadHdf5, TruncationSweepAndCorruption) {
  TempDir dir;
  const std::string path = dir.file("sweep.h5");
  for (const bool deflate : {false, true}) {
    Hdf5Dataset d = volume_dataset("/g/v", make_samples(ScalarType::Int32, 60, 4));
    d.deflate = deflate;
    write_hdf5(path, {d});
    sweep(path, {}, deflate ? "h5 deflate" : "h5", "", deflate ? ByteRange{0, 0} : ByteRange{});
  }
}

// ---------------------------------------------------------------------------
// NetCDF writing

nc_type netcdf_type(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: return NC_UBYTE;
    case ScalarType::Int8: return NC_BYTE;
    case ScalarType::UInt16: return NC_USHORT;
    case ScalarType::Int16: return NC_SHORT;
    case ScalarType::UInt32: return NC_UINT;
    case ScalarType::Int32: return NC_INT;
    case ScalarType::Int64: return NC_INT64;
    case ScalarType::UInt64: return NC_UINT64;
    case ScalarType::Float32: return NC_FLOAT;
    case ScalarType::Float64: return NC_DOUBLE;
    case ScalarType::Float16: return NC_NAT;
  }
  return NC_NAT;
}

#define NC_OK(call) ASSERT_EQ((call), NC_NOERR) << #call

struct NetcdfVariable {
  std::string name;
  ScalarType type = ScalarType::Float32;
  std::vector<Bytes> steps;  // one (z, y, x) block per time step; one block: a 3-D variable
  bool time = false;         // 4-D (time, z, y, x) with an unlimited time
  bool deflate = false;
};

// A file with dimensions time (unlimited), z, y, x of kDims and the variables.
void write_netcdf(const std::string& path, int format, const std::vector<NetcdfVariable>& variables) {
  int file = -1, time = -1, z = -1, y = -1, x = -1;
  NC_OK(nc_create(path.c_str(), NC_CLOBBER | format, &file));
  NC_OK(nc_def_dim(file, "time", NC_UNLIMITED, &time));
  NC_OK(nc_def_dim(file, "z", kDims[2], &z));
  NC_OK(nc_def_dim(file, "y", kDims[1], &y));
  NC_OK(nc_def_dim(file, "x", kDims[0], &x));
  std::vector<int> ids;
  for (const NetcdfVariable& v : variables) {
    const int dims[4] = {time, z, y, x};
    int id = -1;
    NC_OK(nc_def_var(file, v.name.c_str(), netcdf_type(v.type), v.time ? 4 : 3, v.time ? dims : dims + 1, &id));
    if (v.deflate) {
      NC_OK(nc_def_var_deflate(file, id, 1, 1, 6));
    }
    ids.push_back(id);
  }
  NC_OK(nc_enddef(file));
  for (std::size_t n = 0; n < variables.size(); ++n) {
    const NetcdfVariable& v = variables[n];
    for (std::size_t t = 0; t < v.steps.size(); ++t) {
      const std::size_t start[4] = {t, 0, 0, 0}, count[4] = {1, kDims[2], kDims[1], kDims[0]};
      NC_OK(nc_put_vara(file, ids[n], v.time ? start : start + 1, v.time ? count : count + 1, v.steps[t].data()));
    }
  }
  NC_OK(nc_close(file));
}

TEST(ReadNetcdf, EveryTypeClassicAndNetcdf4) {
  TempDir dir;
  const std::string path = dir.file("types.nc");
  for (const ScalarType type : kEveryType) {
    if (type == ScalarType::Float16) continue;  // NetCDF has no half floats
    const Samples s = make_samples(type, 60, 31, /*nonfinite=*/true);
    const bool classic_type = type == ScalarType::Int8 || type == ScalarType::Int16 || type == ScalarType::Int32 ||
                              type == ScalarType::Float32 || type == ScalarType::Float64;
    for (const int format : {0, NC_NETCDF4}) {
      if (format == 0 && !classic_type) continue;
      for (const bool deflate : {false, true}) {
        if (deflate && format == 0) continue;
        write_netcdf(path, format, {{"field", type, {s.little}, false, deflate}});
        const std::string label = std::string(to_string(type)) + (format ? " nc4" : " classic") + (deflate ? " deflate" : "");
        expect_unit_grid_volume(path + ":field", s, label);
      }
    }
  }
}

TEST(ReadNetcdf, TimeIndexSelectsTheStep) {
  TempDir dir;
  const std::string path = dir.file("series.nc");
  std::vector<Samples> steps;
  for (std::uint32_t t = 0; t < 3; ++t) steps.push_back(make_samples(ScalarType::Float64, 60, 40 + t));
  for (const int format : {0, NC_NETCDF4}) {
    write_netcdf(path, format,
                 {{"rho", ScalarType::Float64, {steps[0].little, steps[1].little, steps[2].little}, true, format != 0},
                  {"grid", ScalarType::Int16, {make_samples(ScalarType::Int16, 60, 9).little}}});
    for (std::size_t t = 0; t < 3; ++t)
      expect_values(read_volume(path + ":rho@" + std::to_string(t)), steps[t].expected, "step " + std::to_string(t));
    VolumeReadOptions by_field;
    by_field.field = "rho@2";
    expect_values(read_volume(path, by_field), steps[2].expected, "--field rho@2");
    expect_error(path + ":rho@3", {}, "out of range", "past the last step", path);
    expect_error(path + ":nope", {}, "volume variables: rho, grid", "unknown variable", path);
    expect_error(path, {}, "rho, grid", "two candidates");
    for (const std::string& usage : {path + ":rho", path + ":grid@0", path + ":rho@x"}) {
      try {
        read_volume(usage);
        ADD_FAILURE() << usage << " must be refused";
      } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument) << e.what();
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      }
    }
  }
}

// Every prefix, random corruption anywhere in a classic file (whose header
// isowave checks before libnetcdf 4.9.0, which crashes on some corrupt
// counts), and of the samples only in a NetCDF-4 file (HDF5: libhdf5 fails
// on some corrupt metadata, see ReadHdf5.TruncationSweepAndCorruption).
TEST(ReadNetcdf, TruncationAndCorruptionSweep) {
  TempDir dir;
  const std::string path = dir.file("sweep.nc");
  for (const int format : {0, NC_NETCDF4}) {
    const Samples s = make_samples(ScalarType::Int16, 60, 6), w = make_samples(ScalarType::Float32, 60, 7);
    write_netcdf(path, format, {{"v", ScalarType::Int16, {s.little}, false}, {"w", ScalarType::Float32, {w.little}, true}});
    VolumeReadOptions options;
    options.field = "v";
    sweep(path, options, format ? "nc4" : "nc classic", "", format ? find_bytes(path, s.little) : ByteRange{});
  }
}

// The dimension count that crashed libnetcdf 4.9.0's nc_open is refused first.
TEST(ReadNetcdf, ClassicHeaderCountsBeyondTheFileAreRefused) {
  TempDir dir;
  const std::string path = dir.file("counts.nc");
  write_netcdf(path, 0, {{"v", ScalarType::Int16, {make_samples(ScalarType::Int16, 60, 6).little}}});
  Bytes file = read_file(path);
  ASSERT_EQ(file[11], 0x0a);  // NC_DIMENSION, then the 4-byte count
  file[12] = 0x40;
  write_file(path, file);
  expect_error(path, {}, "corrupt NetCDF header", "dimension count 0x40000004");
}

}  // namespace
}  // namespace isowave
