# Warnings and sanitizers for every rsca target: call rsca_target_options(<target>).
add_library(rsca_compile_options INTERFACE)
target_compile_options(rsca_compile_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wimplicit-fallthrough
  $<$<COMPILE_LANGUAGE:CXX>:-Wnon-virtual-dtor -Woverloaded-virtual>
  $<$<BOOL:${RSCA_WERROR}>:-Werror>)

# Optimised a little (-O1, what ASan's authors advise) and with line tables only (-g1): at -O0 -g
# the whole suite under the sanitizers took most of CI's hour, and each daemon was ~200 MB, which
# every test's domain hashed and copied to its nodes. A report still names file and line.
# GCC 12 warns of a maybe-uninitialized std::function inside std::regex at -O1 with ASan (its
# documentation warns of false positives with sanitizers); the optimised build keeps the warning.
if(RSCA_SANITIZE)
  target_compile_options(rsca_compile_options INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -O1 -g1
    -Wno-maybe-uninitialized)
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
