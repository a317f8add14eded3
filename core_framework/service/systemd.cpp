#include "service/systemd.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <charconv>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include <spdlog/spdlog.h>

#if RSCA_WITH_SYSTEMD
#include <spdlog/sinks/systemd_sink.h>
#include <systemd/sd-daemon.h>
#endif

namespace rsca::service {
namespace {

// One line: a newline in a notification would start another assignment (a status naming a
// file with a newline in it could say READY=1).
std::string one_line(std::string_view text) {
  std::string line(text);
  for (char &c : line)
    if (c == '\n' || c == '\r')
      c = ' ';
  return line;
}

// Sends `state` (newline-separated assignments) to the service manager, if there is one.
void notify(const std::string &state) {
#if RSCA_WITH_SYSTEMD
  // 0: NOTIFY_SOCKET is not set (not run by systemd, or as Type=simple); nothing to tell.
  // The variable stays in the environment: the daemon notifies until it exits, and the processes
  // a node starts, which inherit it, never notify (NotifyAccess=main would ignore them anyway).
  if (const int sent = sd_notify(0, state.c_str()); sent < 0)
    spdlog::warn("cannot notify the service manager ({}): {}", state, std::strerror(-sent));
#else
  (void)state;
#endif
}

// A decimal unsigned number that is all of `text`.
bool parse_number(std::string_view text, unsigned long long &out) {
  const auto *end = text.data() + text.size();
  const auto [at, error] = std::from_chars(text.data(), end, out);
  return !text.empty() && error == std::errc() && at == end;
}

} // namespace

bool built_with_systemd() {
  return RSCA_WITH_SYSTEMD != 0;
}

void notify_status(std::string_view what) {
  notify("STATUS=" + one_line(what));
}

void notify_ready(std::string_view what) {
  notify("READY=1\nSTATUS=" + one_line(what));
}

void notify_stopping(std::string_view what) {
  notify("STOPPING=1\nSTATUS=" + one_line(what));
}

bool is_journal_stream(const char *journal_stream, int fd) {
  if (journal_stream == nullptr)
    return false;
  const std::string_view value(journal_stream);
  const auto colon = value.find(':');
  unsigned long long device = 0;
  unsigned long long inode = 0;
  if (colon == std::string_view::npos || !parse_number(value.substr(0, colon), device) ||
      !parse_number(value.substr(colon + 1), inode))
    return false;
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    return false;
  return st.st_dev == device && st.st_ino == inode;
}

bool log_to_journal_if_connected(const std::string &identifier) {
#if RSCA_WITH_SYSTEMD
  if (!is_journal_stream(std::getenv("JOURNAL_STREAM"), STDERR_FILENO))
    return false;
  // Unformatted: the journal keeps the time, the priority and the identifier as fields of their
  // own, and `journalctl` prints them; a formatted line would repeat them in the message.
  auto sink = std::make_shared<spdlog::sinks::systemd_sink_mt>(identifier);
  auto logger = std::make_shared<spdlog::logger>(identifier, std::move(sink));
  logger->set_level(spdlog::default_logger()->level());
  spdlog::set_default_logger(std::move(logger));
  return true;
#else
  (void)identifier;
  return false;
#endif
}

} // namespace rsca::service
