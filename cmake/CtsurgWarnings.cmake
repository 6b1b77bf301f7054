# Warnings applied to ctsurg's own targets (not to third-party headers). A switch over an enum class
# that misses one of its values is an error (-Werror=switch): the one dispatch over the material laws
# (sim/fem/laws/fem_law.h) and the other kind dispatchers fail to build when a new kind is not handled.
function(ctsurg_target_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wno-unused-parameter -Werror=switch>)
endfunction()
