# Installs the build tree into a fresh prefix and checks that the installed
# `pdyn` finds its shipped plugins by itself (no --plugin-path, no
# PDYN_PLUGIN_PATH) and runs a scene.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DPREFIX=... -P check_install.cmake
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${PREFIX}"
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
set(ENV{PDYN_PLUGIN_PATH} "")
execute_process(COMMAND "${PREFIX}/bin/pdyn" plugins --json
                RESULT_VARIABLE rc OUTPUT_VARIABLE json ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "installed pdyn plugins failed (${rc}): ${err}")
endif()
# Every plugin the build made must be installed and found, with no faults.
file(GLOB built RELATIVE "${PLUGIN_DIR}" "${PLUGIN_DIR}/*.so")
list(LENGTH built expected)
string(JSON count LENGTH "${json}" plugins)
string(JSON faults LENGTH "${json}" faults)
if(NOT count EQUAL expected OR NOT faults EQUAL 0)
  message(FATAL_ERROR "installed pdyn found ${count} plugins and ${faults} faults (expected ${expected} and 0):\n${json}")
endif()
foreach(seed gravity drag spring euler midpoint rk4 plane)
  string(FIND "${json}" "\"name\": \"${seed}\"" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "installed pdyn does not list the plugin '${seed}'")
  endif()
endforeach()
math(EXPR last "${count} - 1")
foreach(i RANGE ${last})
  string(JSON lib GET "${json}" plugins ${i} library)
  string(FIND "${lib}" "${PREFIX}/" at)
  if(NOT at EQUAL 0)
    message(FATAL_ERROR "plugin library ${lib} is not under the install prefix ${PREFIX}")
  endif()
endforeach()
execute_process(COMMAND "${PREFIX}/bin/pdyn" run "${SOURCE_DIR}/tests/install/install_check.yaml" --quiet
                WORKING_DIRECTORY "${PREFIX}"
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "installed pdyn run failed (${rc}): ${err}")
endif()
message(STATUS "installed pdyn found ${count} plugins under ${PREFIX} and ran a scene")
