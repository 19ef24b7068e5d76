# `pdyn new` from the outside: the installed pdyn (prefix made by
# install_sdk.cmake) writes a force, a solver, a collider, a pair, a bonded, a writer and a
# constraint project; each is
# configured and built against the prefix, runs its scene with the installed
# pdyn, passes its own CTest tests (the conformance kit and the scene) and
# `pdyn check`. Refusals are checked first: they are fast.
#   cmake -DPREFIX=... -DWORK=... -DGENERATOR=... -DCXX=... -P check_new.cmake
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/sdk_common.cmake)
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(pdyn "${PREFIX}/bin/pdyn")
set(ENV{PDYN_PLUGIN_PATH} "")

run_refused("pdyn new with a bad name" 2 "'Bad-Name' is not a valid plugin name"
            "${pdyn}" new force Bad-Name "${WORK}/bad")
run_refused("pdyn new with a shipped plugin's name" 2 "a plugin named 'gravity' already exists"
            "${pdyn}" new force gravity "${WORK}/gravity")
file(WRITE "${WORK}/full/keep.txt" "not empty\n")
run_refused("pdyn new into a non-empty folder" 2 "full exists and is not empty"
            "${pdyn}" new solver fine "${WORK}/full")
run_refused("pdyn new with a bad kind" 2 "kind" "${pdyn}" new thing fine "${WORK}/thing")
foreach(leftover bad gravity thing)
  if(EXISTS "${WORK}/${leftover}")
    message(FATAL_ERROR "a refused pdyn new left ${WORK}/${leftover} behind")
  endif()
endforeach()

foreach(kind force solver collider pair bonded writer constraint)
  set(name "my_${kind}")
  set(project "${WORK}/${name}")
  # The default folder is ./NAME.
  execute_process(COMMAND "${pdyn}" new ${kind} ${name} WORKING_DIRECTORY "${WORK}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pdyn new ${kind} ${name} failed (${rc}):\n${out}\n${err}")
  endif()
  foreach(f CMakeLists.txt ${name}.cpp test_${name}.cpp README.md scene.yaml)
    if(NOT EXISTS "${project}/${f}")
      message(FATAL_ERROR "pdyn new ${kind} did not write ${project}/${f}:\n${out}")
    endif()
  endforeach()
  # The README points to the guide installed with pdyn, a file that exists:
  # pairs.md for a pair law, bonded.md for a bonded term, constraints.md for a
  # constraint, plugins.md for the other kinds.
  file(READ "${project}/README.md" readme)
  set(guide plugins)
  if(kind STREQUAL "pair")
    set(guide pairs)
  elseif(kind STREQUAL "bonded")
    set(guide bonded)
  elseif(kind STREQUAL "constraint")
    set(guide constraints)
  endif()
  # (Two ifs: ${CMAKE_MATCH_1} is expanded before the condition is evaluated.)
  if(NOT readme MATCHES "guide is\n([^\n]*/share/doc/pdyn/${guide}\\.md)\\.")
    message(FATAL_ERROR "${project}/README.md does not name the installed guide:\n${readme}")
  endif()
  if(NOT EXISTS "${CMAKE_MATCH_1}")
    message(FATAL_ERROR "${project}/README.md names ${CMAKE_MATCH_1}, which does not exist")
  endif()
  file(GLOB leftovers "${WORK}/*.pdyn-new-*")
  if(leftovers)
    message(FATAL_ERROR "pdyn new left temporary folders: ${leftovers}")
  endif()

  build_project("${project}" "${project}/build")
  set(plugin_kind ${kind})
  if(kind STREQUAL "pair" OR kind STREQUAL "bonded")  # pair and bonded forces are force plugins
    set(plugin_kind force)
  endif()
  if(NOT EXISTS "${project}/build/pdyn_${plugin_kind}_${name}.so")
    message(FATAL_ERROR "${project} did not build pdyn_${plugin_kind}_${name}.so")
  endif()
  execute_process(COMMAND "${pdyn}" run "${project}/scene.yaml" --plugin-path "${project}/build"
                          --quiet
                  WORKING_DIRECTORY "${project}" RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT EXISTS "${project}/out/${name}.csv")
    message(FATAL_ERROR "installed pdyn run of ${project}/scene.yaml failed (${rc}):\n${err}")
  endif()
  check_schema("${project}/scene.yaml" "${project}/build" "${project}/build")
  if(kind STREQUAL "pair")
    # pairs.md gives the scene's force evaluations with verlet and no option:
    # one per step, and one more after each step whose wrap moved a particle
    # (PairForce declares a central law independent of velocity and time).
    file(READ "${PREFIX}/share/doc/pdyn/pairs.md" pairs_md)
    string(REGEX REPLACE "[ \n]+" " " pairs_md "${pairs_md}")
    if(NOT pairs_md MATCHES "the project of `pdyn new pair`: ([0-9]+) evaluations in its scene's ([0-9]+) steps")
      message(FATAL_ERROR "pairs.md no longer gives the pair project's force evaluations")
    endif()
    set(documented "${CMAKE_MATCH_1} force evaluations")
    set(steps "${CMAKE_MATCH_2} steps")
    execute_process(COMMAND "${pdyn}" run "${project}/scene.yaml" --plugin-path "${project}/build"
                    WORKING_DIRECTORY "${project}" RESULT_VARIABLE rc OUTPUT_VARIABLE out
                    ERROR_VARIABLE err)
    if(NOT rc EQUAL 0 OR NOT out MATCHES "pdyn: ${steps} of " OR NOT out MATCHES "pdyn: ${documented},")
      message(FATAL_ERROR "${project}/scene.yaml: pairs.md says ${steps}, ${documented}; "
                          "pdyn run says (${rc}):\n${out}${err}")
    endif()
  endif()
  run("ctest in ${project}" ${CMAKE_CTEST_COMMAND} --test-dir "${project}/build"
      --output-on-failure)
  set(last_ctest_output "${last_output}")
  # The scaffold's own GoogleTest program ran among them.
  if(NOT last_output MATCHES "${name}.PassesTheConformanceKit")
    message(FATAL_ERROR "ctest in ${project} did not run test_${name}:\n${last_output}")
  endif()
  run("pdyn check ${name}" "${pdyn}" check ${name} --plugin-path "${project}/build")
  message(STATUS "${last_output}")
  if(kind STREQUAL "pair")  # the pair checks ran on the law, none skipped
    foreach(check pair.newton_third_law pair.gradient pair.matches_brute_force
                  pair.continuous_at_cutoff pair.selecting_loop)
      if(NOT last_output MATCHES "${check} +pass")
        message(FATAL_ERROR "pdyn check ${name}: ${check} did not pass:\n${last_output}")
      endif()
    endforeach()
  endif()
  if(kind STREQUAL "bonded")  # the bonded checks ran on the terms, none skipped
    foreach(check bonded.third_law bonded.gradient bonded.jacobian_exact bonded.jacobian_definite
                  bonded.matches_terms force.jacobians)
      if(NOT last_output MATCHES "${check} +pass")
        message(FATAL_ERROR "pdyn check ${name}: ${check} did not pass:\n${last_output}")
      endif()
    endforeach()
  endif()
  if(kind STREQUAL "constraint")  # the constraint checks ran on C, J, c_t and b, none skipped
    foreach(check constraint.pattern constraint.satisfied_at_creation constraint.jacobian
                  constraint.rate constraint.bias constraint.deterministic constraint.read_only
                  constraint.finite_on_degenerate constraint.finite_near_singular
                  params.bad_rejected)
      if(NOT last_output MATCHES "${check} +pass")
        message(FATAL_ERROR "pdyn check ${name}: ${check} did not pass:\n${last_output}")
      endif()
    endforeach()
    # The scaffold's physics tests ran too: the motion test that holds for
    # any geometry and the bowl's exact orbit.
    foreach(test ParticlesStayOnTheConstraintUnderGravity ConstraintForceKeepsACircularOrbit)
      if(NOT last_ctest_output MATCHES "${name}.${test}")
        message(FATAL_ERROR "ctest in ${project} did not run ${test}:\n${last_ctest_output}")
      endif()
    endforeach()
  endif()
  # Configured with no build type, as a newcomer does: still optimised.
  if(last_output MATCHES "without optimisation")
    message(FATAL_ERROR "${project}, configured with no build type, was built without "
                        "optimisation:\n${last_output}")
  endif()
endforeach()
message(STATUS "pdyn new force, solver, collider, pair, bonded, writer and constraint: built against "
               "${PREFIX}, ran, passed pdyn check")
