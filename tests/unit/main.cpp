// The main of every test binary: Catch's, with NoAssertions always on, so that a test case that
// asserts nothing fails. ctest adds --warn NoTests, and Catch 2 takes --warn only once.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

int main(int argc, char *argv[]) {
  Catch::Session session;
  if (const int rc = session.applyCommandLine(argc, argv); rc != 0)
    return rc;
  auto &config = session.configData();
  config.warnings =
      static_cast<Catch::WarnAbout::What>(config.warnings | Catch::WarnAbout::NoAssertions);
  return session.run();
}
