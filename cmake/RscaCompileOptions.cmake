# Warnings and sanitizers for every rsca target: call rsca_target_options(<target>).
add_library(rsca_compile_options INTERFACE)
target_compile_options(rsca_compile_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wimplicit-fallthrough
  $<$<COMPILE_LANGUAGE:CXX>:-Wnon-virtual-dtor -Woverloaded-virtual>
  $<$<BOOL:${RSCA_WERROR}>:-Werror>)

if(RSCA_SANITIZE)
  target_compile_options(rsca_compile_options INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  target_link_options(rsca_compile_options INTERFACE -fsanitize=address,undefined)
  target_compile_definitions(rsca_compile_options INTERFACE RSCA_SANITIZE=1)
endif()

function(rsca_target_options target)
  target_link_libraries(${target} PRIVATE rsca_compile_options)
endfunction()
