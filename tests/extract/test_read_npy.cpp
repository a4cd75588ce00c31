// The NumPy .npy reader: files written here byte by byte as numpy.save
// writes them (format 1.0, 2.0, 3.0; every numeric dtype in both byte
// orders; C and Fortran order), malformed headers (each an Error naming the
// file), and truncation / byte-flip sweeps.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/extract/volume_io.h"
#include "volume_io_test_support.h"

namespace isowave {
namespace {

using namespace volume_io_test;

std::string dtype_code(ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: return "u1";
    case ScalarType::Int8: return "i1";
    case ScalarType::UInt16: return "u2";
    case ScalarType::Int16: return "i2";
    case ScalarType::UInt32: return "u4";
    case ScalarType::Int32: return "i4";
    case ScalarType::Int64: return "i8";
    case ScalarType::UInt64: return "u8";
    case ScalarType::Float16: return "f2";
    case ScalarType::Float32: return "f4";
    case ScalarType::Float64: return "f8";
  }
  return "?";
}

// A .npy file as numpy.lib.format writes it: magic, version, little-endian
// header length, the dict padded with spaces to a multiple of 64 bytes and
// ended by a newline, then the data.
Bytes npy_file(const std::string& dict, const Bytes& data, int major = 1) {
  const std::size_t prefix = 8 + (major == 1 ? 2 : 4);
  std::string header = dict;
  while ((prefix + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  Bytes out = {0x93, 'N', 'U', 'M', 'P', 'Y', static_cast<std::uint8_t>(major), 0};
  const std::size_t length = header.size();
  for (std::size_t i = 0; i < prefix - 8; ++i) out.push_back(static_cast<std::uint8_t>(length >> (8 * i)));
  append(out, header);
  append(out, data);
  return out;
}

std::string dict(const std::string& descr, bool fortran, const std::string& shape) {
  return "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") + ", 'shape': " + shape + ", }";
}

// C order: shape (z, y, x) for the test volumes.
const std::string kShapeC = "(3, 4, 5)";

TEST(ReadNpy, EveryDtypeInBothByteOrdersAndEveryVersion) {
  TempDir dir;
  for (const ScalarType type : kEveryType) {
    const bool single_byte = scalar_type_size(type) == 1;
    for (const char order : {'<', '>', '|'}) {
      if (order == '|' && !single_byte) continue;
      for (const int major : {1, 2, 3}) {
        const Samples s = make_samples(type, 60, 17, /*nonfinite=*/true);
        const std::string descr = order + dtype_code(type);
        const std::string path = dir.file("a.npy");
        write_file(path, npy_file(dict(descr, false, kShapeC), s.bytes(order == '>'), major));
        const std::string label = descr + " v" + std::to_string(major);
        const Volume v = read_volume(path);
        expect_geometry(v, kDims, {1, 1, 1}, {0, 0, 0}, label);
        expect_values(v, s.expected, label);
        EXPECT_EQ(v.source_type, type) << label;
      }
    }
  }
}

// Sample (i, j, k) is a[k, j, i] of a C-order array and a[i, j, k] of a
// Fortran-order one: x is the axis that varies fastest in the file.
TEST(ReadNpy, CAndFortranOrderPutTheFastestAxisOnX) {
  TempDir dir;
  const auto value = [](std::size_t i, std::size_t j, std::size_t k) { return float(100 * k + 10 * j + i); };
  for (const bool fortran : {false, true}) {
    Bytes data;
    for (std::size_t k = 0; k < 3; ++k)
      for (std::size_t j = 0; j < 4; ++j)
        for (std::size_t i = 0; i < 5; ++i) {
          const float v = value(i, j, k);
          const auto* bytes = reinterpret_cast<const std::uint8_t*>(&v);
          data.insert(data.end(), bytes, bytes + 4);
        }
    // The same bytes: C order with shape (z, y, x) == Fortran order with shape (x, y, z).
    const std::string path = dir.file("order.npy");
    write_file(path, npy_file(dict("<f4", fortran, fortran ? "(5, 4, 3)" : "(3, 4, 5)"), data));
    const Volume v = read_volume(path);
    ASSERT_EQ(v.dims, kDims) << fortran;
    for (std::size_t k = 0; k < 3; ++k)
      for (std::size_t j = 0; j < 4; ++j)
        for (std::size_t i = 0; i < 5; ++i) ASSERT_EQ(v.at(i, j, k), value(i, j, k)) << fortran;
  }
}

TEST(ReadNpy, HeaderVariantsNumpyAccepts) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Float32, 60, 3);
  const std::string path = dir.file("variants.npy");
  // Key order, double quotes, no trailing comma, Python 2 long literals.
  for (const std::string& text :
       {std::string("{'shape': (3, 4, 5), 'fortran_order': False, 'descr': '<f4'}"),
        std::string("{\"descr\": \"<f4\", \"fortran_order\": False, \"shape\": (3,4,5,)}"),
        std::string("{'descr': '<f4', 'fortran_order': False, 'shape': (3L, 4L, 5L), }")}) {
    write_file(path, npy_file(text, s.little));
    expect_values(read_volume(path), s.expected, text);
  }
}

TEST(ReadNpy, MalformedFilesAreErrorsNamingTheFile) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Float32, 60, 3);
  const std::string path = dir.file("bad.npy");
  const struct {
    std::string dict;
    std::string keyword;
  } cases[] = {
      {dict("<f4", false, "(60,)"), "only 3-D"},
      {dict("<f4", false, "(3, 4, 5, 1)"), "only 3-D"},
      {dict("<f4", false, "()"), "only 3-D"},
      {dict("|b1", false, kShapeC), "booleans"},
      {dict("<c8", false, kShapeC), "complex"},
      {dict("<U4", false, kShapeC), "unsupported dtype"},
      {dict("|f4", false, kShapeC), "single-byte"},
      {dict("<f16", false, kShapeC), "unsupported dtype"},
      {"{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (3, 4, 5), }", "structured"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 5), 'extra': 1, }", "unknown key"},
      {"{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 5), }", "twice"},
      {"{'descr': '<f4', 'shape': (3, 4, 5), }", "required"},
      {"{'descr': '<f4', 'fortran_order': 0, 'shape': (3, 4, 5), }", "True or False"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (3, -4, 5), }", "integer"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 5), } x", "after the closing"},
      {"{'descr': '<f4', 'fortran_order': False, 'shape': (3, 4, 5)", "close the header"},
      {"{'descr': '<f\\x34', 'fortran_order': False, 'shape': (3, 4, 5), }", "unsupported dtype"},
      {dict("<f4", false, "(3, 4, 99999999999999999999)"), "too large"},
      {dict("<f4", false, "(3, 4, 6)"), "truncated data"},
      {dict("<f4", false, "(3, 4, 4)"), "size mismatch"},
      {dict("<f4", false, "(0, 4, 5)"), "empty"},
      {dict("<f4", false, "(4294967296, 4294967296, 4294967296)"), "too large"},
  };
  for (const auto& c : cases) {
    write_file(path, npy_file(c.dict, s.little));
    expect_error(path, {}, c.keyword, c.dict);
  }

  Bytes file = npy_file(dict("<f4", false, kShapeC), s.little);
  file[6] = 4;
  write_file(path, file);
  expect_error(path, {}, "version 4.0", "version 4");
  file = npy_file(dict("<f4", false, kShapeC), s.little, 2);
  file[8] = 0xff, file[9] = 0xff, file[10] = 0xff, file[11] = 0x7f;
  write_file(path, file);
  expect_error(path, {}, "at most", "huge header length");
  file = npy_file(dict("<f4", false, kShapeC), s.little);
  file[20] = 0xe9;
  write_file(path, file);
  expect_error(path, {}, "non-ASCII", "latin-1 byte");
  write_file(path, std::string("\x93NUMPZ\x01\x00", 8));
  expect_error(path, {}, "not a NumPy", "magic");
}

TEST(ReadNpy, TruncationAndCorruptionSweep) {
  TempDir dir;
  const Samples s = make_samples(ScalarType::Int16, 60, 5);
  const std::string path = dir.file("sweep.npy");
  write_file(path, npy_file(dict(">i2", true, "(5, 4, 3)"), s.bytes(true)));
  sweep(path, {}, "npy");
}

}  // namespace
}  // namespace isowave
