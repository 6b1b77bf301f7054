# ctsurg_add_tool(<ctsurg-step> <source.cpp> <stage library>): one thin executable per stage step.
function(ctsurg_add_tool name source library)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${library})
  ctsurg_target_warnings(${name})
  install(TARGETS ${name} RUNTIME DESTINATION bin)
endfunction()
