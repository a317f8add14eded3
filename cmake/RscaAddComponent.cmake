# rsca_add_component(<name> <source>...)
#
# Builds a component both ways, from sources that declare it with RSCA_COMPONENT
# (component/export.hpp):
#   <name>          an executable, named as its SPD's entry point (code type Executable);
#   <name>-library  lib<name>.so, which a component host loads (code type SharedLibrary). It links
#                   no rsca code: the host provides the runtime to every component it holds.
#
# The same function builds rsca's example components in its tree and a user's components against
# an installed rsca (find_package(rsca)); both give it the targets rsca::runtime and
# rsca::component_library.
function(rsca_add_component name)
  if(NOT ARGN)
    message(FATAL_ERROR "rsca_add_component(${name}): no sources given")
  endif()
  add_executable(${name} ${ARGN})
  target_link_libraries(${name} PRIVATE rsca::runtime)
  add_library(${name}-library MODULE ${ARGN})
  set_target_properties(${name}-library PROPERTIES OUTPUT_NAME ${name} PREFIX lib)
  target_link_libraries(${name}-library PRIVATE rsca::component_library)
endfunction()
