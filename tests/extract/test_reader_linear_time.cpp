// The volume readers' text parsing runs in time linear in the file: see
// support/linear_time.h.
#include <string>

#include <gtest/gtest.h>

#include "isowave/extract/volume_io.h"
#include "support/linear_time.h"

namespace isowave {
namespace {

// The files are valid 2x2x2 volumes: the whole of each is parsed.
void read_eight_samples(const std::string& path) { EXPECT_EQ(read_volume(path).values.size(), 8u) << path; }

// A valid VTI file whose one extra attribute is `bytes` of '&' (each '&'
// used to start a search to the end of the attribute for its ';').
TEST(ReaderLinearTime, VtiAttributeOfAmpersands) {
  test::expect_linear_time(".vti", [](std::size_t bytes) {
    return "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
           "<ImageData WholeExtent=\"0 1 0 1 0 1\" Origin=\"0 0 0\" Spacing=\"1 1 1\" Note=\"" +
           std::string(bytes, '&') +
           "\">\n<Piece Extent=\"0 1 0 1 0 1\"><PointData Scalars=\"s\">"
           "<DataArray type=\"Float32\" Name=\"s\" format=\"ascii\">0 1 2 3 4 5 6 7</DataArray>"
           "</PointData></Piece>\n</ImageData>\n</VTKFile>\n";
  }, read_eight_samples);
}

// A NRRD header of unique unknown fields, `bytes` long (each field used to be
// compared with every field before it).
TEST(ReaderLinearTime, NrrdHeaderOfUniqueFields) {
  test::expect_linear_time(".nrrd", [](std::size_t bytes) {
    std::string text = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: raw\nendian: little\n";
    for (std::size_t k = 0; text.size() < bytes; ++k) text += "field" + std::to_string(k) + ": 1\n";
    return text + "\n" + std::string(8 * sizeof(float), '\0');
  }, read_eight_samples);
}

// A legacy VTK header whose geometry holds a FIELD block of `bytes` worth of
// one-value arrays with %-encoded names, each skipped, and METADATA blocks,
// before the scalars.
TEST(ReaderLinearTime, VtkHeaderOfFieldArrays) {
  test::expect_linear_time(".vtk", [](std::size_t bytes) {
    std::string arrays;
    std::size_t count = 0;
    for (; arrays.size() < bytes; ++count)
      arrays += "a%20" + std::to_string(count) + " 1 1 float\n" + std::to_string(count) + "\nMETADATA\nINFORMATION 0\n\n";
    return "# vtk DataFile Version 3.0\nhostile\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
           "FIELD FieldData " + std::to_string(count) + "\n" + arrays +
           "POINT_DATA 8\nSCALARS s float 1\nLOOKUP_TABLE default\n0 1 2 3 4 5 6 7\n";
  }, read_eight_samples);
}

}  // namespace
}  // namespace isowave
