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
# Assimp only for exporting surfaces to glTF/OBJ/STL/PLY, confined to mesh/src/surface_export.cpp.
find_package(assimp 5.2 REQUIRED)
# CGAL (header-only, with GMP/MPFR) for tetrahedral meshing and surface decimation, confined to the .cpp files that use it.
find_package(CGAL 5.5 REQUIRED)
# OSMesa (Mesa's offscreen OpenGL, llvmpipe: an OpenGL 4.5 core context without a window system) for the
# render stage; libOSMesa also exports the GL entry points, so nothing else is linked.
find_path(OSMESA_INCLUDE_DIR GL/osmesa.h)
find_library(OSMESA_LIBRARY OSMesa)
if(NOT OSMESA_INCLUDE_DIR OR NOT OSMESA_LIBRARY)
  message(FATAL_ERROR "OSMesa not found: install libosmesa6-dev (scripts/install-deps.sh)")
endif()
add_library(OSMesa::OSMesa UNKNOWN IMPORTED)
set_target_properties(OSMesa::OSMesa PROPERTIES IMPORTED_LOCATION "${OSMESA_LIBRARY}"
                      INTERFACE_INCLUDE_DIRECTORIES "${OSMESA_INCLUDE_DIR}")

# Scenario files (sim/src/scenario.cpp): YAML (JSON is read as YAML 1.2 flow style).
find_package(yaml-cpp REQUIRED)

# SuiteSparse's CHOLMOD: the sparse Cholesky factorisation of the FEM's Newton and linear solves
# (sim/fem/src/sparse_cholesky.cpp, docs/fem.md). Debian 12's SuiteSparse 5 ships no CMake package, so the
# header and library are found directly. Its supernodal factorisation runs on BLAS: install-deps.sh installs
# OpenBLAS, which Debian's alternatives then select over the reference BLAS (10x faster factorisations).
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
if(NOT CHOLMOD_INCLUDE_DIR OR NOT CHOLMOD_LIBRARY)
  message(FATAL_ERROR "CHOLMOD not found: install libsuitesparse-dev (scripts/install-deps.sh)")
endif()
add_library(SuiteSparse::CHOLMOD UNKNOWN IMPORTED)
set_target_properties(SuiteSparse::CHOLMOD PROPERTIES IMPORTED_LOCATION "${CHOLMOD_LIBRARY}"
                      INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}")
