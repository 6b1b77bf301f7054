# ctsurg_add_tool(<ctsurg-step> <source.cpp> <stage library>): one thin executable per stage step.
# Every tool main reuses one precompiled header (ctsurg_tool_pch below): CLI11, spdlog and what core's
# headers pull in (Eigen, nlohmann::json, HDF5's definitions) were most of a main's 30 s compile.
function(ctsurg_add_tool name source library)
  if(NOT TARGET ctsurg_tool_pch AND NOT CTSURG_FUZZ)
    # A do-nothing program built with the tools' own flags (an executable: -fPIE; core's definitions;
    # ctsurg_driver_optimization), so GCC accepts its header for each main (-Winvalid-pch says when not).
    file(WRITE ${PROJECT_BINARY_DIR}/tool_pch_main.cpp "int main() { return 0; }\n")
    add_executable(ctsurg_tool_pch ${PROJECT_BINARY_DIR}/tool_pch_main.cpp)
    target_link_libraries(ctsurg_tool_pch PRIVATE ctsurg::core)
    target_precompile_headers(ctsurg_tool_pch PRIVATE
      <CLI/CLI.hpp> <spdlog/spdlog.h> <Eigen/Core> <Eigen/Geometry> <nlohmann/json.hpp>
      <algorithm> <array> <cmath> <cstdint> <filesystem> <functional> <map> <memory> <sstream> <string> <vector>)
    ctsurg_target_warnings(ctsurg_tool_pch)
    ctsurg_driver_optimization(ctsurg_tool_pch)
  endif()
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${library})
  if(TARGET ctsurg_tool_pch)
    target_precompile_headers(${name} REUSE_FROM ctsurg_tool_pch)
    target_compile_options(${name} PRIVATE $<$<COMPILE_LANGUAGE:CXX>:-Winvalid-pch>)
  endif()
  ctsurg_target_warnings(${name})
  ctsurg_driver_optimization(${name})
  install(TARGETS ${name} RUNTIME DESTINATION bin)
  # ctsurg_tools: every tool and nothing else (the demo builds this, not the tests and benchmarks).
  if(NOT TARGET ctsurg_tools)
    add_custom_target(ctsurg_tools)
  endif()
  add_dependencies(ctsurg_tools ${name})
endfunction()

# ctsurg_driver_optimization(<target>): CTSURG_DRIVER_OPTIMIZATION (e.g. -O0) for a test program or a tool
# main; it comes after the build type's flags, so it wins. The libraries keep the build type's level.
function(ctsurg_driver_optimization target)
  if(CTSURG_DRIVER_OPTIMIZATION)
    target_compile_options(${target} PRIVATE $<$<COMPILE_LANGUAGE:CXX>:${CTSURG_DRIVER_OPTIMIZATION}>)
  endif()
endfunction()
