# The SDK from the outside: installs the build tree into a fresh prefix,
# builds examples/third_party_force against that prefix only (never the build
# tree), runs its scene with the installed `pdyn`, and checks the plugin with
# the conformance kit.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DPREFIX=... -DWORK=... -DGENERATOR=...
#         -DCXX=... -P check_sdk.cmake
file(REMOVE_RECURSE "${PREFIX}" "${WORK}")
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

run("cmake --install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${PREFIX}")
foreach(f lib/cmake/pdyn/pdynConfig.cmake lib/cmake/pdyn/pdynConfigVersion.cmake
          lib/cmake/pdyn/pdynTargets.cmake lib/cmake/pdyn/PdynPlugin.cmake
          include/pdyn/plugin.hpp include/pdyn/conformance.hpp bin/pdyn)
  if(NOT EXISTS "${PREFIX}/${f}")
    message(FATAL_ERROR "not installed: ${PREFIX}/${f}")
  endif()
endforeach()

set(example "${SOURCE_DIR}/examples/third_party_force")
run("configuring the example" ${CMAKE_COMMAND} -S "${example}" -B "${WORK}" -G "${GENERATOR}"
    -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE=RelWithDebInfo
    -DCMAKE_PREFIX_PATH=${PREFIX} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
file(STRINGS "${WORK}/CMakeCache.txt" pdyn_dir REGEX "^pdyn_DIR:")
string(FIND "${pdyn_dir}" "${PREFIX}/" at)
if(at EQUAL -1)
  message(FATAL_ERROR "the example found pdyn outside the install prefix: ${pdyn_dir}")
endif()
run("building the example" ${CMAKE_COMMAND} --build "${WORK}")
if(NOT EXISTS "${WORK}/pdyn_force_vortex.so")
  message(FATAL_ERROR "the example did not build ${WORK}/pdyn_force_vortex.so")
endif()

set(ENV{PDYN_PLUGIN_PATH} "")
run("installed pdyn run scene.yaml" "${PREFIX}/bin/pdyn" run "${example}/scene.yaml"
    --plugin-path "${WORK}" --quiet)
run("installed pdyn check vortex" "${PREFIX}/bin/pdyn" check vortex --plugin-path "${WORK}")
message(STATUS "${last_output}")
run("ctest in the example" ${CMAKE_CTEST_COMMAND} --test-dir "${WORK}" --output-on-failure)

# The plugin's own install rule puts it in <its prefix>/lib/pdyn/plugins.
run("installing the example" ${CMAKE_COMMAND} --install "${WORK}" --prefix "${WORK}/prefix")
if(NOT EXISTS "${WORK}/prefix/lib/pdyn/plugins/pdyn_force_vortex.so")
  message(FATAL_ERROR "the example's install rule did not install into lib/pdyn/plugins")
endif()
message(STATUS "examples/third_party_force built against ${PREFIX}, ran and passed pdyn check")
