# ctsurg_add_tool(<ctsurg-step> <source.cpp> <stage library>): one thin executable per stage step.
function(ctsurg_add_tool name source library)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${library})
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
