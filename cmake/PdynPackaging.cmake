# Debian packages of pdyn, made by CPack from the install rules
# (scripts/package.sh builds them; scripts/package_smoke.sh installs and
# tries them on a clean system):
#
#   pdyn          the program, its libraries, the shipped plugins, the viewer
#                 page, the example scenes (/usr/share/pdyn/configs), the docs
#   pdyn-dev      the plugin SDK: headers, the libraries' development links,
#                 the conformance kit, the CMake package (find_package(pdyn),
#                 pdyn_add_plugin); `pdyn new`'s templates are compiled into
#                 the program, whose projects build against this package
#   python3-pdyn  `import pdyn` for Debian's python3
#
# Runtime dependencies are found by dpkg-shlibdeps from what the binaries
# link (the plugins that the program dlopens are in the same package and
# scanned too); what they load or need otherwise is named below.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME pdyn)
set(CPACK_PACKAGE_VENDOR "pdyn")
# No real mail address exists for the project yet; a distributor sets theirs.
set(PDYN_PACKAGE_CONTACT "pdyn developers <pdyn@localhost>"
    CACHE STRING "Maintainer of the Debian packages (Name <address>)")
set(CPACK_PACKAGE_CONTACT "${PDYN_PACKAGE_CONTACT}")
# Each package's Description names its own synopsis on its first line: with
# a package-wide summary, CPack would put that one first on all three.
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "")
if(EXISTS "${PROJECT_SOURCE_DIR}/LICENSE")
  set(CPACK_RESOURCE_FILE_LICENSE "${PROJECT_SOURCE_DIR}/LICENSE")
endif()
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev python)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# Stripped, as Debian ships binaries (their debug info made the program
# package 58 MB); the conformance kit's static library is stripped of its
# debug sections by its own install rule (conformance/CMakeLists.txt).
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# pdyn's own libraries come in the runtime package, not from the system.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS
    "${PROJECT_BINARY_DIR}/${CMAKE_INSTALL_LIBDIR}")
# A shlibs file, so that another package's binaries linking libpdyn_kernel
# or libpdyn_host get `pdyn (= VERSION)` from dpkg-shlibdeps: exact, because
# while the major version is 0 a minor release may change the plugin ABI
# (CHANGELOG.md) under the same soname.
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS_POLICY "=")

set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME pdyn)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SUGGESTS "pdyn-dev, python3-pdyn")
# What dpkg-shlibdeps cannot see: implicit_euler loads OpenBLAS with dlopen
# (its first factorisation), so nothing links it.
set(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS "libopenblas0")
set(CPACK_DEBIAN_RUNTIME_DESCRIPTION
    "plugin-based particle dynamics (Witkin's particle systems)
Particles, forces, solvers, colliders and output writers as plugins loaded at
run time, simulations assembled from YAML scene files: the pdyn program
(run, validate, render, serve, check, new), its shipped plugins, the viewer
page and example scenes in /usr/share/pdyn/configs.")
set(CPACK_DEBIAN_DEV_PACKAGE_NAME pdyn-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# A plugin project (`pdyn new`'s, or docs/plugins.md's) needs the compiler,
# CMake with a build tool for its default generator, and what
# pdynConfig.cmake's find_dependency calls find: Eigen and fmt.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
    "pdyn (= ${PROJECT_VERSION}), g++, cmake, make | ninja-build, libeigen3-dev, libfmt-dev")
set(CPACK_DEBIAN_DEV_PACKAGE_SUGGESTS "libgtest-dev")
set(CPACK_DEBIAN_DEV_DESCRIPTION
    "pdyn plugin SDK: headers, conformance kit, CMake package
The headers, the conformance kit and the CMake package (find_package(pdyn),
pdyn_add_plugin) to build force, solver, collider and writer plugins, as
`pdyn new` writes them and `pdyn check` checks them.")
set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-pdyn)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
# The compiled module is built for one interpreter version (its file name
# says cpython-3XY), so the package takes that python3 and no other.
set(python_depends "python3")
if(PDYN_PYTHON_VERSION)
  string(REPLACE "." ";" v "${PDYN_PYTHON_VERSION}")
  list(GET v 0 major)
  list(GET v 1 minor)
  math(EXPR next "${minor} + 1")
  set(python_depends "python3 (>= ${major}.${minor}~), python3 (<< ${major}.${next})")
endif()
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS
    "pdyn (= ${PROJECT_VERSION}), ${python_depends}, python3-numpy")
set(CPACK_DEBIAN_PYTHON_DESCRIPTION
    "pdyn from Python: scenes, steps and state as NumPy arrays
Load a pdyn scene, step it, read and write its state as NumPy arrays, add
forces written in Python, sweep parameters.")

# Debian's files for each package (Policy 12.5 and 12.7): the copyright
# file, here the project's license (by reference to Debian's copy of the
# Apache-2.0 text, as Debian asks; the text itself is LICENSE beside it),
# its third-party notices and the MIT notice of three.js, whose files the
# viewer page ships; and a changelog in Debian's format pointing at
# CHANGELOG.md. pdyn-dev and python3-pdyn depend on the same version of
# pdyn, so their doc folders are links to pdyn's (Policy 12.3). Installed
# only by component installs (the packages), not by a plain `cmake --install`.
set(deb_dir "${PROJECT_BINARY_DIR}/debian")
set(copyright "pdyn ${PROJECT_VERSION}: plugin-based particle dynamics

Copyright: the pdyn developers
License: Apache-2.0
 Licensed under the Apache License, Version 2.0 (the \"License\"); you may
 not use this software except in compliance with the License. On Debian
 systems the complete text of the License is in
 /usr/share/common-licenses/Apache-2.0, and in LICENSE beside this file.
 .
 Unless required by applicable law or agreed to in writing, software
 distributed under the License is distributed on an \"AS IS\" BASIS,
 WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 See the License for the specific language governing permissions and
 limitations under the License.

The third-party software that the binaries and the viewer page use:
")
foreach(part THIRD_PARTY_NOTICES.md viewer/node_modules/three/LICENSE)
  if(EXISTS "${PROJECT_SOURCE_DIR}/${part}")
    file(READ "${PROJECT_SOURCE_DIR}/${part}" text)
    string(APPEND copyright "\n---------- ${part}\n\n${text}")
  endif()
endforeach()
file(WRITE "${deb_dir}/copyright" "${copyright}")
# The entry's date is the configure time, or SOURCE_DATE_EPOCH (package.sh
# sets it to the commit's time, so that two builds of a commit agree).
string(TIMESTAMP released "%a, %d %b %Y %H:%M:%S +0000" UTC)
file(WRITE "${deb_dir}/changelog"
"pdyn (${PROJECT_VERSION}) unstable; urgency=medium

  * pdyn ${PROJECT_VERSION}: what changed is in CHANGELOG.md beside this file.

 -- ${PDYN_PACKAGE_CONTACT}  ${released}
")
execute_process(COMMAND gzip -9nc "${deb_dir}/changelog"
                OUTPUT_FILE "${deb_dir}/changelog.gz" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "gzip of ${deb_dir}/changelog failed (${rc})")
endif()
install(FILES "${deb_dir}/copyright" "${deb_dir}/changelog.gz"
        DESTINATION "${CMAKE_INSTALL_DATADIR}/doc/pdyn" COMPONENT runtime EXCLUDE_FROM_ALL)
foreach(package pdyn-dev:dev python3-pdyn:python)
  string(REPLACE ":" ";" package "${package}")
  list(GET package 0 name)
  list(GET package 1 component)
  file(CREATE_LINK pdyn "${deb_dir}/${name}" SYMBOLIC)
  install(FILES "${deb_dir}/${name}" DESTINATION "${CMAKE_INSTALL_DATADIR}/doc"
          COMPONENT ${component} EXCLUDE_FROM_ALL)
endforeach()
# A manual page for `pdyn` (Policy 12.1), made by help2man from the
# program's own --help and --version, pointing at each subcommand's --help
# and the guides. Only for the packages (scripts/package.sh turns it on).
option(PDYN_MANPAGE "Make pdyn.1 with help2man for the Debian package" OFF)
if(PDYN_MANPAGE)
  find_program(HELP2MAN help2man REQUIRED)
  file(WRITE "${deb_dir}/pdyn.h2m" "[SEE ALSO]
Each subcommand's options: pdyn SUBCOMMAND --help. Scenes, plugins, output,
the viewer and the Python module: the guides in ${CMAKE_INSTALL_FULL_DOCDIR}
(scenes.md, plugins.md, output.md, viewer.md, python.md); example scenes in
${CMAKE_INSTALL_FULL_DATADIR}/pdyn/configs.
")
  add_custom_command(OUTPUT "${deb_dir}/pdyn.1.gz"
    COMMAND "${HELP2MAN}" --no-info --section 1 --name "plugin-based particle dynamics"
            --include "${deb_dir}/pdyn.h2m" --output "${deb_dir}/pdyn.1" $<TARGET_FILE:pdyn>
    COMMAND gzip -9nf "${deb_dir}/pdyn.1"
    DEPENDS pdyn "${deb_dir}/pdyn.h2m" VERBATIM)
  add_custom_target(pdyn_manpage ALL DEPENDS "${deb_dir}/pdyn.1.gz")
  install(FILES "${deb_dir}/pdyn.1.gz" DESTINATION "${CMAKE_INSTALL_MANDIR}/man1"
          COMPONENT runtime EXCLUDE_FROM_ALL)
endif()
# The libraries in /usr/lib/<triplet> are announced to ldconfig by a
# trigger at the end of dpkg's run, as Debian packages do (lintian:
# lacks-ldconfig-trigger).
file(WRITE "${deb_dir}/triggers" "activate-noawait ldconfig\n")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_CONTROL_EXTRA "${deb_dir}/triggers")
include(CPack)
