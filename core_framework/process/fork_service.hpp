// The serving side of a fork server (process/fork_server.hpp is the node's side): what a
// component executable does when its node starts it as one.
//
// Why: a component process costs about 3 ms of CPU before its main runs on this class of machine
// (exec, mapping, the dynamic loader's relocations of libstdc++, spdlog, Cyclone DDS and OpenSSL),
// three quarters of what it costs the node to launch it. A node that launches many processes of
// one executable starts it once, loaded, and forks it for each (as Android's zygote does): a
// fork of a loaded process that has run no thread costs a fraction of an exec.
//
// Each request is served by forking twice: the middle process forks the component process and
// exits, so the component is re-parented to the node, the child subreaper that started the fork
// server (gpp/process_launcher.hpp), and is the node's to reap and signal as if it had been
// spawned. The component process then takes what the request gives it, the way process/spawn.hpp
// gives a spawned process: its own process group, stdin from /dev/null, stdout and stderr to its
// log file, its inherited descriptors and no other, its working directory, environment variables,
// CPUs and command line (/proc/PID/cmdline, where the kernel lets it be set), and returns to main.
//
// What it shares with its fork server, and a spawned process would not: what static initialisers
// did, and the address space's layout.
#pragma once

#include <string_view>

namespace rsca::process {

// Without kForkServerVariable in the environment: returns at once. With it: says `ready` (the
// executable's kForkServerReady: process/fork_request.hpp), serves requests until the node
// closes its socket, then exits; returns only in a started component process, `argc` and `argv`
// that process's. Must be called before any thread starts.
void serve_forks_if_asked(int &argc, char **&argv, std::string_view ready);

} // namespace rsca::process
