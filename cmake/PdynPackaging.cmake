# Debian packages of pdyn, made by CPack from the install rules
# (scripts/package.sh builds them; scripts/package_smoke.sh installs and
# tries them on a clean system):
#
#   pdyn          the program, its libraries, the shipped plugins, the viewer
#                 page, the example scenes (/usr/share/pdyn/configs), the docs
#   pdyn-dev      the plugin SDK: headers, the conformance kit, the CMake
#                 package (find_package(pdyn), pdyn_add_plugin); `pdyn new`'s
#                 templates are inside the program
#   python3-pdyn  `import pdyn` for Debian's python3
#
# Runtime dependencies are found by dpkg-shlibdeps from what the binaries
# link; what they load or need otherwise is named below.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME pdyn)
set(CPACK_PACKAGE_VENDOR "pdyn")
set(CPACK_PACKAGE_CONTACT "pdyn developers <pdyn@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "plugin-based particle dynamics (Witkin's particle systems)")
set(CPACK_RESOURCE_FILE_LICENSE "${PROJECT_SOURCE_DIR}/LICENSE")
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev python)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# Stripped, as Debian ships binaries (their debug info is what made the
# program package 58 MB).
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# pdyn's own libraries come in the runtime package, not from the system.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS
    "${PROJECT_BINARY_DIR}/${CMAKE_INSTALL_LIBDIR}")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME pdyn)
set(CPACK_DEBIAN_RUNTIME_DESCRIPTION
    "plugin-based particle dynamics\n Particles, forces, solvers, colliders and writers as plugins, scenes in YAML;\n the pdyn program, its shipped plugins, the viewer page and example scenes.")
set(CPACK_DEBIAN_DEV_PACKAGE_NAME pdyn-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# A plugin project needs the compiler, CMake, and the headers the kernel's
# public headers include (Eigen, fmt).
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
    "pdyn (= ${PROJECT_VERSION}), g++, cmake, libeigen3-dev, libfmt-dev")
set(CPACK_DEBIAN_DEV_PACKAGE_SUGGESTS "libgtest-dev, ninja-build")
set(CPACK_DEBIAN_DEV_DESCRIPTION
    "pdyn plugin SDK\n Headers, the conformance kit and the CMake package (find_package(pdyn),\n pdyn_add_plugin) to build force, solver, collider and writer plugins.")
set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-pdyn)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS "pdyn (= ${PROJECT_VERSION}), python3, python3-numpy")
set(CPACK_DEBIAN_PYTHON_DESCRIPTION
    "pdyn from Python\n Load a pdyn scene, step it, read and write its state as NumPy arrays, add\n forces in Python, sweep parameters.")
include(CPack)
