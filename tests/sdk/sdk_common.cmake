# Helpers of the SDK test scripts (included by them).
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

# Runs a command that must fail with exit status `status` and print `expected`
# (a regular expression) on standard error.
function(run_refused what status expected)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL status)
    message(FATAL_ERROR "${what}: exit status ${rc}, expected ${status}:\n${out}\n${err}")
  endif()
  if(NOT err MATCHES "${expected}")
    message(FATAL_ERROR "${what}: the message does not match '${expected}':\n${err}")
  endif()
endfunction()

# Configures and builds the plugin project in `source` into `build` against
# the install prefix PREFIX only (never the build tree).
# ARGV2, if given, is the build type; none given means none set, as a
# newcomer configures (`cmake -S . -B build`).
function(build_project source build)
  set(build_type "")
  if(ARGC GREATER 2)
    set(build_type "-DCMAKE_BUILD_TYPE=${ARGV2}")
  endif()
  # The flags pdyn was built with (sanitizers, in the asan preset): a test
  # program linking an instrumented libpdyn_kernel must be linked alike.
  run("configuring ${source}" ${CMAKE_COMMAND} -S "${source}" -B "${build}" -G "${GENERATOR}"
      -DCMAKE_CXX_COMPILER=${CXX} ${build_type} "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}"
      "-DCMAKE_EXE_LINKER_FLAGS=${CXX_FLAGS}"
      -DCMAKE_PREFIX_PATH=${PREFIX} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
  file(STRINGS "${build}/CMakeCache.txt" pdyn_dir REGEX "^pdyn_DIR:")
  string(FIND "${pdyn_dir}" "${PREFIX}/" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${source} found pdyn outside the install prefix: ${pdyn_dir}")
  endif()
  run("building ${source}" ${CMAKE_COMMAND} --build "${build}")
endfunction()

# The scene `scene` is accepted by the JSON Schema that the installed
# `pdyn schema` writes with the plugins in `plugin_dir` (tests/schema/validate.py).
function(check_schema scene plugin_dir work)
  run("pdyn schema --plugin-path ${plugin_dir}" "${PREFIX}/bin/pdyn" schema --plugin-path
      "${plugin_dir}" --output "${work}/pdyn.schema.json")
  run("validating ${scene} against the schema" /usr/bin/python3
      "${CMAKE_CURRENT_FUNCTION_LIST_DIR}/../schema/validate.py" "${work}/pdyn.schema.json"
      --good "${scene}")
endfunction()
