# The imported target isowave_opensubdiv (OpenSubdiv's CPU library and headers),
# for the build and, installed beside isowaveConfig.cmake, for its consumers.
# Debian's OpenSubdivConfig.cmake names a static library that is not shipped,
# so locate the shared CPU library and the headers directly.
find_path(ISOWAVE_OPENSUBDIV_INCLUDE_DIR opensubdiv/far/topologyRefiner.h REQUIRED)
find_library(ISOWAVE_OPENSUBDIV_LIBRARY NAMES osdCPU REQUIRED)
if(NOT TARGET isowave_opensubdiv)
  add_library(isowave_opensubdiv INTERFACE IMPORTED)
  target_include_directories(isowave_opensubdiv SYSTEM INTERFACE "${ISOWAVE_OPENSUBDIV_INCLUDE_DIR}")
  target_link_libraries(isowave_opensubdiv INTERFACE "${ISOWAVE_OPENSUBDIV_LIBRARY}")
endif()
