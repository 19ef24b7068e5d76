# pdyn_unity_build(TARGET): compile TARGET's sources in batches of 16 (CMake's
# unity build). Each of pdyn's libraries includes the same heavy headers in
# every source file (yaml-cpp, fmt, Eigen, CLI11, pybind11): parsed and
# instantiated once per batch instead of once per file, the libraries took
# about half the compile time on the 2-core machine (docs/building.md,
# "Build time"; 16 rather than 8 saved another quarter), most of the quick
# start's build. So a name at file scope, even in an anonymous namespace,
# must be unique within its library: give a file's helpers specific names,
# or share them through a header.
# PDYN_UNITY=OFF compiles file by file (an editor's single-file rebuilds).
option(PDYN_UNITY "Compile pdyn's libraries in batches (unity build)" ON)
function(pdyn_unity_build target)
  if(PDYN_UNITY)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 16)
  endif()
endfunction()
