# `pdyn schema` against real scenes: the generated schema must be a valid
# draft 2020-12 schema, accept every configs/*.yaml and tests/scenes/shared/*.yaml
# and tests/scenes/import/*.yaml, and refuse the bad scenes of tests/scenes/bad/ that a
# schema can express.
#   cmake -DPDYN=... -DSOURCE_DIR=... -DWORK=... -P check_schema.cmake
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
execute_process(COMMAND "${PDYN}" schema --output "${WORK}/pdyn.schema.json"
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pdyn schema failed (${rc}): ${err}")
endif()

# What only the loader can know: --set overrides, duplicate keys (PyYAML
# keeps the last), particle indices against the particle count, a factory's
# own refusals (a box's min above its max, a field's expressions, a group
# name resolved against the builders, group and ids together), a builder's
# cross-key rules (a cloud's one region, whole lattice sizes), the
# simulation box's (max above min, the particles inside it along open axes),
# files and folders and what a particle file holds (its frames, types and
# format), NaN and infinity (numbers to JSON Schema).
set(beyond_a_schema
  box_min_above_max cloud_without_region field_constant_named_x field_invalid_expression
  field_unknown_function field_unknown_variable group_unknown lattice_n_not_whole selection_group_and_ids
  duplicate_key duplicate_section duration_too_many_steps grid_pin_outside output_path_folder
  output_same_file set_bad_value set_into_missing_list set_missing_element
  set_steps_with_duration set_unknown_section set_without_value spring_index_out_of_range
  spring_rest_count spring_self velocity_nan sim_box_min_not_below_max sim_box_not_finite
  sim_box_particle_outside import_frame_missing import_masses_missing import_unknown_extension)
file(GLOB good "${SOURCE_DIR}/configs/*.yaml" "${SOURCE_DIR}/tests/scenes/shared/*.yaml"
               "${SOURCE_DIR}/tests/scenes/import/*.yaml")
file(GLOB all_bad "${SOURCE_DIR}/tests/scenes/bad/*.yaml")
set(bad "")
foreach(scene IN LISTS all_bad)
  get_filename_component(name "${scene}" NAME_WE)
  if(NOT name IN_LIST beyond_a_schema)
    list(APPEND bad "${scene}")
  endif()
endforeach()
list(LENGTH bad n_bad)
if(n_bad LESS 20)
  message(FATAL_ERROR "only ${n_bad} bad scenes found in ${SOURCE_DIR}/tests/scenes/bad")
endif()
execute_process(COMMAND /usr/bin/python3 "${CMAKE_CURRENT_LIST_DIR}/validate.py"
                        "${WORK}/pdyn.schema.json" --good ${good} --bad ${bad}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "validate.py (${rc}):\n${out}\n${err}")
endif()
message(STATUS "${out}")
