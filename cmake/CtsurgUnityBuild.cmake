# Unity build (CTSURG_UNITY_BUILD, on by default): each library's sources are compiled in batches of
# eight, so the Eigen, CGAL and ITK templates a batch shares are instantiated and optimised once instead
# of once per file (docs/architecture.md, "Build time and CI"). Sources that define the same name at
# file scope cannot share a batch: shared helpers live in one header (core/elapsed_seconds.h,
# preprocess/src/header_text.h, sim/vessel/src/vessel_math.h), and file-local names differ.
#
# ctsurg_compile_alone(<sources...>): these sources of the calling folder keep an object file of their
# own. For the files that call a heavy third-party shared library (OpenCV, ITK and GDCM, assimp, OSMesa):
# in a batch, a program that needs any neighbour of theirs would load that library too, and OpenCV's
# imgcodecs alone costs a program 0.24 s at every start (GDAL's tree of 140 libraries), paid by every
# test case and every tool run. For CGAL's two files: they are the longest to compile (the batch holding
# tetrahedral_meshing.cpp took 134 s), so alone they build in parallel with the rest.
function(ctsurg_compile_alone)
  set_source_files_properties(${ARGN} PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
endfunction()
