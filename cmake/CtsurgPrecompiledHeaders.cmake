# Precompiled headers for ctsurg's own libraries: the third-party and standard headers that nearly
# every source reaches through ctsurg/core (Eigen through volume.h, nlohmann::json through
# provenance.h) are parsed once per library instead of once per file: 40-75 % of a file's compile
# time on the 2-core CI machine, which builds everything twice (release and ASan).
#
# ctsurg_library_precompiled_headers(<target> [<extra header>...]): one PCH per library, built with
# that library's own flags (so GCC accepts it for each of its files; a file with its own options,
# e.g. the sanitizer exemptions in mesh/ and preprocess/, silently parses the headers as before).
# The CUDA sources skip it (nvcc). Not for the fuzz build (clang,
# core only) nor the tests (tests/CMakeLists.txt has its own, shared by every test program).
function(ctsurg_library_precompiled_headers target)
  target_precompile_headers(${target} PRIVATE
    <Eigen/Core> <Eigen/Geometry> <nlohmann/json.hpp>
    <algorithm> <array> <cmath> <cstdint> <filesystem> <functional> <map> <sstream> <string> <vector>
    ${ARGN})
  # nvcc takes no GCC precompiled header: the CUDA sources include what they include.
  get_target_property(sources ${target} SOURCES)
  list(FILTER sources INCLUDE REGEX "\\.cu$")
  if(sources)
    set_source_files_properties(${sources} TARGET_DIRECTORY ${target} PROPERTIES SKIP_PRECOMPILE_HEADERS ON)
  endif()
endfunction()
