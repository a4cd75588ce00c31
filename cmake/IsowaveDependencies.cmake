# Every dependency is a Debian 12 package installed by scripts/setup.
find_package(Threads REQUIRED)
find_package(TBB REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)

include(IsowaveOpenSubdiv)

find_package(OpenMesh REQUIRED)
find_package(ZLIB REQUIRED)

# CGAL is header-only; keep its headers out of widely included headers.
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
find_package(CGAL REQUIRED)

# Debian ships FindOpenVDB.cmake outside the default module path; it needs
# Boost iostreams.
set(ISOWAVE_OPENVDB_MODULE_DIR "/usr/lib/x86_64-linux-gnu/cmake/OpenVDB")
list(APPEND CMAKE_MODULE_PATH "${ISOWAVE_OPENVDB_MODULE_DIR}")
find_package(Boost REQUIRED COMPONENTS iostreams)
find_package(OpenVDB REQUIRED)

# The HDF5 and NetCDF volume readers (extract/src/read_hdf5.cpp,
# read_netcdf.cpp). Through pkg-config: FindHDF5 needs the C language, which
# this C++ project does not enable.
find_package(PkgConfig REQUIRED)
pkg_check_modules(ISOWAVE_HDF5 REQUIRED IMPORTED_TARGET hdf5)
pkg_check_modules(ISOWAVE_NETCDF REQUIRED IMPORTED_TARGET netcdf)
# MPI is optional: without it isowave convert runs its batches on one machine.
# Its C API (FindMPI's C component needs the C language).
if(ISOWAVE_MPI)
  enable_language(C)
  find_package(MPI COMPONENTS C)
  if(MPI_C_FOUND)
    message(STATUS "isowave: MPI ${MPI_C_VERSION} found: isowave convert spreads batches over mpirun's ranks")
  else()
    message(STATUS "isowave: MPI not found: isowave convert runs batches on one machine "
                   "(install libopenmpi-dev for batches over mpirun's ranks, or -DISOWAVE_MPI=OFF to skip the search)")
  endif()
endif()

if(ISOWAVE_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(ISOWAVE_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
