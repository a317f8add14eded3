// The daemons run as systemd runs them, for the service tests: a folder of the test's own (the
// notify socket, the daemons' stderr, the domain's store, the node's control socket), a DDS
// domain of its own, and a client endpoint on it. Every process started is killed and reaped
// when its guard goes, also when the test fails. A build without libsystemd has nothing to
// test here: the test process exits 77, which ctest reports as skipped.
#pragma once

#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "../integration/child_process.hpp"
#include "../integration/wait_for.hpp"
#include "../unit/test_domain.hpp"
#include "control/endpoint.hpp"
#include "notify_socket.hpp"
#include "service/systemd.hpp"

namespace rsca::test {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using rsca::control::Json;

inline const fs::path kBin = RSCA_BIN_DIR;
inline const fs::path kSource = RSCA_SOURCE_DIR;
inline constexpr int kSkipped = 77; // SKIP_RETURN_CODE in tests/CMakeLists.txt

// How long a daemon may take to be ready: a 2-core CI host running the suite in parallel.
inline constexpr auto kReadyWithin = 30s;

// The whole of a (small) file.
inline std::string read_file(const fs::path &path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// systemd's JOURNAL_STREAM for `path` ("DEVICE:INODE"), the file made empty if it is not there.
inline std::string journal_stream_of(const fs::path &path) {
  std::ofstream(path, std::ios::app).close();
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return fmt::format("{}:{}", st.st_dev, st.st_ino);
}

class ServiceRun {
public:
  ServiceRun()
      : dir_(fs::temp_directory_path() /
             fmt::format("rsca-svc-{}-{}", getpid(), std::random_device{}())) {
    if (!service::built_with_systemd()) {
      std::cout << "skipped: this build has no libsystemd (RSCA_WITH_SYSTEMD)\n" << std::flush;
      std::exit(kSkipped);
    }
    fs::create_directories(dir_);
    env_ = {{"RSCA_DDS_DOMAIN", std::to_string(isolated_domain_id())},
            {"RSCA_DDS_TAG", isolated_tag()}};
  }
  ~ServiceRun() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  ServiceRun(const ServiceRun &) = delete;
  ServiceRun &operator=(const ServiceRun &) = delete;

  const fs::path &dir() const { return dir_; }

  // The environment of this run's DDS domain, with `more`.
  ChildProcess::Environment env(const ChildProcess::Environment &more = {}) const {
    auto all = env_;
    all.insert(all.end(), more.begin(), more.end());
    return all;
  }

  // rsca-domaind's command line, its store in the run's folder.
  std::vector<std::string> domaind_args() const {
    return {(kBin / "rsca-domaind").string(), "--repository", (dir_ / "repository").string()};
  }

  // rsca-noded's command line for the project's node1, its control socket in the run's folder.
  std::vector<std::string> noded_args() const {
    return {(kBin / "rsca-noded").string(),
            "--dcd",
            (kSource / "profiles/dev/nodes/node1/DeviceManager.dcd.xml").string(),
            "--log-dir",
            (dir_ / "logs").string(),
            "--exec-path",
            kBin.string(),
            "--control-socket",
            node_socket().string()};
  }
  fs::path node_socket() const { return dir_ / "node1.sock"; }

  // Starts `command` (program first) with the run's environment and `more`, its stdout and
  // stderr to `log`.
  std::unique_ptr<ChildProcess> start(std::vector<std::string> command,
                                      const ChildProcess::Environment &more, const fs::path &log) {
    const std::string program = command.front();
    command.erase(command.begin());
    return std::make_unique<ChildProcess>(program, command, env(more), log);
  }

  // The test's endpoint on the run's DDS domain, opened on first use.
  control::Endpoint &client() {
    if (!client_) {
      participant_ = participant();
      auto endpoint = control::Endpoint::open(
          participant_, fmt::format("rsca/cli/svc-{}", getpid()), control::EndpointOptions{});
      REQUIRE(endpoint.has_value());
      client_ = std::move(*endpoint);
    }
    return *client_;
  }

  // Runs the CLI with the run's environment and `more`; its exit code and output.
  std::pair<int, std::string> cli(const std::vector<std::string> &args,
                                  const ChildProcess::Environment &more = {}) {
    const fs::path out = dir_ / fmt::format("cli-{}.out", ++cli_runs_);
    ChildProcess cli((kBin / "rsca").string(), args, env(more), out);
    const auto status = cli.wait_exit(60s);
    return {status && WIFEXITED(*status) ? WEXITSTATUS(*status) : -1, read_file(out)};
  }

private:
  fs::path dir_;
  ChildProcess::Environment env_;
  std::shared_ptr<dds::Participant> participant_;
  std::unique_ptr<control::Endpoint> client_;
  int cli_runs_ = 0;
};

// A daemon's notifications: READY=1 within kReadyWithin, from the daemon's own process.
inline DatagramSocket::Message wait_ready(DatagramSocket &notify, const ChildProcess &daemon) {
  auto ready = notify.wait_for([](const auto &m) { return assigns(m, "READY=1"); }, kReadyWithin);
  REQUIRE(ready.has_value());
  CHECK(ready->pid == daemon.pid()); // NotifyAccess=main takes only the main process's
  return *ready;
}

} // namespace rsca::test
