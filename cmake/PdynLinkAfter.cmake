# pdyn_link_after(TARGET DEPENDENCY...): TARGET is linked only once each
# DEPENDENCY (a program or a plugin its tests run) is built, and its sources
# compile beside theirs. add_dependencies would hold back every compile of
# TARGET until the dependencies were all linked, which left the test
# program's batches to compile last and mostly one at a time (issue 45);
# LINK_DEPENDS names the dependencies' files to TARGET's link step alone.
function(pdyn_link_after target)
  foreach(dependency IN LISTS ARGN)
    set_property(TARGET ${target} APPEND PROPERTY LINK_DEPENDS $<TARGET_FILE:${dependency}>)
  endforeach()
endfunction()
