# rsca_add_device(<name> <source>...)
#
# Builds a device library, lib<name>.so, from sources that declare its devices with RSCA_DEVICES
# (node/device_export.hpp). A device's SPD names the file (code type SharedLibrary) and rsca-noded
# loads it when its DCD places the device. The library links no rsca code: rsca-noded exports the
# node and component runtime, which the library's devices share with it.
#
# The same function builds rsca's devices in its tree and a user's against an installed rsca
# (find_package(rsca)); both give it the target rsca::device_library.
function(rsca_add_device name)
  if(NOT ARGN)
    message(FATAL_ERROR "rsca_add_device(${name}): no sources given")
  endif()
  add_library(${name} MODULE ${ARGN})
  set_target_properties(${name} PROPERTIES PREFIX lib)
  target_link_libraries(${name} PRIVATE rsca::device_library)
endfunction()
