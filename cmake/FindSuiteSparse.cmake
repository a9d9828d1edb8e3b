# Finds the parts of SuiteSparse that curvflow uses (CHOLMOD, UMFPACK and
# their dependencies) as Debian installs them: headers in
# /usr/include/suitesparse, no CMake or pkg-config files.
#
# Defines SuiteSparse_FOUND, SuiteSparse_INCLUDE_DIRS, SuiteSparse_LIBRARIES.

find_path(SuiteSparse_INCLUDE_DIR cholmod.h
  PATH_SUFFIXES suitesparse
  PATHS /usr/include /usr/local/include)

set(_cf_ss_components cholmod umfpack amd colamd camd ccolamd suitesparseconfig)
set(SuiteSparse_LIBRARIES "")
set(_cf_ss_missing "")
foreach(_c IN LISTS _cf_ss_components)
  find_library(SuiteSparse_${_c}_LIBRARY NAMES ${_c})
  if(SuiteSparse_${_c}_LIBRARY)
    list(APPEND SuiteSparse_LIBRARIES ${SuiteSparse_${_c}_LIBRARY})
  else()
    list(APPEND _cf_ss_missing ${_c})
  endif()
endforeach()

# CHOLMOD's supernodal module calls BLAS/LAPACK; its partition module uses METIS.
find_library(SuiteSparse_metis_LIBRARY NAMES metis)
find_library(SuiteSparse_blas_LIBRARY NAMES openblas blas)
find_library(SuiteSparse_lapack_LIBRARY NAMES lapack openblas)
foreach(_c metis blas lapack)
  if(SuiteSparse_${_c}_LIBRARY)
    list(APPEND SuiteSparse_LIBRARIES ${SuiteSparse_${_c}_LIBRARY})
  else()
    list(APPEND _cf_ss_missing ${_c})
  endif()
endforeach()

set(SuiteSparse_INCLUDE_DIRS ${SuiteSparse_INCLUDE_DIR})
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(SuiteSparse
  REQUIRED_VARS SuiteSparse_INCLUDE_DIR SuiteSparse_cholmod_LIBRARY SuiteSparse_umfpack_LIBRARY
  FAIL_MESSAGE "SuiteSparse not found - install libsuitesparse-dev libopenblas-dev libmetis-dev")
mark_as_advanced(SuiteSparse_INCLUDE_DIR)
