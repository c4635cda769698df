# Finds the SuiteSparse parts gcpstereo uses (UMFPACK, CHOLMOD and their common libraries).
# Debian 12 ships SuiteSparse 5.12 without a CMake package; headers live in /usr/include/suitesparse.
# Defines the imported target SuiteSparse::SuiteSparse.
find_path(SuiteSparse_INCLUDE_DIR NAMES umfpack.h cholmod.h PATH_SUFFIXES suitesparse)
foreach(lib umfpack cholmod amd colamd camd ccolamd suitesparseconfig)
  find_library(SuiteSparse_${lib}_LIBRARY NAMES ${lib})
  list(APPEND SuiteSparse_LIBRARIES_REQUIRED SuiteSparse_${lib}_LIBRARY)
endforeach()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(SuiteSparse REQUIRED_VARS SuiteSparse_INCLUDE_DIR ${SuiteSparse_LIBRARIES_REQUIRED})
if(SuiteSparse_FOUND AND NOT TARGET SuiteSparse::SuiteSparse)
  add_library(SuiteSparse::SuiteSparse INTERFACE IMPORTED)
  set_target_properties(SuiteSparse::SuiteSparse PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${SuiteSparse_INCLUDE_DIR}")
  foreach(lib umfpack cholmod amd colamd camd ccolamd suitesparseconfig)
    target_link_libraries(SuiteSparse::SuiteSparse INTERFACE "${SuiteSparse_${lib}_LIBRARY}")
  endforeach()
endif()
mark_as_advanced(SuiteSparse_INCLUDE_DIR)
