# Runs every scene of configs/ to its end and compares the SHA-256 of every
# file it writes with tests/host/config_outputs.sha256: a refactoring that
# changes no behaviour leaves every byte of every output as it was.
#
#   cmake -DPDYN=<pdyn> -DCONFIGS=<configs/> -DREFERENCE=<.sha256> -DWORK=<dir> -P config_outputs.cmake
#   add -DUPDATE=ON to rewrite the reference (after a deliberate change of output);
#   add -DISA=LEVEL under PDYN_ISA=LEVEL to check an ISA level's outputs.
#
# The reference lines are "<sha256>  ./<scene>/<path written>", sorted.
foreach(var PDYN CONFIGS REFERENCE WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "config_outputs.cmake: -D${var}=... is required")
  endif()
endforeach()

get_filename_component(PDYN "${PDYN}" ABSOLUTE)

# -DISA=LEVEL (the isa.outputs_identical.* tests, run with PDYN_ISA=LEVEL):
# first make sure the plugins with ISA variants load as LEVEL's (baseline:
# none of them), so that the same reference checks that every level writes
# the same bytes (host/src/isa_variant.hpp). A level the CPU does not run
# is skipped.
if(ISA)
  execute_process(COMMAND "${PDYN}" plugins --json OUTPUT_VARIABLE listing RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pdyn plugins --json failed (exit ${rc})")
  endif()
  string(REGEX MATCH "\"library\": \"[^\"]*pdyn_force_spring\\.so\"" spring "${listing}")
  if(ISA STREQUAL "baseline")
    if(spring MATCHES "/isa/")
      message(FATAL_ERROR "PDYN_ISA=baseline loaded a variant: ${spring}")
    endif()
  elseif(NOT spring MATCHES "/isa/${ISA}/")
    message(STATUS "this CPU does not run ${ISA} (spring loads as ${spring}): skipped")
    return()
  endif()
  message(STATUS "PDYN_ISA=${ISA}: ${spring}")
endif()
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
