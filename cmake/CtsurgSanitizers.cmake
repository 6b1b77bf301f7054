# -DCTSURG_SANITIZE=ON: AddressSanitizer + UndefinedBehaviorSanitizer for every target.
# Used by the test configuration `cmake --preset asan` (see CMakePresets.json).
if(CTSURG_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
