#include "node/daemon_log.hpp"

#include <limits>
#include <memory>
#include <vector>

#include <fmt/format.h>
#include <spdlog/sinks/rotating_file_sink.h>
#include <spdlog/spdlog.h>

#include "node/process_logs.hpp"

namespace rsca::node {
namespace {

namespace fs = std::filesystem;
using RotatingSink = spdlog::sinks::rotating_file_sink_mt;

// A component's log line starts so (its runtime's spdlog default): `rsca logs --since` reads the
// time there.
constexpr const char *kFilePattern = "[%Y-%m-%d %H:%M:%S.%e] [noded] [%l] %v";

} // namespace

fs::path daemon_log_file(const fs::path &log_dir, std::string_view node) {
  return log_dir / fmt::format("rsca-noded.{}.log", node);
}

Expected<void> log_also_to_file(const fs::path &file, std::uint64_t max_bytes) {
  const auto bound = max_bytes == 0 ? std::numeric_limits<std::size_t>::max()
                                    : static_cast<std::size_t>(max_bytes);
  std::shared_ptr<RotatingSink> sink;
  try { // spdlog reports a file it cannot open by throwing
    sink = std::make_shared<RotatingSink>(file.string(), bound, 1);
  } catch (const spdlog::spdlog_ex &e) {
    return make_error({file.string(), 0, 0}, "io", e.what());
  }
  sink->set_pattern(kFilePattern);
  const auto old = spdlog::default_logger();
  std::vector<spdlog::sink_ptr> sinks = old->sinks();
  sinks.push_back(std::move(sink));
  auto logger = std::make_shared<spdlog::logger>(old->name(), sinks.begin(), sinks.end());
  logger->set_level(old->level());
  logger->flush_on(spdlog::level::trace);
  spdlog::set_default_logger(std::move(logger));
  return {};
}

control::CallResult<protocol::node::LogsReply>
read_daemon_log(const fs::path &log_dir, std::string_view node,
                const protocol::node::DaemonLogsRequest &request) {
  const auto file = daemon_log_file(log_dir, node);
  const auto what = fmt::format("node {}", node);
  std::error_code ec;
  if (!fs::exists(file, ec))
    return protocol::call_error(protocol::Status::NotFound,
                                fmt::format("{} keeps no log in its log folder", what));
  return read_piece({file, RotatingSink::calc_filename(file.string(), 1)}, log_dir, request.offset,
                    request.max_bytes, what);
}

} // namespace rsca::node
