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

# ThreadSanitizer. It cannot share a process with ASan, hence its own option and build folder
# (tools/build --tsan). Only rsca's code is instrumented: Cyclone DDS, spdlog and the C++ runtime
# are the Debian packages' (TSan still sees their locks, through its interceptors, but not their
# memory accesses); tests/tsan.supp holds what is theirs.
if(RSCA_SANITIZE_THREAD)
  if(RSCA_SANITIZE)
    message(FATAL_ERROR "RSCA_SANITIZE_THREAD and RSCA_SANITIZE exclude each other (TSan cannot run with ASan)")
  endif()
  target_compile_options(rsca_compile_options INTERFACE -fsanitize=thread -fno-omit-frame-pointer)
  target_link_options(rsca_compile_options INTERFACE -fsanitize=thread)
  target_compile_definitions(rsca_compile_options INTERFACE RSCA_SANITIZE_THREAD=1)
endif()

function(rsca_target_options target)
  target_link_libraries(${target} PRIVATE rsca_compile_options)
endfunction()
