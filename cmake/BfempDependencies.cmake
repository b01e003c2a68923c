# Checks the Trilinos build and finds the other libraries bfemp links.
include(CheckCXXSymbolExists)
kokkos_check(DEVICES OpenMP RETURN_VALUE bfemp_kokkos_has_openmp)
if(NOT bfemp_kokkos_has_openmp)
  message(FATAL_ERROR
    "The Trilinos at ${Trilinos_DIR} has a Kokkos without the OpenMP backend "
    "(Debian's own packages are Serial-only). Run scripts/setup.sh to install "
    "the OpenMP build under /opt/bfemp-deps and configure with it.")
endif()

find_package(MPI REQUIRED COMPONENTS C CXX)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(CLI11 REQUIRED)

set(HDF5_PREFER_PARALLEL ON)
find_package(HDF5 REQUIRED COMPONENTS C)
if(NOT HDF5_IS_PARALLEL)
  message(WARNING "HDF5 found is not the MPI build (libhdf5-openmpi-dev expected)")
endif()

find_library(GMSH_LIBRARY NAMES gmsh)
find_path(GMSH_INCLUDE_DIR gmsh.h)
if(NOT GMSH_LIBRARY OR NOT GMSH_INCLUDE_DIR)
  message(FATAL_ERROR "Gmsh C++ API not found (Debian: libgmsh-dev). Run scripts/setup.sh.")
endif()

# One interface target carrying the whole stack.
add_library(bfemp_deps INTERFACE)
target_include_directories(bfemp_deps SYSTEM INTERFACE
  ${Trilinos_INCLUDE_DIRS} ${Trilinos_TPL_INCLUDE_DIRS} ${HDF5_C_INCLUDE_DIRS} ${GMSH_INCLUDE_DIR})
target_link_libraries(bfemp_deps INTERFACE
  ${Trilinos_LIBRARIES} ${Trilinos_TPL_LIBRARIES} Kokkos::kokkos
  MPI::MPI_CXX OpenMP::OpenMP_CXX Eigen3::Eigen CLI11::CLI11 ${HDF5_C_LIBRARIES} ${GMSH_LIBRARY})
target_compile_definitions(bfemp_deps INTERFACE ${HDF5_C_DEFINITIONS})
target_compile_options(bfemp_deps INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wno-unused-parameter>)
