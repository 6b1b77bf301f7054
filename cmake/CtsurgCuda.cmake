# CUDA is optional. CTSURG_CUDA=AUTO enables it when nvcc is found, ON requires it, OFF disables it.
# Sets CTSURG_CUDA_ENABLED and, when enabled, the CUDA language with architectures "80-real;90" unless
# CMAKE_CUDA_ARCHITECTURES is given: machine code for Ampere (sm_80, which also runs on the sm_86 and
# sm_89 cards of the same major version) and Hopper (sm_90, the H100/H200 the GPU checks run on), and
# sm_90's PTX, which the driver compiles for a newer card. Two code generations instead of the four of
# 80;86;89;90 halve the CUDA files' share of a build (docs/architecture.md, "Build time and CI").
set(CTSURG_CUDA_ENABLED OFF)
if(NOT CTSURG_CUDA STREQUAL "OFF")
  include(CheckLanguage)
  if(NOT CMAKE_CUDA_COMPILER)
    find_program(_ctsurg_nvcc nvcc HINTS /usr/local/cuda/bin ENV CUDA_PATH PATH_SUFFIXES bin)
    if(_ctsurg_nvcc)
      set(CMAKE_CUDA_COMPILER ${_ctsurg_nvcc} CACHE FILEPATH "CUDA compiler")
    endif()
  endif()
  check_language(CUDA)
  if(CMAKE_CUDA_COMPILER)
    if(NOT DEFINED CMAKE_CUDA_ARCHITECTURES)
      set(CMAKE_CUDA_ARCHITECTURES 80-real 90)
    endif()
    enable_language(CUDA)
    set(CMAKE_CUDA_STANDARD 20)
    set(CMAKE_CUDA_STANDARD_REQUIRED ON)
    set(CTSURG_CUDA_ENABLED ON)
  elseif(CTSURG_CUDA STREQUAL "ON")
    message(FATAL_ERROR "CTSURG_CUDA=ON but no CUDA compiler (nvcc) was found; install it or use -DCTSURG_CUDA=OFF")
  endif()
endif()
