# Every dependency is a Debian 12 package installed by scripts/setup.
find_package(Threads REQUIRED)
find_package(TBB REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)

# Debian's OpenSubdivConfig.cmake names a static library that is not shipped,
# so locate the shared CPU library and the headers directly.
find_path(ISOWAVE_OPENSUBDIV_INCLUDE_DIR opensubdiv/far/topologyRefiner.h REQUIRED)
find_library(ISOWAVE_OPENSUBDIV_LIBRARY NAMES osdCPU REQUIRED)
if(NOT TARGET isowave_opensubdiv)
  add_library(isowave_opensubdiv INTERFACE IMPORTED)
  target_include_directories(isowave_opensubdiv SYSTEM INTERFACE "${ISOWAVE_OPENSUBDIV_INCLUDE_DIR}")
  target_link_libraries(isowave_opensubdiv INTERFACE "${ISOWAVE_OPENSUBDIV_LIBRARY}")
endif()

find_package(OpenMesh REQUIRED)
find_package(ZLIB REQUIRED)

# CGAL is header-only; keep its headers out of widely included headers.
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
find_package(CGAL REQUIRED)

# Debian ships FindOpenVDB.cmake outside the default module path; it needs
# Boost iostreams.
list(APPEND CMAKE_MODULE_PATH "/usr/lib/x86_64-linux-gnu/cmake/OpenVDB")
find_package(Boost REQUIRED COMPONENTS iostreams)
find_package(OpenVDB REQUIRED)

# The HDF5 and NetCDF volume readers (extract/src/read_hdf5.cpp,
# read_netcdf.cpp). Through pkg-config: FindHDF5 needs the C language, which
# this C++ project does not enable.
find_package(PkgConfig REQUIRED)
pkg_check_modules(ISOWAVE_HDF5 REQUIRED IMPORTED_TARGET hdf5)
pkg_check_modules(ISOWAVE_NETCDF REQUIRED IMPORTED_TARGET netcdf)

if(ISOWAVE_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(ISOWAVE_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
