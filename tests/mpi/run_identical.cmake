# `mpirun -np N pdyn run` writes the plain run's files, byte for byte
# (issue 43; docs/parallel.md): a scene run by one process and by N ranks,
# every output file compared; and a run checkpointed on one rank count and
# resumed on another, compared with the plain run's files and checkpoint.
#
#   cmake -DPDYN=<pdyn> -DMPIEXEC=<mpiexec> -DSCENE=<scene.yaml> -DWORK=<dir>
#         -DRANKS=2 [-DSTEPS=N] [-DRESUME_RANKS=3] [-DGRID=NX,NY,NZ] -P run_identical.cmake
#
# -DLAMMPS_INPUT=<in.file> instead of -DSCENE: the scene is that LAMMPS
# input converted by `pdyn convert` first. The scene's folder is copied
# (its side files with it), so that each run writes its own out/.
if(DEFINED LAMMPS_INPUT AND DEFINED WORK)
  file(REMOVE_RECURSE "${WORK}")
  get_filename_component(input_stem "${LAMMPS_INPUT}" NAME_WE)
  set(SCENE "${WORK}/converted/${input_stem}.yaml")
  file(MAKE_DIRECTORY "${WORK}/converted")
  execute_process(COMMAND "${PDYN}" convert "${LAMMPS_INPUT}" -o "${SCENE}"
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pdyn convert ${LAMMPS_INPUT}: exit ${rc}\n${err}")
  endif()
  # Its thermo goes under out/ with the rest, and its checkpoint is a
  # top-level key (the scene's outputs are a list).
  file(READ "${SCENE}" text)
  string(REPLACE "path: ${input_stem}" "path: out/${input_stem}" text "${text}")
  file(WRITE "${SCENE}" "${text}")
  set(CHECKPOINT_KEY checkpoint)
endif()
if(NOT DEFINED CHECKPOINT_KEY)
  set(CHECKPOINT_KEY output.checkpoint)
endif()
foreach(var PDYN MPIEXEC SCENE WORK RANKS)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_identical.cmake: -D${var}=... is required")
  endif()
endforeach()
if(NOT DEFINED STEPS)
  set(STEPS 400)
endif()
get_filename_component(scene_dir "${SCENE}" DIRECTORY)
get_filename_component(scene_name "${SCENE}" NAME)
get_filename_component(stem "${SCENE}" NAME_WE)
foreach(name plain ranks${RANKS} resumed)
  file(REMOVE_RECURSE "${WORK}/${name}")
endforeach()
set(checkpoint "--set=${CHECKPOINT_KEY}={path: out/run.ckpt}")

# Runs `pdyn run` in a fresh copy of the scene's folder named `name`,
# under `ranks` MPI ranks (0: no mpirun), with the extra arguments.
function(run_in name ranks)
  set(dir "${WORK}/${name}")
  file(MAKE_DIRECTORY "${dir}")
  file(GLOB inputs "${scene_dir}/${stem}.*")
  file(COPY ${inputs} DESTINATION "${dir}")
  set(command "${PDYN}" run "${scene_name}" -q ${ARGN})
  if(ranks GREATER 0)
    set(command "${MPIEXEC}" -n ${ranks} --oversubscribe ${command})
  endif()
  execute_process(COMMAND ${command} WORKING_DIRECTORY "${dir}" RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name}: exit ${rc}\n${out}\n${err}")
  endif()
endfunction()

# Every file the plain run wrote under out/ must be in `name`'s out/, the same bytes.
function(expect_same name)
  file(GLOB_RECURSE written RELATIVE "${WORK}/plain/out" "${WORK}/plain/out/*")
  if(NOT written)
    message(FATAL_ERROR "the plain run wrote nothing under out/")
  endif()
  foreach(f IN LISTS written)
    file(SHA256 "${WORK}/plain/out/${f}" want)
    if(NOT EXISTS "${WORK}/${name}/out/${f}")
      message(FATAL_ERROR "${name}: out/${f} was not written")
    endif()
    file(SHA256 "${WORK}/${name}/out/${f}" got)
    if(NOT want STREQUAL got)
      message(FATAL_ERROR "${name}: out/${f} differs from the plain run's")
    endif()
  endforeach()
  message(STATUS "${name}: ${written} identical to the plain run's")
endfunction()

set(grid_args "")
if(DEFINED GRID)
  set(grid_args --grid ${GRID})
endif()
run_in(plain 0 --steps ${STEPS} "${checkpoint}")
run_in(ranks${RANKS} ${RANKS} --steps ${STEPS} "${checkpoint}" ${grid_args})
expect_same(ranks${RANKS})
if(DEFINED RESUME_RANKS)
  # Half the steps on RANKS ranks, the rest resumed on RESUME_RANKS.
  math(EXPR half "${STEPS} / 2")
  run_in(resumed ${RANKS} --steps ${half} "${checkpoint}")
  execute_process(COMMAND "${MPIEXEC}" -n ${RESUME_RANKS} --oversubscribe "${PDYN}" run "${scene_name}" -q
                          --steps ${STEPS} "${checkpoint}" --resume out/run.ckpt
                  WORKING_DIRECTORY "${WORK}/resumed" RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "resumed on ${RESUME_RANKS} ranks: exit ${rc}\n${err}")
  endif()
  expect_same(resumed)
endif()
