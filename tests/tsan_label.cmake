# Run by ctest after the Catch tests are discovered (tests/CMakeLists.txt adds it to
# TEST_INCLUDE_FILES): labels `tsan` the tests that run clean under ThreadSanitizer, which
# `tools/test --tsan` runs (ctest -L tsan in build-tsan/). The label is set in every build; only
# the TSan build's tests see TSAN_OPTIONS. Every Catch test is in, but for the ones below (the
# cli.* tests are labelled where they are added; the format check, which runs no rsca code, is
# not).
#
# Left out, by name, each with its reason. None today: every test runs clean under TSan, all of
# them in 6 to 9 minutes on 2 cores shared with other builds (the slowest, the synthetic
# applications, 50 to 75 s; 8 s without TSan).
set(rsca_tsan_excluded
)

foreach(test IN LISTS rsca_unit_tests_TESTS rsca_integration_tests_TESTS)
  list(FIND rsca_tsan_excluded "${test}" excluded) # ctest's scripts know no IN_LIST
  if(excluded EQUAL -1)
    set_tests_properties("${test}" PROPERTIES LABELS tsan)
  endif()
endforeach()
