# The installed package (ISOWAVE_INSTALL): the isowave command, the stage
# libraries and their headers (installed by isowave_add_stage), a CMake
# package with the targets isowave::NAME and a pkg-config file. docs/PACKAGE.md
# describes how to use them.
include(CMakePackageConfigHelpers)
set(ISOWAVE_CMAKE_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/isowave")

# The command, as the imported executable isowave::cli.
set_target_properties(isowave PROPERTIES EXPORT_NAME cli)
install(TARGETS isowave EXPORT isowaveTargets RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")

install(EXPORT isowaveTargets NAMESPACE isowave:: DESTINATION "${ISOWAVE_CMAKE_DIR}")
configure_package_config_file(cmake/isowaveConfig.cmake.in "${PROJECT_BINARY_DIR}/isowaveConfig.cmake"
  INSTALL_DESTINATION "${ISOWAVE_CMAKE_DIR}")
# 0.y releases may break the interface between minor versions.
write_basic_package_version_file("${PROJECT_BINARY_DIR}/isowaveConfigVersion.cmake"
  COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/isowaveConfig.cmake" "${PROJECT_BINARY_DIR}/isowaveConfigVersion.cmake"
  cmake/IsowaveOpenSubdiv.cmake DESTINATION "${ISOWAVE_CMAKE_DIR}")

# pkg-config: the stages in link order (each before the stages it uses: the
# reverse of pipeline order), then what they use from other packages. The
# prefix is found relative to the .pc file, so the package can be moved.
get_property(stages GLOBAL PROPERTY ISOWAVE_STAGES)
list(REVERSE stages)
set(ISOWAVE_PC_LIBS "")
foreach(stage IN LISTS stages)
  string(APPEND ISOWAVE_PC_LIBS " -lisowave_${stage}")
endforeach()
get_target_property(ISOWAVE_OPENVDB_LIBRARY OpenVDB::openvdb IMPORTED_LOCATION)
file(RELATIVE_PATH ISOWAVE_PC_TO_PREFIX "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
string(REGEX REPLACE "/$" "" ISOWAVE_PC_TO_PREFIX "${ISOWAVE_PC_TO_PREFIX}")
configure_file(cmake/isowave.pc.in "${PROJECT_BINARY_DIR}/isowave.pc" @ONLY)
install(FILES "${PROJECT_BINARY_DIR}/isowave.pc" DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
