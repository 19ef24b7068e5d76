# The SDK from the outside: builds examples/third_party_force against the
# install prefix made by install_sdk.cmake (never the build tree), runs its
# scene with the installed `pdyn`, and checks the plugin with the
# conformance kit.
#   cmake -DSOURCE_DIR=... -DPREFIX=... -DWORK=... -DGENERATOR=... -DCXX=... -P check_sdk.cmake
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/sdk_common.cmake)
file(REMOVE_RECURSE "${WORK}")

set(example "${SOURCE_DIR}/examples/third_party_force")
build_project("${example}" "${WORK}" RelWithDebInfo)
if(NOT EXISTS "${WORK}/pdyn_force_vortex.so")
  message(FATAL_ERROR "the example did not build ${WORK}/pdyn_force_vortex.so")
endif()

set(ENV{PDYN_PLUGIN_PATH} "")
run("installed pdyn run scene.yaml" "${PREFIX}/bin/pdyn" run "${example}/scene.yaml"
    --plugin-path "${WORK}" --quiet)
run("installed pdyn check vortex" "${PREFIX}/bin/pdyn" check vortex --plugin-path "${WORK}")
message(STATUS "${last_output}")
check_schema("${example}/scene.yaml" "${WORK}" "${WORK}")
run("ctest in the example" ${CMAKE_CTEST_COMMAND} --test-dir "${WORK}" --output-on-failure)

# The plugin's own install rule puts it in <its prefix>/lib/pdyn/plugins.
run("installing the example" ${CMAKE_COMMAND} --install "${WORK}" --prefix "${WORK}/prefix")
if(NOT EXISTS "${WORK}/prefix/lib/pdyn/plugins/pdyn_force_vortex.so")
  message(FATAL_ERROR "the example's install rule did not install into lib/pdyn/plugins")
endif()
message(STATUS "examples/third_party_force built against ${PREFIX}, ran and passed pdyn check")
