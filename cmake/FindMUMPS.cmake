# FindMUMPS: Debian's libmumps-dev, double precision (dmumps), parallel (MPI) build.
#
# Provides MUMPS::dmumps and MUMPS_FOUND, MUMPS_INCLUDE_DIR, MUMPS_LIBRARIES.
find_path(MUMPS_INCLUDE_DIR NAMES dmumps_c.h)
find_library(MUMPS_DMUMPS_LIBRARY NAMES dmumps)
find_library(MUMPS_COMMON_LIBRARY NAMES mumps_common)
find_library(MUMPS_PORD_LIBRARY NAMES pord)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(MUMPS
  REQUIRED_VARS MUMPS_DMUMPS_LIBRARY MUMPS_COMMON_LIBRARY MUMPS_INCLUDE_DIR)

if(MUMPS_FOUND)
  set(MUMPS_LIBRARIES ${MUMPS_DMUMPS_LIBRARY} ${MUMPS_COMMON_LIBRARY})
  if(MUMPS_PORD_LIBRARY)
    list(APPEND MUMPS_LIBRARIES ${MUMPS_PORD_LIBRARY})
  endif()
  if(NOT TARGET MUMPS::dmumps)
    add_library(MUMPS::dmumps INTERFACE IMPORTED)
    set_target_properties(MUMPS::dmumps PROPERTIES
      INTERFACE_INCLUDE_DIRECTORIES "${MUMPS_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES "${MUMPS_LIBRARIES};MPI::MPI_C")
  endif()
endif()
mark_as_advanced(MUMPS_INCLUDE_DIR MUMPS_DMUMPS_LIBRARY MUMPS_COMMON_LIBRARY MUMPS_PORD_LIBRARY)
