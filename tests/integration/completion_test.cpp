// Shell completion of live names (issue 39, item 7): `rsca completion words` and the bash script
// `rsca completion bash` makes, against a running domain and without one.
#include "domain_fixture.hpp"
#include <catch2/catch.hpp>

namespace rsca::test {
namespace {

// What the completion script offers after `words` (the last is the word being completed), as
// tests/cli/complete prints it, with the domain's environment.
std::string offers(const TestDomain &domain, const std::vector<std::string> &words) {
  const fs::path out = domain.run_dir() / "complete.out";
  std::vector<std::string> args{"-c", "\"$0\" \"$@\" > " + out.string() + " 2>&1",
                                (kSource / "tests/cli/complete").string(),
                                (kBin / "rsca").string()};
  args.insert(args.end(), words.begin(), words.end());
  ChildProcess complete("/bin/bash", args, domain.env());
  REQUIRE(complete.wait_exit(60s).has_value());
  return read_file(out);
}

bool has(const std::string &text, const std::string &word) {
  return text.find(word) != std::string::npos;
}

} // namespace

TEST_CASE("completion offers the running domain's applications, nodes, devices and installed "
          "applications",
          "[integration][completion]") {
  TestDomain domain(2);
  domain.launch_shipped("ProducerConsumer");
  auto [rc, words] = domain.cli({"completion", "words", "apps", "nodes", "devices", "installed"});
  INFO(words);
  CHECK(rc == 0);
  CHECK(has(words, "ProducerConsumer\n"));
  CHECK(has(words, "node1\n"));
  CHECK(has(words, "node2\n"));
  CHECK(has(words, "node1:GPP_1\n"));

  const auto stop = offers(domain, {"stop", ""});
  INFO(stop);
  CHECK(has(stop, "ProducerConsumer"));
  CHECK_FALSE(has(stop, "node1")); // stop takes an application only
  const auto query = offers(domain, {"query", "node2"});
  INFO(query);
  CHECK(has(query, "node2:GPP_1"));
  CHECK_FALSE(has(query, "node1:GPP_1"));
  // A value option's word is not taken for the argument: `ls` still completes its first.
  const auto ls = offers(domain, {"--timeout-ms", "900", "ls", "conn"});
  INFO(ls);
  CHECK(ls == "connections\n");
}

TEST_CASE("completion without a domain offers no names and prints nothing else",
          "[integration][completion]") {
  ChildProcess::Environment env{{"RSCA_DDS_DOMAIN", std::to_string(isolated_domain_id())},
                                {"RSCA_DDS_TAG", isolated_tag() + "-nobody"},
                                {"RSCA_RUN_DIR", "/nonexistent"}};
  const fs::path out = fs::temp_directory_path() / fmt::format("rsca-words-{}", getpid());
  ChildProcess words("/bin/sh",
                     {"-c", "\"$0\" completion words apps nodes > " + out.string() + " 2>&1",
                      (kBin / "rsca").string()},
                     env);
  const auto status = words.wait_exit(60s);
  REQUIRE(status.has_value());
  CHECK(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) == 0);
  CHECK(read_file(out).empty());
  fs::remove(out);
}

} // namespace rsca::test
