# Compile settings shared by every isowave target, attached as an interface
# library so that nothing is set globally.
add_library(isowave_build_settings INTERFACE)
target_compile_features(isowave_build_settings INTERFACE cxx_std_17)
target_compile_options(isowave_build_settings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wno-unused-parameter>)
if(ISOWAVE_SANITIZE)
  target_compile_options(isowave_build_settings INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(isowave_build_settings INTERFACE -fsanitize=address,undefined)
endif()
if(ISOWAVE_FUZZ)
  # Coverage for libFuzzer plus ASan and UBSan, every UB report fatal; the
  # harnesses in fuzz/ link libFuzzer itself.
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "ISOWAVE_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++")
  endif()
  target_compile_options(isowave_build_settings INTERFACE
    -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  target_link_options(isowave_build_settings INTERFACE -fsanitize=address,undefined)
endif()

# isowave_add_stage(NAME SOURCES... LINKS ...): one library per pipeline stage
# with its public headers in NAME/include/isowave/NAME/; installed (with
# ISOWAVE_INSTALL) as isowave::NAME, see cmake/IsowavePackage.cmake. The
# stages are recorded in pipeline order in the global property ISOWAVE_STAGES.
function(isowave_add_stage name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LINKS;PRIVATE_LINKS" ${ARGN})
  add_library(isowave_${name} STATIC ${ARG_SOURCES})
  add_library(isowave::${name} ALIAS isowave_${name})
  target_include_directories(isowave_${name} PUBLIC
    "$<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>" "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
  # The build settings are not part of the package (warnings, sanitizers).
  target_link_libraries(isowave_${name} PUBLIC ${ARG_LINKS}
    PRIVATE $<BUILD_INTERFACE:isowave_build_settings> ${ARG_PRIVATE_LINKS})
  target_compile_features(isowave_${name} PUBLIC cxx_std_17)
  set_target_properties(isowave_${name} PROPERTIES EXPORT_NAME ${name})
  set_property(GLOBAL APPEND PROPERTY ISOWAVE_STAGES ${name})
  if(ISOWAVE_INSTALL)
    install(TARGETS isowave_${name} EXPORT isowaveTargets ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}")
    install(DIRECTORY include/ DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")
  endif()
endfunction()
