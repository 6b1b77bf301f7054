# Precompiled headers for ctsurg's own libraries: the third-party and standard headers that nearly
# every source reaches through ctsurg/core (Eigen through volume.h, nlohmann::json through
# provenance.h) are parsed once per library instead of once per file: 40-75 % of a file's compile
# time on the 2-core CI machine.
#
# ctsurg_library_precompiled_headers(<target> [<extra header>...]): one PCH per library, built with
# that library's own flags, so GCC accepts it for each of its files. Not for the fuzz build (clang,
# core only) nor the tests (tests/CMakeLists.txt has its own, shared by every test program).
function(ctsurg_library_precompiled_headers target)
  target_precompile_headers(${target} PRIVATE
    <Eigen/Core> <Eigen/Geometry> <nlohmann/json.hpp>
    <algorithm> <array> <cmath> <cstdint> <filesystem> <functional> <map> <sstream> <string> <vector>
    ${ARGN})
  # nvcc takes no GCC precompiled header, and a file with options of its own (the CPU kernels'
  # -ffp-contract=off -fno-math-errno, the sanitizer exemptions) would not match the library's: both
  # include what they include.
  get_target_property(sources ${target} SOURCES)
  get_target_property(dir ${target} SOURCE_DIR)
  foreach(source IN LISTS sources)
    # Relative to the target's folder (the property calls below would read them relative to this one).
    cmake_path(ABSOLUTE_PATH source BASE_DIRECTORY "${dir}")
    get_source_file_property(options "${source}" TARGET_DIRECTORY ${target} COMPILE_OPTIONS)
    if(source MATCHES "\\.cu$" OR options)
      set_source_files_properties("${source}" TARGET_DIRECTORY ${target} PROPERTIES SKIP_PRECOMPILE_HEADERS ON)
    endif()
  endforeach()
endfunction()
