# Third-party dependencies, all from Debian 12 packages (see scripts/install-deps.sh).
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(HDF5 REQUIRED COMPONENTS C)
find_package(spdlog REQUIRED)
find_package(CLI11 REQUIRED CONFIG)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(OpenSSL REQUIRED COMPONENTS Crypto)
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(Threads REQUIRED)
# Boost.Beast and Boost.Asio (header-only): ctsurg-live's HTTP and WebSocket server.
find_package(Boost 1.74 REQUIRED)
# zlib: ctsurg checks gzip and zlib streams itself (NIfTI .nii.gz, compressed MetaImage).
find_package(ZLIB REQUIRED)
# ITK (with GDCM) only for medical image I/O, confined to preprocess/src/*reader*.cpp.
find_package(ITK 5.2 REQUIRED COMPONENTS ITKCommon ITKIOImageBase ITKIOGDCM ITKIONIFTI ITKIONRRD ITKIOMeta ITKGDCM
             ITKConnectedComponents ITKBinaryMathematicalMorphology ITKLabelMap ITKThresholding ITKImageGrid)
find_package(GDCM REQUIRED)
if(CTSURG_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(CTSURG_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()
# Assimp for exporting surfaces to glTF/OBJ/STL/PLY (mesh/src/surface_export.cpp) and reading the instruments'
# triangle meshes (core/src/triangle_mesh_file.cpp, in a child process), confined to those two files.
find_package(assimp 5.2 REQUIRED)
# A library that ships no CMake package, found by its header and library and imported as TARGET:
#   ctsurg_import_library(TARGET PREFIX HEADER LIBRARY DEBIAN_PACKAGE [PATH_SUFFIXES folder...])
# with the cache variables PREFIX_INCLUDE_DIR and PREFIX_LIBRARY; a clear error naming the package when absent.
function(ctsurg_import_library target prefix header library package)
  cmake_parse_arguments(ARG "" "" "PATH_SUFFIXES" ${ARGN})
  find_path(${prefix}_INCLUDE_DIR "${header}" PATH_SUFFIXES ${ARG_PATH_SUFFIXES})
  find_library(${prefix}_LIBRARY "${library}")
  if(NOT ${prefix}_INCLUDE_DIR OR NOT ${prefix}_LIBRARY)
    message(FATAL_ERROR "${target} not found (${header}, lib${library}): install ${package} (scripts/install-deps.sh)")
  endif()
  add_library(${target} UNKNOWN IMPORTED)
  set_target_properties(${target} PROPERTIES IMPORTED_LOCATION "${${prefix}_LIBRARY}"
                        INTERFACE_INCLUDE_DIRECTORIES "${${prefix}_INCLUDE_DIR}")
endfunction()

# CGAL (header-only, with GMP/MPFR) for tetrahedral meshing and surface decimation, confined to the .cpp files that use it.
find_package(CGAL 5.5 REQUIRED)
# OSMesa (Mesa's offscreen OpenGL, llvmpipe: an OpenGL 4.5 core context without a window system) for the
# render stage; libOSMesa also exports the GL entry points, so nothing else is linked.
ctsurg_import_library(OSMesa::OSMesa OSMESA GL/osmesa.h OSMesa libosmesa6-dev)

# Scenario files (sim/src/scenario.cpp): YAML (JSON is read as YAML 1.2 flow style).
find_package(yaml-cpp REQUIRED)

# SuiteSparse's CHOLMOD: the sparse Cholesky factorisation of the FEM's Newton and linear solves
# (sim/fem/src/sparse_cholesky.cpp, docs/fem.md). Debian 12's SuiteSparse 5 ships no CMake package, so the
# header and library are found directly. Its supernodal factorisation runs on BLAS: install-deps.sh installs
# OpenBLAS, which Debian's alternatives then select over the reference BLAS (10x faster factorisations).
ctsurg_import_library(SuiteSparse::CHOLMOD CHOLMOD cholmod.h cholmod libsuitesparse-dev PATH_SUFFIXES suitesparse)
# The same BLAS, linked directly for the single-precision substitutions (sgemv, strsv: the quasi-Newton
# iteration's preconditioner, sparse_cholesky.h); libsuitesparse-dev depends on a libblas.so.
find_package(BLAS REQUIRED)
