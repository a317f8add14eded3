"""A real local rsca domain for the benchmarks, and the helpers they share (domain_bench.py,
port_bench.py; run by tools/bench, never by ctest).

Domain starts `rsca domain up` (a domain daemon and N node daemons) on a DDS domain id and run
folder of its own, optionally on another SDR root, and runs the CLI against it. Processes starts
other programs, each in a process group of its own. Both kill everything they started when they
go, also on failure: the daemons are taken down gracefully first, then whatever is left of them,
of the component processes they ran and of the other programs is killed by process group.
"""
import argparse
import json
import os
import select
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time


def bench_arguments(doc, sdrroot=True):
    """The arguments every benchmark script takes from tools/bench: the build's bin folder, the
    SDR root (when it launches profiles), the JSON results file and --quick. `doc` is the script's
    docstring, whose first line describes it."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--bin", required=True, help="the build's bin folder")
    if sdrroot:
        parser.add_argument("--sdrroot", required=True, help="the SDR root of the profiles")
    parser.add_argument("--out", required=True, help="the JSON results file")
    parser.add_argument("--quick", action="store_true", help="fewer runs")
    return parser


def percentile(values, p):
    ordered = sorted(values)
    index = min(len(ordered) - 1, max(0, round(p / 100 * (len(ordered) - 1))))
    return ordered[index]


def summary(values):
    return {"median": statistics.median(values), "p95": percentile(values, 95),
            "min": min(values), "max": max(values), "runs": len(values)}


def memory_kb(pid):
    fields = {}
    with open(f"/proc/{pid}/smaps_rollup") as f:
        for line in f:
            parts = line.split()
            if len(parts) >= 2 and parts[0].endswith(":") and parts[1].isdigit():
                fields[parts[0][:-1]] = int(parts[1])
    return {"rss_kb": fields["Rss"], "pss_kb": fields["Pss"],
            "private_kb": fields.get("Private_Clean", 0) + fields.get("Private_Dirty", 0)}


def cpu_ticks(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return int(fields[11]) + int(fields[12])  # utime + stime


def alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def kill_group(pid, sig=signal.SIGKILL):
    """Signals the process group led by `pid`: the daemons, the component processes and what
    Processes starts each lead their own. (A group id is not reused while the group has members,
    so this never reaches a stranger.)"""
    try:
        os.killpg(pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def wait_gone(pids, timeout):
    deadline = time.monotonic() + timeout
    while any(alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)  # pacing a poll of processes exiting
    return not any(alive(p) for p in pids)


def dds_env():
    """The environment of a benchmark run's DDS programs: a DDS domain id and discovery tag of
    the run's own, so that nothing else on the host takes part."""
    # DDS domain ids up to 101 (dds::kLastPortSafeDomainId, core_framework/dds/dds_settings.hpp):
    # a domain's discovery port must stay below the kernel's ephemeral ports, which any socket
    # may take first; the tag separates runs whose ids collide.
    return dict(os.environ, RSCA_DDS_DOMAIN=str(1 + os.getpid() % 101),
                RSCA_DDS_TAG=f"bench-{os.getpid()}")


class NetHosts:
    """`tools/hosts up N` (network namespaces on a bridge; needs root), removed when it goes, also
    on failure. `hosts`: their namespaces; a process runs on one as `ip netns exec HOST ...`."""
    TOOL = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))), "tools/hosts")

    def __init__(self, count):
        self.name = f"rsca{os.getpid()}b"
        self.count = count
        self.hosts = []

    @classmethod
    def unavailable(cls):
        """Why hosts cannot be made here, or None when they can."""
        probe = subprocess.run([cls.TOOL, "probe"], capture_output=True, text=True)
        return None if probe.returncode == 0 else probe.stderr.strip()

    def __enter__(self):
        out = subprocess.run([self.TOOL, "up", str(self.count), "--name", self.name],
                             capture_output=True, text=True)
        if out.returncode != 0:
            raise RuntimeError(f"tools/hosts up: {out.stderr.strip()}")
        self.hosts = [line.split()[0] for line in out.stdout.splitlines() if line.strip()]
        return self

    def __exit__(self, *exc):
        subprocess.run([self.TOOL, "down", self.name], capture_output=True)


def skipped_without_hosts(out_path):
    """True, having said why and written it as the results, when network hosts cannot be made."""
    why = NetHosts.unavailable()
    if not why:
        return False
    print(f"skipped: {why}")
    with open(out_path, "w") as f:
        json.dump({"skipped": why}, f)
    return True


def on_host(host, args):
    """`args` run on network host `host` (a namespace of NetHosts), or here when None."""
    return ["ip", "netns", "exec", host, *args] if host else list(args)


def work_dir(prefix, components_write=False):
    """A new folder in the temporary folder, which the components' user can pass through (the
    nodes run components as their GPP's run_as user, `rsca` or else `nobody`: mkdtemp makes it
    0700) and, with `components_write`, write their result files into."""
    folder = tempfile.mkdtemp(prefix=prefix)
    os.chmod(folder, 0o1777 if components_write else 0o755)
    return folder


class Domain:
    """`rsca domain up --nodes N` on a DDS domain id and run folder of its own. With `sdrroot`,
    the DMD and the node DCDs (dev/nodes/node1..N) come from that SDR root; `env` adds to the
    environment of the daemons (and so of the components) and of the CLI, e.g. RSCA_DDS_* settings
    (docs/architecture.md). `env` is what other programs of the run must use to join the domain."""

    def __init__(self, rsca, nodes, sdrroot=None, env=None, domaind_args=None, cli_args=None,
                 hosts=None, cli_host=None, node_dcds=None):
        self.rsca = rsca
        # The node daemons as (name, DCD) pairs, the k-th on hosts[k + 1] (with hosts); None:
        # node1..N of the SDR root's dev/nodes.
        self.node_dcds = node_dcds
        # With hosts (network namespaces, tools/hosts), the daemons are started by hand, the domain
        # daemon on hosts[0] and node i on hosts[i]; with cli_host, the CLI runs on that host and
        # over DDS (not through a node's socket).
        self.hosts = hosts
        self.cli_host = cli_host
        # With domaind_args (e.g. ["--registration-timeout-ms", "60000"]), the daemons are started
        # here as `rsca domain up` starts them (own session, log and pid file in the run folder,
        # the SDR root's DMD and dev/nodes/nodeI DCDs), rsca-domaind with these arguments more.
        self.domaind_args = domaind_args
        # Global CLI options of every call through cli(), e.g. ["--timeout-ms", "30000"].
        self.cli_args = cli_args or []
        self.spawned = []
        self.run_dir = work_dir("rsca-bench-")
        self.env = dict(dds_env(), RSCA_RUN_DIR=self.run_dir, **(env or {}))
        self.nodes = nodes
        self.sdrroot = sdrroot
        self.daemons = {}
        self.components = set()  # pids of component processes launched, killed at the end
        self.exe_dir = os.path.dirname(os.path.realpath(rsca))

    def _global(self):
        return ["--sdrroot", self.sdrroot] if self.sdrroot else []

    def cli(self, *args, check=True, timeout=600):
        started = time.perf_counter()
        command, env = [self.rsca, "--json", *self.cli_args, *args], self.env
        if self.cli_host:
            command = on_host(self.cli_host, command)
            env = dict(env, RSCA_NODE_SOCKET="none")
        else:  # here, through a node's socket; over DDS only on loopback, never this machine's
            env = {k: v for k, v in env.items() if k != "RSCA_DDS_INTERFACE"}  # own network
        out = subprocess.run(command, env=env, capture_output=True, text=True, timeout=timeout)
        elapsed = (time.perf_counter() - started) * 1e3
        if check and out.returncode != 0:
            raise RuntimeError(f"rsca {' '.join(args)} failed ({out.returncode}): "
                               f"{out.stderr}{out.stdout}")
        reply = json.loads(out.stdout) if out.stdout.strip() else {}
        self._remember_components(reply)
        return reply, elapsed

    def _remember_components(self, reply):
        def walk(node):
            if isinstance(node, dict):
                for c in node.get("components", []) if isinstance(node.get("components"),
                                                                   list) else []:
                    if isinstance(c, dict) and isinstance(c.get("pid"), int) and c["pid"] > 0:
                        self.components.add(c["pid"])
                for v in node.values():
                    walk(v)
            elif isinstance(node, list):
                for v in node:
                    walk(v)
        walk(reply)

    def _spawn(self, name, args, host=None):
        args = on_host(host, args)
        with open(os.path.join(self.run_dir, f"{name}.log"), "ab") as log:
            proc = subprocess.Popen(args, env=self.env, stdin=subprocess.DEVNULL, stdout=log,
                                    stderr=subprocess.STDOUT, start_new_session=True)
        self.spawned.append(proc)
        with open(os.path.join(self.run_dir, f"{name}.pid"), "w") as f:
            f.write(f"{proc.pid}\n")

    def _up_by_hand(self):
        bin_dir = os.path.dirname(os.path.realpath(self.rsca))
        sdrroot = self.sdrroot or os.path.join(bin_dir, "../../profiles")
        os.makedirs(os.path.join(self.run_dir, "logs"), exist_ok=True)
        self._spawn("domaind", [os.path.join(bin_dir, "rsca-domaind"), "--dmd",
                                os.path.join(sdrroot, "dom/domain/DomainManager.dmd.xml"),
                                "--repository", os.path.join(self.run_dir, "repository"),
                                *(self.domaind_args or [])], host=self.hosts and self.hosts[0])
        dcds = self.node_dcds or [
            (f"node{i}", os.path.join(sdrroot, f"dev/nodes/node{i}/DeviceManager.dcd.xml"))
            for i in range(1, self.nodes + 1)]
        for i, (name, dcd) in enumerate(dcds, start=1):
            self._spawn(name, [
                os.path.join(bin_dir, "rsca-noded"), "--dcd", dcd, "--sdrroot", sdrroot, "--log-dir",
                os.path.join(self.run_dir, "logs"), "--exec-path", bin_dir,
                "--control-socket", os.path.join(self.run_dir, f"{name}.sock")],
                host=self.hosts and self.hosts[i])
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                reply, _ = self.cli("ls", "nodes", check=False, timeout=30)
            except ValueError:  # not JSON: the domain daemon is not there yet
                reply = {}
            if len(reply.get("nodes", [])) >= self.nodes:
                return
            time.sleep(0.2)  # pacing a poll of the domain
        raise RuntimeError(f"the nodes did not all register within 60 s (see {self.run_dir})")

    def __enter__(self):
        try:
            if self.domaind_args is not None or self.hosts or self.node_dcds:
                self._up_by_hand()
            else:
                subprocess.run([self.rsca, *self._global(), "domain", "up", "--nodes",
                                str(self.nodes)], env=self.env, check=True,
                               stdout=subprocess.DEVNULL, timeout=120)
        except BaseException:
            self.daemons = self.daemon_pids()
            self.__exit__(*sys.exc_info())
            raise
        self.daemons = self.daemon_pids()
        return self

    def __exit__(self, *exc):
        try:
            subprocess.run([self.rsca, "domain", "down"], env=self.env,
                           stdout=subprocess.DEVNULL, timeout=60)
        except (subprocess.SubprocessError, OSError):
            pass
        # Whatever survived: the daemons lead their sessions, each component its group.
        leftovers = [p for p in list(self.daemons.values()) + sorted(self.components)
                     if alive(p) and self._ours(p)]
        for pid in leftovers:
            kill_group(pid)
        wait_gone(leftovers, 5)
        for proc in self.spawned:  # stopped as a service manager would, first
            if proc.poll() is None:
                proc.terminate()
        for proc in self.spawned:  # reaped: no zombie outlives the benchmark
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                kill_group(proc.pid)
                proc.wait()
        # The run folder (daemon and component logs) stays only when something went wrong.
        if exc[0] is None:
            shutil.rmtree(self.run_dir, ignore_errors=True)
        else:
            print(f"local domain: logs kept in {self.run_dir}", file=sys.stderr)

    def _ours(self, pid):
        """Whether `pid` still runs one of the build's programs (and is not a reused pid)."""
        try:
            return os.path.dirname(os.path.realpath(f"/proc/{pid}/exe")) == self.exe_dir
        except OSError:
            return False

    def daemon_pids(self):
        pids = {}
        for name in sorted(os.listdir(self.run_dir)):
            if name.endswith(".pid"):
                with open(os.path.join(self.run_dir, name)) as f:
                    pids[name[:-4]] = int(f.read().split()[0])
        return pids


# The leader of a shared session (Processes(shared_session=True)). It starts programs in its
# session on request (a JSON line on stdin: args, env, stdout and stderr paths), each in a process
# group of its own, and says so on stdout ({"started": pid} or {"error": why}); a thread waits for
# them, blocked, and reports each end ({"exited": pid, "returncode": rc}). It never polls: it runs
# in the session it serves, and a process that woke up there would share the benchmark's CPUs as
# no process in a node's session does. When stdin closes, what it started and is still running
# is killed.
SESSION_LEADER = r"""
import json, os, signal, sys, threading
lock = threading.Condition()
running = set()

def say(message):
    with lock:
        sys.stdout.write(json.dumps(message) + "\n")
        sys.stdout.flush()

def reap():
    while True:
        with lock:
            while not running:
                lock.wait()
        pid, status = os.wait()
        with lock:
            running.discard(pid)
        say({"exited": pid, "returncode": os.waitstatus_to_exitcode(status)})

threading.Thread(target=reap, daemon=True).start()
for line in sys.stdin:
    request = json.loads(line)
    try:
        files = [(os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0),
                 (os.POSIX_SPAWN_OPEN, 1, request["stdout"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644),
                 (os.POSIX_SPAWN_OPEN, 2, request["stderr"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)]
        with lock:
            pid = os.posix_spawnp(request["args"][0], request["args"], request["env"],
                                  file_actions=files, setpgroup=0)
            running.add(pid)
            lock.notify()
        say({"started": pid})
    except Exception as e:
        say({"error": f"cannot start {request['args'][0]}: {e}"})
with lock:
    for pid in running:
        try:
            os.killpg(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
"""


class SessionChild:
    """A program a session leader started: what Processes needs of a subprocess.Popen (pid, poll,
    communicate, returncode); its stdout is read from the file it went to."""

    def __init__(self, leader, pid, stdout_path):
        self.leader, self.pid, self.stdout_path = leader, pid, stdout_path
        self.returncode = None

    def poll(self):
        self.returncode = self.leader.returncode(self.pid, 0)
        return self.returncode

    def communicate(self, timeout=None):
        self.returncode = self.leader.returncode(self.pid, timeout)
        if self.returncode is None:
            raise subprocess.TimeoutExpired(str(self.pid), timeout)
        with open(self.stdout_path) as f:
            return f.read(), None


class SessionLeader:
    """A process in a new session of its own that starts programs in that session for us
    (SESSION_LEADER)."""

    def __init__(self):
        self.proc = subprocess.Popen([sys.executable, "-c", SESSION_LEADER],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     start_new_session=True)
        self.pending = b""   # what was read of the leader's stdout beyond the last whole line
        self.exited = {}     # pid -> return code, as reported
        self.started = []    # the leader's answers to start requests, in order

    def _read(self, timeout):
        """Takes in the leader's next messages; waits up to `timeout` s (None: for ever) for
        some. Returns whether any came."""
        fd = self.proc.stdout.fileno()
        if not select.select([fd], [], [], timeout)[0]:
            return False
        chunk = os.read(fd, 65536)
        if not chunk:
            raise RuntimeError("the session leader of the benchmark's processes exited")
        *lines, self.pending = (self.pending + chunk).split(b"\n")
        for line in lines:
            message = json.loads(line)
            if "exited" in message:
                self.exited[message["exited"]] = message["returncode"]
            else:
                self.started.append(message)
        return True

    def start(self, args, env, log_path):
        stdout_path = log_path + ".out"
        request = {"args": args, "env": env, "stdout": stdout_path, "stderr": log_path}
        self.proc.stdin.write((json.dumps(request) + "\n").encode())
        self.proc.stdin.flush()
        while not self.started:
            if not self._read(30):
                raise RuntimeError(f"the session leader did not start {args[0]} within 30 s")
        answer = self.started.pop(0)
        if "error" in answer:
            raise RuntimeError(answer["error"])
        return SessionChild(self, answer["started"], stdout_path)

    def returncode(self, pid, timeout):
        """`pid`'s return code once it has ended, waiting up to `timeout` s (None: for ever) for
        that; None if it still runs."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while pid not in self.exited:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if not self._read(left):
                return None
        return self.exited[pid]

    def close(self):
        """Ends the leader, which kills what it started and still runs."""
        self.proc.stdin.close()
        try:
            self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            kill_group(self.proc.pid)
            self.proc.wait()


class Processes:
    """Programs started for a benchmark, each in a process group of its own; all of them are
    stopped (SIGTERM, then SIGKILL) when it goes, also on failure. Each is in a session of its own,
    or with `shared_session` all are in one new session, as the component processes a node
    starts share its session: with autogroup scheduling (Linux's default) a session is a
    scheduling group, and that changes how processes that talk to each other are scheduled
    (docs/architecture.md)."""

    def __init__(self, shared_session=False):
        self.started = []
        self.leader = SessionLeader() if shared_session else None

    def start(self, args, env, log_path):
        if self.leader is not None:
            proc = self.leader.start(args, env, log_path)
            self.started.append(proc)
            return proc
        log = open(log_path, "w")
        try:
            proc = subprocess.Popen(args, env=env, stdin=subprocess.DEVNULL,
                                    stdout=subprocess.PIPE, stderr=log, text=True,
                                    start_new_session=True)
        finally:
            log.close()
        self.started.append(proc)
        return proc

    @staticmethod
    def stop(procs, timeout=10):
        """SIGTERM to each, then SIGKILL to what is still there after `timeout`; returns each
        one's stdout."""
        for p in procs:
            if p.poll() is None:
                kill_group(p.pid, signal.SIGTERM)
        outputs = []
        deadline = time.monotonic() + timeout
        for p in procs:
            try:
                out, _ = p.communicate(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                kill_group(p.pid)
                out, _ = p.communicate()
            outputs.append(out)
        return outputs

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        """Stops every program started, and their process groups, also when stopping them
        fails (e.g. the session leader is gone)."""
        try:
            running = [p for p in self.started if p.poll() is None]
            if running:
                self.stop(running, timeout=5)
        finally:
            for p in self.started:  # their groups too: nothing they started may outlive them
                kill_group(p.pid)
            if self.leader is not None:
                self.leader.close()
