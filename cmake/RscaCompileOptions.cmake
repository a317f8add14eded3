# Warnings and sanitizers for every rsca target: call rsca_target_options(<target>).
add_library(rsca_compile_options INTERFACE)
target_compile_options(rsca_compile_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wimplicit-fallthrough
  $<$<COMPILE_LANGUAGE:CXX>:-Wnon-virtual-dtor -Woverloaded-virtual>
  $<$<BOOL:${RSCA_WERROR}>:-Werror>)

# -Og -g1 (was the Debug type's -O0 -g): the sanitizer half was most of CI's 75 minutes, and each
# daemon ~200 MB, which every test's domain hashed and copied to its nodes. Line tables are all a
# report needs to name file and line. Compile time of one unity batch of rsca_domain (user CPU):
# -O0 -g 38.5 s, -Og -g1 33.5 s, -O1 -g1 50.5 s (-O1, which ASan's authors advise: 39 min of CPU
# for the whole ASan build, against 20 at -O0 -g); -Og still optimises what slows -O0 at run time.
# GCC 12 warns of a maybe-uninitialized std::function inside std::regex once optimising with ASan
# (its documentation warns of false positives with sanitizers); the optimised build keeps it.
if(RSCA_SANITIZE)
  target_compile_options(rsca_compile_options INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -Og -g1
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

# The linker: lld when the compiler can use it (Debian's lld package, which tools/install-deps
# installs), else the default (GNU ld). Linking is a large share of a build here: every component
# executable links the component library whole, and the ASan build's are ~65 MB each. Measured on
# the ASan unit-test binary (238 MB): GNU ld 9.3 s, gold 7.5 s, lld 2.9 s. Only rsca's own targets:
# the SDK a user builds against keeps the user's linker.
include(CheckLinkerFlag)
check_linker_flag(CXX -fuse-ld=lld RSCA_HAVE_LLD)
if(RSCA_HAVE_LLD)
  add_link_options(-fuse-ld=lld)
endif()

function(rsca_target_options target)
  target_link_libraries(${target} PRIVATE rsca_compile_options)
endfunction()
