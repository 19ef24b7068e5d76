# pdyn_library_properties(TARGET): what pdyn's shared libraries (kernel,
# host, host_mpi) have in common. The soname follows the plugin ABI
# (libpdyn_kernel.so.7): a binary names the ABI it was linked for. Hidden
# visibility: only what a library's public headers mark for export
# (PDYN_API, PDYN_HOST_API) is in its dynamic symbol table.
function(pdyn_library_properties target)
  set_target_properties(${target} PROPERTIES
    OUTPUT_NAME ${target}
    VERSION ${PDYN_ABI_VERSION}.${PROJECT_VERSION_MINOR}.${PROJECT_VERSION_PATCH}
    SOVERSION ${PDYN_ABI_VERSION}
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON)
endfunction()
