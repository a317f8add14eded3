// The daemons' logs under systemd: when JOURNAL_STREAM names their stderr (systemd connected it
// to the journal) they log through the journal's own protocol, each message with its priority and
// identifier, and nothing to stderr; otherwise to stderr as before. No journald runs here: the
// test stands in for it, its socket bound where libsystemd sends (/run/systemd/journal/socket) in
// a mount namespace of the daemon's own, which needs root; without, that test is skipped (77).
#include <cstdint>
#include <map>

#include "service_fixture.hpp"

namespace {

using namespace rsca::test;

// A message of journald's native protocol as fields: "KEY=value\n", or for a value with a
// newline "KEY\n", its length (64 bits, little-endian), the value and "\n".
std::map<std::string, std::string> journal_fields(const std::string &d) {
  std::map<std::string, std::string> fields;
  std::size_t i = 0;
  while (i < d.size()) {
    const auto nl = d.find('\n', i);
    const auto eq = d.find('=', i);
    if (nl == std::string::npos)
      break;
    if (eq != std::string::npos && eq < nl) {
      fields[d.substr(i, eq - i)] = d.substr(eq + 1, nl - eq - 1);
      i = nl + 1;
      continue;
    }
    std::uint64_t size = 0;
    if (nl + 1 + sizeof(size) > d.size())
      break;
    std::memcpy(&size, d.data() + nl + 1, sizeof(size));
    fields[d.substr(i, nl - i)] = d.substr(nl + 1 + sizeof(size), size);
    i = nl + 1 + sizeof(size) + size + 1;
  }
  return fields;
}

// Whether `out` holds a line the daemon logged as text ("<time> info domaind: ..."); spdlog's
// own report that the journal could not be reached ("[*** LOG ERROR ... [rsca-domaind] ...") is
// none.
bool has_log_lines(const std::string &out, const std::string &daemon) {
  return out.find(" " + daemon + ": ") != std::string::npos;
}

// Starts rsca-domaind with `journal_stream` and waits until it serves; its stderr.
std::string domaind_output(ServiceRun &run, const fs::path &log,
                           const std::string &journal_stream) {
  DatagramSocket notify(run.dir() / "domaind.notify");
  auto domaind = run.start(
      run.domaind_args(),
      {{"NOTIFY_SOCKET", notify.path().string()}, {"JOURNAL_STREAM", journal_stream}}, log);
  wait_ready(notify, *domaind);
  return read_file(log);
}

// Whether this process may make a mount namespace and bind a folder over /run in it.
bool can_bind_over_run() {
  if (::access("/usr/bin/unshare", X_OK) != 0)
    return false;
  ChildProcess probe(
      "/usr/bin/unshare",
      {"--mount", "--propagation", "private", "--", "/bin/sh", "-c", "mount --bind /tmp /run"}, {});
  const auto status = probe.wait_exit(10s);
  return status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0;
}

// `command` run in a mount namespace of its own whose /run is `run_dir`.
std::vector<std::string> with_run_at(const fs::path &run_dir, std::vector<std::string> command) {
  std::vector<std::string> wrapped{"/usr/bin/unshare",
                                   "--mount",
                                   "--propagation",
                                   "private",
                                   "--",
                                   "/bin/sh",
                                   "-c",
                                   "mount --bind \"$0\" /run && exec \"$@\"",
                                   run_dir.string()};
  wrapped.insert(wrapped.end(), command.begin(), command.end());
  return wrapped;
}

// Journal messages received until one whose MESSAGE contains `text`; that one's fields.
std::map<std::string, std::string> journal_message(DatagramSocket &journal,
                                                   const std::string &text) {
  auto m = journal.wait_for(
      [&](const auto &d) {
        return journal_fields(d.text)["MESSAGE"].find(text) != std::string::npos;
      },
      10s);
  REQUIRE(m.has_value());
  return journal_fields(m->text);
}

} // namespace

TEST_CASE("with JOURNAL_STREAM naming its stderr, rsca-domaind writes no log line to stderr") {
  ServiceRun run;
  const auto log = run.dir() / "domaind.log";
  const std::string out = domaind_output(run, log, journal_stream_of(log));
  // Without a journald here, spdlog may report that it could not send ("LOG ERROR"): that is
  // the journal path failing, never a log line.
  INFO(out);
  CHECK_FALSE(has_log_lines(out, "domaind"));
}

TEST_CASE("with JOURNAL_STREAM naming another file, rsca-domaind logs to stderr as before") {
  ServiceRun run;
  const auto log = run.dir() / "domaind.log";
  const std::string out = domaind_output(run, log, journal_stream_of(run.dir() / "other"));
  INFO(out);
  CHECK(has_log_lines(out, "domaind"));
}

TEST_CASE("rsca-noded's messages reach the journal with their priority and its identifier") {
  ServiceRun run;
  if (!can_bind_over_run()) {
    std::cout << "skipped: cannot make a mount namespace (needs root) to stand in for journald\n"
              << std::flush;
    std::exit(kSkipped);
  }
  const auto fake_run = run.dir() / "run";
  fs::create_directories(fake_run / "systemd/journal");
  DatagramSocket journal(fake_run / "systemd/journal/socket");
  DatagramSocket notify(run.dir() / "noded.notify");
  const auto log = run.dir() / "noded.log";
  const ChildProcess::Environment env{{"NOTIFY_SOCKET", notify.path().string()},
                                      {"JOURNAL_STREAM", journal_stream_of(log)}};

  SECTION("info as priority 6, and nothing on stderr") {
    auto noded = run.start(with_run_at(fake_run, run.noded_args()), env, log);
    wait_ready(notify, *noded);
    auto announced = journal_message(journal, "node node1 announced with 1 device(s)");
    CHECK(announced["PRIORITY"] == "6");
    CHECK(announced["SYSLOG_IDENTIFIER"] == "rsca-noded");
    CHECK(read_file(log).empty());
  }
  SECTION("an error as priority 3") {
    auto args = run.noded_args();
    args.insert(args.end(), {"--ring-kib", "1048576"}); // refused: more than a ring may hold
    auto noded = run.start(with_run_at(fake_run, args), env, log);
    const auto status = noded->wait_exit(20s);
    CHECK((status && WIFEXITED(*status) && WEXITSTATUS(*status) == 2));
    auto refused = journal_message(journal, "a ring holds at most");
    CHECK(refused["PRIORITY"] == "3");
    CHECK(refused["SYSLOG_IDENTIFIER"] == "rsca-noded");
    CHECK(read_file(log).empty());
  }
}
