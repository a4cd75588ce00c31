// Compiled and linked with nothing but `pkg-config --cflags --libs isowave`
// (check_installed_package.sh): the whole conversion of a small generated
// sphere, its bytes decoded again. Exit code 0 when the decode gives every
// fine control point the conversion made.
#include <cstdio>
#include <exception>

#include "isowave/codec/isw_format.h"
#include "isowave/extract/builtin_fields.h"
#include "isowave/pipeline/convert.h"

int main() {
  try {
    isowave::ConvertOptions options;
    options.levels = 1;
    const isowave::ConvertResult result =
        isowave::convert_volume(isowave::make_builtin_field("sphere", 16), "builtin:sphere:16", options);
    const isowave::IswDecoded decoded = isowave::decode_isw(result.bytes, "converted");
    std::printf("%zu bytes, %zu fine vertices, %zu decoded\n", result.bytes.size(), result.fine_vertices,
                decoded.coefficients.size());
    return decoded.coefficients.size() == result.fine_vertices ? 0 : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "pkg_config_consumer: %s\n", error.what());
    return 1;
  }
}
