#!/usr/bin/env bash
# The Python module as `cmake --install` leaves it: installs the build's
# python component alone into a fresh prefix, then imports the module from
# its directory there (nothing from the build tree) and extracts a sphere.
# Usage: check_installed_module.sh CMAKE BUILD_DIR PYTHON MODULE_DIR WORK_DIR
set -euo pipefail
cmake="$1" build_dir="$2" python="$3" module_dir="$4" work="$5"
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
"$cmake" --install "$build_dir" --prefix "$prefix" --component python
ls "$prefix/$module_dir"/isowave*.so
(cd "$work" && PYTHONPATH="$prefix/$module_dir" "$python" -B -c "
import isowave, numpy
assert isowave.__file__.startswith('$prefix/'), isowave.__file__
field = numpy.fromfunction(lambda x, y, z: (x - 8) ** 2 + (y - 8) ** 2 + (z - 8) ** 2, (17, 17, 17))
vertices, faces = isowave.extract(field, 25.0)
assert len(vertices) > 100, vertices.shape
print('imported', isowave.__file__)")
rm -rf "$work"
