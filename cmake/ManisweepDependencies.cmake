# Every third-party dependency, found once. A missing one stops configuration with the Debian
# package that provides it (deploy/setup.sh installs them all).

macro(ms_require package debian_package)
  find_package(${package} ${ARGN} QUIET)
  if(NOT ${package}_FOUND)
    message(FATAL_ERROR "manisweep: ${package} not found. Install the Debian package "
                        "'${debian_package}' (or run deploy/setup.sh).")
  endif()
endmacro()

ms_require(Eigen3 libeigen3-dev NO_MODULE)
ms_require(CGAL libcgal-dev)
ms_require(OpenCV libopencv-dev COMPONENTS core imgproc imgcodecs)
ms_require(Protobuf "libprotobuf-dev and protobuf-compiler")
ms_require(cppzmq "cppzmq-dev and libzmq3-dev")
ms_require(HDF5 libhdf5-dev COMPONENTS C CXX)
ms_require(OpenGL "libegl-dev, libgl-dev and libegl-mesa0" COMPONENTS OpenGL EGL)
ms_require(spdlog libspdlog-dev)
ms_require(fmt libfmt-dev)
ms_require(CLI11 libcli11-dev)
ms_require(nlohmann_json nlohmann-json3-dev)
if(NOT Protobuf_PROTOC_EXECUTABLE)
  message(FATAL_ERROR "manisweep: protoc not found. Install the Debian package 'protobuf-compiler'.")
endif()
if(MANISWEEP_BUILD_TESTS)
  ms_require(GTest "libgtest-dev and libgmock-dev")
endif()
if(MANISWEEP_BUILD_BENCH)
  ms_require(benchmark libbenchmark-dev)
endif()

# HDF5's FindHDF5 gives variables on older CMake; wrap them in one imported target.
if(NOT TARGET ms_hdf5)
  add_library(ms_hdf5 INTERFACE)
  target_include_directories(ms_hdf5 SYSTEM INTERFACE ${HDF5_INCLUDE_DIRS})
  target_link_libraries(ms_hdf5 INTERFACE ${HDF5_CXX_LIBRARIES} ${HDF5_LIBRARIES})
  target_compile_definitions(ms_hdf5 INTERFACE ${HDF5_DEFINITIONS})
endif()
