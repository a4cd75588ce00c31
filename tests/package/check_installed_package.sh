#!/usr/bin/env bash
# The installed package as a user meets it: installs the build tree into a
# fresh prefix, then (1) configures, builds and runs examples/consumer with
# find_package(isowave) and (2) compiles, links and runs
# pkg_config_consumer.cpp with `pkg-config --cflags --libs isowave` alone.
# Usage: check_installed_package.sh CMAKE CXX BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
cmake="$1" cxx="$2" build_dir="$3" source_dir="$4" work="$5"
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"

echo "== cmake --install into $prefix"
"$cmake" --install "$build_dir" --prefix "$prefix" >"$work/install.log" || { cat "$work/install.log"; exit 1; }

echo "== examples/consumer with find_package(isowave)"
"$cmake" -S "$source_dir/examples/consumer" -B "$work/consumer" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_PREFIX_PATH="$prefix" >"$work/configure.log" 2>&1 ||
  { cat "$work/configure.log"; exit 1; }
"$cmake" --build "$work/consumer"
"$work/consumer/isowave_consumer"

echo "== pkg-config --cflags --libs isowave"
libdir="$(dirname "$(find "$prefix" -name isowave.pc -print -quit)")"
flags="$(PKG_CONFIG_PATH="$libdir" pkg-config --cflags --libs isowave)"
echo "$flags"
# shellcheck disable=SC2086  # the flags are words
"$cxx" -std=c++17 -O1 "$source_dir/tests/package/pkg_config_consumer.cpp" -o "$work/pkg_config_consumer" $flags
"$work/pkg_config_consumer"
rm -rf "$work"
