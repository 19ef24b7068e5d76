# The layers, checked: the kernel (what a plugin sees) never reaches up into
# the host, and neither the kernel library nor a shipped plugin depends on
# yaml-cpp or Boost.
#
#   cmake -DSOURCE_DIR=<repo> -DKERNEL_LIB=<libpdyn_kernel.so> -DPLUGIN_DIR=<plugins> -P layers.cmake
#
# Fails with one line per violation: FILE:LINE: what is included, or the
# library and the dependency it should not have.
foreach(var SOURCE_DIR KERNEL_LIB PLUGIN_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "layers.cmake: -D${var}=... is required")
  endif()
endforeach()

set(violations "")

# 1. Sources: the kernel and the plugins include only the kernel's headers
#    (and the standard library, Eigen, fmt, OpenMP); nothing outside host/
#    includes a file of host/src.
file(GLOB_RECURSE kernel_sources
  "${SOURCE_DIR}/kernel/*.cpp" "${SOURCE_DIR}/kernel/*.hpp"
  "${SOURCE_DIR}/plugins/*.cpp" "${SOURCE_DIR}/plugins/*.hpp")
set(forbidden_in_kernel "pdyn/host/|yaml-cpp/|boost/|host/src|registry\\.hpp|scene\\.hpp|runner\\.hpp")
foreach(file IN LISTS kernel_sources)
  file(RELATIVE_PATH rel "${SOURCE_DIR}" "${file}")
  file(STRINGS "${file}" lines REGEX "^[ \t]*#[ \t]*include")
  foreach(line IN LISTS lines)
    if(line MATCHES "${forbidden_in_kernel}")
      string(APPEND violations "  ${rel}: ${line} (the kernel and plugins include kernel headers only)\n")
    elseif(rel MATCHES "^plugins/" AND line MATCHES "pdyn/kernel/")
      # pdyn/kernel/ is what the kernel offers hosts (the crash record).
      string(APPEND violations "  ${rel}: ${line} (a plugin includes the SDK, kernel/include/pdyn/, only)\n")
    endif()
  endforeach()
endforeach()
file(GLOB_RECURSE all_sources "${SOURCE_DIR}/*.cpp" "${SOURCE_DIR}/*.hpp")
foreach(file IN LISTS all_sources)
  file(RELATIVE_PATH rel "${SOURCE_DIR}" "${file}")
  if(rel MATCHES "^(build|host/|\\.git/)")
    continue()
  endif()
  file(STRINGS "${file}" lines REGEX "^[ \t]*#[ \t]*include.*(host|kernel)/src/")
  foreach(line IN LISTS lines)
    string(APPEND violations "  ${rel}: ${line} (use the library's public headers, never its src/)\n")
  endforeach()
endforeach()

# 2. Binaries: what the dynamic loader would bring in.
file(GLOB plugins "${PLUGIN_DIR}/*.so")
list(LENGTH plugins plugin_count)
if(plugin_count EQUAL 0)
  string(APPEND violations "  no plugin found in ${PLUGIN_DIR}\n")
endif()
foreach(lib IN LISTS KERNEL_LIB plugins)
  execute_process(COMMAND ldd "${lib}" OUTPUT_VARIABLE deps RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(APPEND violations "  ldd ${lib} failed (exit ${rc})\n")
    continue()
  endif()
  string(REGEX MATCHALL "lib(yaml-cpp|boost|pdyn_host)[^ \t\n]*" bad "${deps}")
  foreach(dep IN LISTS bad)
    string(APPEND violations "  ${lib} depends on ${dep} (the kernel layer links Eigen, OpenMP and fmt only)\n")
  endforeach()
endforeach()

if(violations)
  message(FATAL_ERROR "The kernel/host layering is broken:\n${violations}")
endif()
message(STATUS "layers: ${plugin_count} plugins and the kernel depend on no host library; no source crosses a layer")
