# pdyn_add_plugin(NAME KIND force|solver|collider|writer|constraint SOURCES file.cpp ...)
#
# Builds one loadable pdyn plugin: a MODULE library named pdyn_<kind>_<name>.so
# (no "lib" prefix) with hidden symbols except the two entry points that
# PDYN_PLUGIN exports, placed where the registry looks for plugins, and
# installed beside the shipped ones.
#
# The same file is installed with pdyn's CMake package, so that out-of-tree
# plugin projects get it from find_package(pdyn). There, the plugin is built
# into the project's build folder (load it with `pdyn run --plugin-path
# <build dir>`) and installed into lib/pdyn/plugins of the project's own
# install prefix (add that folder to PDYN_PLUGIN_PATH). Set
# PDYN_PLUGIN_INSTALL_DIR to "" before calling it for no install rule.
function(pdyn_add_plugin name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "KIND;OUTPUT_DIRECTORY" "SOURCES")
  if(NOT ARG_KIND MATCHES "^(force|solver|collider|writer|constraint)$")
    message(FATAL_ERROR
      "pdyn_add_plugin(${name}): KIND must be force, solver, collider, writer or constraint")
  endif()
  if(NOT name MATCHES "^[a-z0-9_]+$")
    message(FATAL_ERROR "pdyn_add_plugin(${name}): the name must match [a-z0-9_]+")
  endif()
  if(NOT ARG_OUTPUT_DIRECTORY)
    set(ARG_OUTPUT_DIRECTORY "${PDYN_PLUGIN_OUTPUT_DIR}")
  endif()
  if(NOT ARG_OUTPUT_DIRECTORY)  # out of tree: the project's build folder
    set(ARG_OUTPUT_DIRECTORY "${CMAKE_BINARY_DIR}")
  endif()
  if(NOT DEFINED PDYN_PLUGIN_INSTALL_DIR)
    include(GNUInstallDirs)
    set(PDYN_PLUGIN_INSTALL_DIR "${CMAKE_INSTALL_LIBDIR}/pdyn/plugins")
  endif()
  add_library(${name} MODULE ${ARG_SOURCES})
  set_property(GLOBAL APPEND PROPERTY PDYN_PLUGIN_TARGETS ${name})
  target_link_libraries(${name} PRIVATE pdyn::kernel)
  set_target_properties(${name} PROPERTIES
    PREFIX ""
    OUTPUT_NAME "pdyn_${ARG_KIND}_${name}"
    LIBRARY_OUTPUT_DIRECTORY "${ARG_OUTPUT_DIRECTORY}"
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    INSTALL_RPATH "$ORIGIN/../..")
  target_compile_features(${name} PRIVATE cxx_std_20)
  # No fused multiply-add contraction: pdyn/pair.hpp's one-thread and
  # threaded loops must round identically (bit-identical for any thread
  # count), whatever -march the plugin is built for. No trapping math: no
  # value changes (pdyn never reads the floating-point exception flags), but
  # a select on a law's value may then be vectorized (pdyn/pair.hpp,
  # evaluate_beyond_cutoff). No errno from the math functions: no value
  # changes either (pdyn never reads errno), but a law's std::log or
  # std::sqrt whose value the force loop does not use (a FENE bond's
  # energy) is then dropped, and sqrt is one instruction.
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${name} PRIVATE -ffp-contract=off -fno-trapping-math -fno-math-errno)
  endif()
  # A missing symbol (e.g. an Eigen template defined in a header the plugin
  # forgot to include) is a link error, not a load failure at run time.
  # Not with sanitizers: their runtime lives in the executable, so an
  # instrumented plugin rightly leaves its symbols undefined.
  if(CMAKE_SYSTEM_NAME STREQUAL "Linux" AND NOT CMAKE_CXX_FLAGS MATCHES "-fsanitize")
    target_link_options(${name} PRIVATE "LINKER:--no-undefined")
  endif()
  if(PDYN_WARNINGS)
    target_compile_options(${name} PRIVATE ${PDYN_WARNINGS})
  endif()
  # A project that sets no build type compiles with no -O at all, and a force
  # loop then runs about 150 times slower. Optimise unless the author chose,
  # with line tables (-g1, as pdyn's own default build): backtraces and
  # perf name the plugin's lines, and a bonded plugin compiles in 18 s of
  # CPU instead of 25 s with full debug information (-g).
  if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
    target_compile_options(${name} PRIVATE -O2 -g1)
    message(STATUS "pdyn_add_plugin(${name}): no CMAKE_BUILD_TYPE given, building optimised "
                   "(-O2 -g1); -DCMAKE_BUILD_TYPE=Debug for a debug build")
  endif()
  if(PDYN_PLUGIN_INSTALL_DIR)
    install(TARGETS ${name} LIBRARY DESTINATION "${PDYN_PLUGIN_INSTALL_DIR}")
  endif()
endfunction()
