# Runs every scene of configs/ to its end and compares the SHA-256 of every
# file it writes with tests/host/config_outputs.sha256: a refactoring that
# changes no behaviour leaves every byte of every output as it was.
#
#   cmake -DPDYN=<pdyn> -DCONFIGS=<configs/> -DREFERENCE=<.sha256> -DWORK=<dir> -P config_outputs.cmake
#   add -DUPDATE=ON to rewrite the reference (after a deliberate change of output).
#
# The reference lines are "<sha256>  ./<scene>/<path written>", sorted.
foreach(var PDYN CONFIGS REFERENCE WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "config_outputs.cmake: -D${var}=... is required")
  endif()
endforeach()

get_filename_component(PDYN "${PDYN}" ABSOLUTE)
get_filename_component(WORK "${WORK}" ABSOLUTE)
file(REMOVE_RECURSE "${WORK}")
file(GLOB scenes "${CONFIGS}/*.yaml")
list(SORT scenes)
foreach(scene IN LISTS scenes)
  get_filename_component(name "${scene}" NAME_WE)
  file(MAKE_DIRECTORY "${WORK}/${name}")
  execute_process(COMMAND "${PDYN}" run "${scene}" --quiet
    WORKING_DIRECTORY "${WORK}/${name}" RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pdyn run ${scene} failed (exit ${rc}):\n${err}")
  endif()
endforeach()

file(GLOB_RECURSE written RELATIVE "${WORK}" "${WORK}/*")
list(SORT written)
set(actual "")
foreach(path IN LISTS written)
  file(SHA256 "${WORK}/${path}" hash)
  string(APPEND actual "${hash}  ./${path}\n")
endforeach()

if(UPDATE)
  file(WRITE "${REFERENCE}" "${actual}")
  message(STATUS "wrote ${REFERENCE}")
  return()
endif()
file(READ "${REFERENCE}" expected)
if(NOT actual STREQUAL expected)
  file(WRITE "${WORK}/actual.sha256" "${actual}")
  message(FATAL_ERROR "The outputs of configs/ differ from ${REFERENCE}.\n"
    "diff ${REFERENCE} ${WORK}/actual.sha256 shows which files; "
    "after a deliberate change of output, rerun with -DUPDATE=ON.")
endif()
list(LENGTH written count)
message(STATUS "${count} output files of configs/ are byte-identical to the reference")
