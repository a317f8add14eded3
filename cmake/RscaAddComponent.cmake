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
# What a node runs is the code, not the debug information (issue 37: a RelWithDebInfo example
# executable was 63 MB, 1.9 MB of it code, and a fresh domain hashed and stripped all of it at its
# first launch): the executable keeps its symbols and loses its debug sections to <file>.debug
# beside it, which gdb finds through the executable's .gnu_debuglink, as Debian's dh_strip lays
# out a -dbgsym package. Not under the sanitizers, whose reports read the debug information in
# the executable itself.
function(rsca_split_debug_info target)
  if(RSCA_SANITIZE OR RSCA_SANITIZE_THREAD OR NOT CMAKE_OBJCOPY)
    return()
  endif()
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND ${CMAKE_OBJCOPY} --only-keep-debug $<TARGET_FILE:${target}> $<TARGET_FILE:${target}>.debug
    COMMAND ${CMAKE_OBJCOPY} --strip-debug --add-gnu-debuglink=$<TARGET_FILE:${target}>.debug
            $<TARGET_FILE:${target}>
    VERBATIM)
endfunction()

# What the built code declares (its ports, the properties it binds) goes beside the executable, as
# <file>.rsca-code.json, written by the executable itself (`--rsca-describe`): `rsca validate`
# and `rsca launch` compare it with the component's SPD, SCD and PRF, so that a misspelled
# property or a port the SCD lacks is found before a launch (issue 39). Install it beside the
# executable. A cross build cannot run its code: it writes none, and nothing is compared.
function(rsca_describe_code target)
  if(CMAKE_CROSSCOMPILING)
    return()
  endif()
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND ${CMAKE_COMMAND} -E env ASAN_OPTIONS=detect_leaks=0
            $<TARGET_FILE:${target}> --rsca-describe $<TARGET_FILE:${target}>.rsca-code.json
    VERBATIM)
endfunction()

function(rsca_add_component name)
  if(NOT ARGN)
    message(FATAL_ERROR "rsca_add_component(${name}): no sources given")
  endif()
  add_executable(${name} ${ARGN})
  target_link_libraries(${name} PRIVATE rsca::runtime)
  rsca_split_debug_info(${name})
  rsca_describe_code(${name})
  add_library(${name}-library MODULE ${ARGN})
  set_target_properties(${name}-library PROPERTIES OUTPUT_NAME ${name} PREFIX lib)
  target_link_libraries(${name}-library PRIVATE rsca::component_library)
endfunction()
