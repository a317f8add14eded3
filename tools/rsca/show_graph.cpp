// rsca show APP --graph dot|svg [-o FILE]: the running application's picture (app_graph.hpp), as
// DOT text, or as SVG made by Graphviz's dot in a child process started the project's one way
// (process/spawn.hpp). dot reads the DOT text from a temporary file (its stdin is /dev/null) and
// writes the SVG itself, to FILE or to this process's stdout, which it shares.
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "app_graph.hpp"
#include "commands.hpp"
#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "process/run_program.hpp"
#include "protocol/application_ops.hpp"

namespace rsca::cli {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr auto kDotTimeout = 30s;

tl::unexpected<Error> graphviz_error(std::string message) {
  return make_error({"dot", 0, 0}, "graphviz", std::move(message));
}

Expected<fs::path> find_dot() {
  if (auto dot = process::find_program("dot"))
    return *dot;
  return graphviz_error("no Graphviz dot in PATH: --graph svg needs it (install the Debian "
                        "package graphviz: apt-get install graphviz), or use --graph dot");
}

// A file of this process's own in the temporary folder, removed when it goes.
class TempFile {
public:
  static Expected<TempFile> create(const std::string &suffix) {
    std::string name = (fs::temp_directory_path() / ("rsca-graph-XXXXXX" + suffix)).string();
    const int fd = ::mkstemps(name.data(), static_cast<int>(suffix.size()));
    if (fd < 0)
      return make_error({name, 0, 0}, "write", process::errno_text(errno));
    ::close(fd);
    return TempFile(name);
  }
  TempFile(TempFile &&other) noexcept : path_(std::exchange(other.path_, {})) {}
  TempFile(const TempFile &) = delete;
  TempFile &operator=(const TempFile &) = delete;
  TempFile &operator=(TempFile &&) = delete;
  ~TempFile() {
    std::error_code ec;
    if (!path_.empty())
      fs::remove(path_, ec);
  }
  const fs::path &path() const { return path_; }

private:
  explicit TempFile(fs::path path) : path_(std::move(path)) {}
  fs::path path_;
};

Expected<void> write_file(const fs::path &file, const std::string &text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (out)
    out << text;
  if (!out)
    return make_error({file.string(), 0, 0}, "write",
                      fmt::format("cannot write {}: {}", file.string(), std::strerror(errno)));
  return {};
}

// `dot_text` as SVG, by `dot`, into `output` (empty: this process's stdout).
Expected<void> render_svg(const fs::path &dot, const std::string &dot_text,
                          const std::string &output) {
  auto input = TempFile::create(".dot");
  if (!input)
    return tl::unexpected(std::move(input.error()));
  if (auto written = write_file(input->path(), dot_text); !written)
    return written;
  std::vector<std::string> args{"-Tsvg"};
  if (!output.empty())
    args.insert(args.end(), {"-o", output});
  args.push_back(input->path().string());
  std::fflush(stdout); // what this process printed comes before dot's output
  // dot lays out a picture of a hundred components in well under a second: past this it is stuck.
  if (auto ran = process::run_to_end({.program = dot, .args = args}, kDotTimeout); !ran)
    return graphviz_error(ran.error());
  return {};
}

} // namespace

int show_application_graph(const std::string &name, const GraphOptions &options,
                           const GlobalOptions &global) {
  Expected<fs::path> dot = fs::path();
  if (options.format == "svg")
    dot = find_dot(); // before the domain is asked: a missing dot is known at once
  if (!dot) {
    return fail(global, "show", kFailed, dot.error().to_string());
  }
  auto client = DomainClient::connect(global);
  if (!client) {
    return fail(global, "show", kFailed, client.error().to_string());
  }
  auto app = client->call<protocol::application::Show>(
      {name}, std::chrono::milliseconds(global.timeout_ms) * 2);
  if (!app)
    return report_failure(global, "show", app.error());
  const std::string text = application_dot(*app);
  Expected<void> done;
  if (options.format == "svg")
    done = render_svg(*dot, text, options.output);
  else if (!options.output.empty())
    done = write_file(options.output, text);
  else
    fmt::print("{}", text);
  if (!done) {
    return fail(global, "show", kFailed, done.error().to_string());
  }
  return kOk;
}

} // namespace rsca::cli
