# Every C++ source of the repository is formatted as .clang-format says.
#
#   cmake -DSOURCE_DIR=<repo> [-DCLANG_FORMAT=clang-format-14] -P format.cmake
#
# The major version is pinned (Debian 12's clang-format-14): another version
# formats some constructs differently, and a check that flips with the tool
# is no check. cli/templates/ is skipped: its @NAME@ placeholders are not C++.
# To fix what it reports: clang-format-14 -i FILE...
if(NOT DEFINED SOURCE_DIR)
  message(FATAL_ERROR "format.cmake: -DSOURCE_DIR=... is required")
endif()
if(NOT CLANG_FORMAT)
  find_program(CLANG_FORMAT NAMES clang-format-14)
endif()
if(NOT CLANG_FORMAT)
  message(FATAL_ERROR "clang-format-14 not found (apt-get install clang-format-14; "
                      "scripts/quickstart.sh installs it)")
endif()
execute_process(COMMAND "${CLANG_FORMAT}" --version OUTPUT_VARIABLE version)
if(NOT version MATCHES "version 14\\.")
  message(FATAL_ERROR "${CLANG_FORMAT} is not clang-format 14: ${version}")
endif()

set(folders kernel host plugins cli conformance viewer/server bench tests fuzz examples python)
set(files "")
foreach(folder IN LISTS folders)
  file(GLOB_RECURSE found "${SOURCE_DIR}/${folder}/*.cpp" "${SOURCE_DIR}/${folder}/*.hpp")
  list(APPEND files ${found})
endforeach()
list(FILTER files EXCLUDE REGEX "/cli/templates/|/node_modules/")
list(LENGTH files count)
execute_process(COMMAND "${CLANG_FORMAT}" --dry-run --Werror ${files}
  WORKING_DIRECTORY "${SOURCE_DIR}" RESULT_VARIABLE rc ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  string(REGEX MATCHALL "[^\n]*: error: code should be clang-formatted[^\n]*" where "${out}")
  set(names "")
  foreach(line IN LISTS where)
    string(REGEX REPLACE ":[0-9]+:[0-9]+: error.*" "" name "${line}")
    list(APPEND names "${name}")
  endforeach()
  list(REMOVE_DUPLICATES names)
  list(JOIN names "\n  " listed)
  message(FATAL_ERROR "These files differ from .clang-format (fix: ${CLANG_FORMAT} -i FILE...):\n  ${listed}")
endif()
message(STATUS "${count} C++ files match .clang-format")
