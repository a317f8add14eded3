// The daemons under systemd: what a daemon tells its service manager (sd_notify(3): its
// status while it starts, that it is ready once it serves, that it is stopping) and where it
// logs (the journal, when systemd connected its stderr to the journal). Both daemons use this and
// nothing else of libsystemd.
//
// Run by no service manager (no NOTIFY_SOCKET, no JOURNAL_STREAM) or built without libsystemd
// (RSCA_WITH_SYSTEMD off, or libsystemd absent at configure time), every call does nothing and a
// daemon logs to stderr as before.
#pragma once

#include <string>
#include <string_view>

namespace rsca::service {

// Whether this build talks to systemd (libsystemd was found and RSCA_WITH_SYSTEMD is on).
bool built_with_systemd();

// STATUS=<what>: what the daemon is doing, shown by `systemctl status`.
void notify_status(std::string_view what);
// READY=1 with STATUS=<what>: the daemon serves; `systemctl start` of a Type=notify unit
// returns now, and units ordered after it start.
void notify_ready(std::string_view what);
// STOPPING=1 with STATUS=<what>: the daemon is shutting down.
void notify_stopping(std::string_view what);

// Whether `journal_stream` (systemd's JOURNAL_STREAM, "DEVICE:INODE" in decimal) names the file
// `fd` is open on. systemd sets the variable when it connects a service's stdout or stderr to the
// journal; a process that inherited it but whose descriptor was redirected elsewhere (a child
// writing to a log file, `rsca-domaind 2>file` from a shell under systemd) sees another file.
// Null, malformed or a closed `fd`: false.
bool is_journal_stream(const char *journal_stream, int fd);

// When stderr is the journal (is_journal_stream(getenv("JOURNAL_STREAM"), 2)) and this build has
// libsystemd: the default logger becomes one that writes each message straight to the journal
// (spdlog's systemd sink), with its level as the journal's priority (trace and debug as debug,
// info, warn as warning, error, critical as crit) and `identifier` as SYSLOG_IDENTIFIER; the
// journal stamps the time itself. Returns whether it did; otherwise the logger is left as it is.
// Call first in main, before any thread logs.
bool log_to_journal_if_connected(const std::string &identifier);

} // namespace rsca::service
