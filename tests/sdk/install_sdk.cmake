# The SDK tests' shared set-up (CTest fixture sdk.prefix): installs the build
# tree into a fresh prefix and checks that the SDK's files are there.
#   cmake -DBUILD_DIR=... -DPREFIX=... -P install_sdk.cmake
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/sdk_common.cmake)
file(REMOVE_RECURSE "${PREFIX}")
run("cmake --install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${PREFIX}")
foreach(f lib/cmake/pdyn/pdynConfig.cmake lib/cmake/pdyn/pdynConfigVersion.cmake
          lib/cmake/pdyn/pdynTargets.cmake lib/cmake/pdyn/PdynPlugin.cmake
          include/pdyn/plugin.hpp include/pdyn/conformance.hpp bin/pdyn
          share/doc/pdyn/plugins.md share/doc/pdyn/scenes.md)
  if(NOT EXISTS "${PREFIX}/${f}")
    message(FATAL_ERROR "not installed: ${PREFIX}/${f}")
  endif()
endforeach()
