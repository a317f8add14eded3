"""The port benchmarks' helpers (tests/bench/port_bench.py): the SDR root and DDS leases of a run,
result files and their statistics, the host's state, the QoS the domain gave, and the two sides
of the latency benchmark: the rsca components (LatencyRsca) and the raw programs (LatencyRaw),
each run one round at a time."""
import array
import json
import math
import os
import statistics
import subprocess
import time

from local_domain import Processes, on_host, percentile

HERE = os.path.dirname(os.path.abspath(__file__))
SDRROOT = os.path.join(HERE, "profiles")
# The fan-out runs every process (daemons, components, raw programs alike) with a DDS participant
# lease of 10 s instead of the project's 1 s: with the 1 s lease, Cyclone's discovery traffic
# grows with the square of the participants, and a hundred idle participants on one host take two
# cores by themselves (50: ~0.8 core, 100: ~2 cores, measured); the daemons then miss their own
# leases and the domain drops its nodes. --lease-ms 1000 runs it with the default anyway.
FANOUT_LEASE_MS = 10000


def lease_env(lease_ms):
    """The environment that gives every process of the run this DDS lease: the daemons and the CLI
    (RSCA_DDS_LEASE_MS), the components and the raw programs that stand in for them
    (RSCA_DDS_COMPONENT_LEASE_MS). None: the project's own leases."""
    if not lease_ms:
        return {}
    return {"RSCA_DDS_LEASE_MS": str(lease_ms), "RSCA_DDS_COMPONENT_LEASE_MS": str(lease_ms)}
# A launch the domain rolled back (e.g. a component not registered within the domain's 10 s while
# the host is busy) is tried again, this many times in all.
LAUNCH_ATTEMPTS = 3


def read_u64(path):
    values = array.array("Q")
    with open(path, "rb") as f:
        values.frombytes(f.read())
    return values


def wait_for_file(path, size, timeout, why):
    """Waits for a result file to be complete. Files, not control calls: a CLI call during a
    measurement would start a DDS participant, whose discovery every process would feel."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if os.path.getsize(path) >= size:
                return
        except OSError:
            pass
        time.sleep(0.05)  # pacing a poll of the file system
    raise RuntimeError(f"{why}: no complete {path} after {timeout:.0f} s")


def latency_stats(values_ns):
    us = [v / 1e3 for v in values_ns]
    return {"p50_us": percentile(us, 50), "p90_us": percentile(us, 90),
            "p99_us": percentile(us, 99), "p999_us": percentile(us, 99.9),
            "min_us": min(us), "max_us": max(us), "mean_us": statistics.fmean(us),
            "count": len(us)}


def ratio(a, b):
    return a / b if b else math.inf


def host_state():
    """How busy the host's CPUs are now (over one second, from /proc/stat), its load average and
    CPU count."""
    def times():
        with open("/proc/stat") as f:
            values = [int(v) for v in f.readline().split()[1:]]
        return sum(values), values[3] + values[4]  # all, idle + iowait
    total0, idle0 = times()
    time.sleep(1.0)  # the sampling interval itself
    total1, idle1 = times()
    busy = 100.0 * (1 - (idle1 - idle0) / max(1, total1 - total0))
    return {"cpus": os.cpu_count(), "busy_percent": round(busy, 1),
            "loadavg": [round(x, 2) for x in os.getloadavg()]}


def busy_note(results):
    """A line saying the host was busy just before the run (other processes then compete for the
    CPUs with the benchmark, and latencies say more about the scheduler than about the data path),
    or nothing."""
    state = results["host_before"]
    if state["busy_percent"] > 20:
        return (f"note: the host's CPUs were {state['busy_percent']:.0f}% busy just before the run "
                f"(load average {state['loadavg'][0]:.1f} on {state['cpus']} CPUs): the figures "
                "are noisy.")
    return None


def connection_qos(domain, app):
    """The QoS the domain gave the connections of `app` (all the same here), as component.connect
    carries it: what the raw programs use."""
    reply, _ = domain.cli("ls", "connections", app)
    qos = [c["qos"] for c in reply.get("connections", []) if "qos" in c]
    if not qos:
        raise RuntimeError(f"no connection QoS in `rsca ls connections {app}`: {reply}")
    if any(q != qos[0] for q in qos):
        raise RuntimeError(f"the connections of {app} differ in QoS: {qos}")
    return qos[0]


def raw_sizes(raw, env):
    out = subprocess.run([raw, "sizes"], env=env, capture_output=True, text=True, check=True,
                         timeout=60)
    return json.loads(out.stdout)


# ---- latency ----------------------------------------------------------------------------------

def cpu_us(pid):
    """CPU time (user + system, all threads) of a live process so far, in microseconds."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) * 1e6 / os.sysconf("SC_CLK_TCK")


class LatencyRsca:
    """BenchPing_1 and BenchEcho_1 launched once (not started); each round configures the ping's
    output, starts the application, waits for the file and stops it. `path`:
    - "same_host": both on one node (placement "pack"), connected through its shared memory;
    - "relayed": on two nodes ("spread"), through each node's ring and relay (the default path);
    - "direct": on two nodes, each process on DDS itself (the connections ask transport="direct":
      a copy of the SAD made so under `work`).
    Which one the domain made is checked, not assumed."""

    def __init__(self, domain, work, count, warmup, path="relayed"):
        self.domain, self.work, self.count, self.warmup = domain, work, count, warmup
        self.name = {"same_host": "latency-same-host", "relayed": "latency",
                     "direct": "latency-direct"}[path]
        # The node daemons carry the relayed path (their rings and relays): their CPU is part of a
        # round trip's; counted apart (cpu_nodes_us) on every path, in cpu_us on the relayed one.
        self.node_pids = [pid for name, pid in domain.daemons.items() if name != "domaind"]
        self.count_nodes = path == "relayed"
        sad = os.path.join(SDRROOT, "dom/waveforms/BenchPortLatency/BenchPortLatency.sad.xml")
        installed, sdr = "BenchPortLatency", []
        if path == "direct":
            sad, root = direct_copy(sad, work)
            installed, sdr = "BenchPortLatencyDirect", ["--sdrroot", root]
        domain.cli(*sdr, "install", sad, check=False)  # once for the sides that share it
        reply, _ = domain.cli("launch", installed, "--name", self.name, "--no-start",
                              "--strategy", "pack" if path == "same_host" else "spread")
        self.pids = {c["id"]: c["pid"] for c in reply["components"]}
        self.qos = connection_qos(domain, self.name)
        listed, _ = domain.cli("ls", "connections", self.name)
        made = [connection_path(c.get("provides_state", {}))
                for c in listed.get("connections", [])]
        if not made or any(m != path for m in made):
            raise RuntimeError(f"{self.name}: connections are not all {path}: {listed}")
        domain.cli("configure", f"{self.name}/BenchPing_1", f"count={count}", f"warmup={warmup}")
        self.cpu_us = 0.0
        self.cpu_nodes_us = 0.0
        self.round_trips = 0
        self.resent = 0

    def run(self, index):
        output = os.path.join(self.work, f"{self.name}-rtt-{index}.bin")
        self.domain.cli("configure", f"{self.name}/BenchPing_1", f"output={output}")
        # The window is the components' whole run (`start` to the file), the nodes' handling of
        # `start` included: an over-count of the nodes' part, never an under-count.
        before = sum(cpu_us(p) for p in self.pids.values())
        nodes_before = sum(cpu_us(p) for p in self.node_pids)
        self.domain.cli("start", self.name)
        wait_for_file(output, 8 * self.count, 60 + self.count * 0.01, "BenchPing_1")
        nodes = sum(cpu_us(p) for p in self.node_pids) - nodes_before
        self.cpu_nodes_us += nodes
        self.cpu_us += sum(cpu_us(p) for p in self.pids.values()) - before + (
            nodes if self.count_nodes else 0.0)
        props, _ = self.domain.cli("query", f"{self.name}/BenchPing_1", "completed", "resent")
        self.domain.cli("stop", self.name)
        self.round_trips += props["properties"]["completed"]
        self.resent += props["properties"]["resent"]
        return read_u64(output)

    def close(self):
        self.domain.cli("release", self.name, check=False)


def connection_path(state):
    """How a connection end is carried, from its state in `rsca ls connections`."""
    if state.get("relayed"):
        return "relayed"
    return "same_host" if state.get("same_host") else "direct"


def direct_copy(sad, work):
    """The latency SAD with its connections asking for direct DDS, under its own name, in an SDR
    root of its own in `work` whose components are those of tests/bench/profiles. Returns the
    SAD's path and the SDR root."""
    with open(sad) as f:
        text = f.read()
    text = text.replace('name="BenchPortLatency"', 'name="BenchPortLatencyDirect"')
    text = text.replace("0d7c7d0e-5b7a-4c55-9d54-6f0f6a1b2c01",
                        "0d7c7d0e-5b7a-4c55-9d54-6f0f6a1b2c02")
    text = text.replace("    </connectinterface>",
                        '      <qos transport="direct"/>\n    </connectinterface>')
    sdr = os.path.join(work, "sdr-direct")
    folder = os.path.join(sdr, "dom/waveforms/BenchPortLatencyDirect")
    os.makedirs(folder, exist_ok=True)
    if not os.path.exists(os.path.join(sdr, "dom/components")):
        os.symlink(os.path.join(SDRROOT, "dom/components"), os.path.join(sdr, "dom/components"))
    out = os.path.join(folder, "BenchPortLatencyDirect.sad.xml")
    with open(out, "w") as f:
        f.write(text)
    return out, sdr


class RawPingSide:
    """What the raw sides share: their processes in one session (as a node's components share
    the node's), started by `start` (all stopped if one fails), and the totals run_ping adds to."""

    def __init__(self, work, count, warmup):
        self.work, self.count, self.warmup = work, count, warmup
        self.procs = Processes(shared_session=True)
        self.cpu_us = 0.0
        self.round_trips = 0
        self.resent = 0

    def start(self, starts):
        try:
            starts()
        except BaseException:
            self.procs.close()
            raise

    def close(self):
        self.procs.close()


class LatencyIceoryx(RawPingSide):
    """The raw iceoryx ping-pong (tests/bench/raw/raw_iceoryx.cpp): RouDi and the echo for the
    whole run, in one session as a node's processes are; each round runs a ping to its end. The
    payload is the size of the ping's SampleSeq on DDS."""

    def __init__(self, program, work, count, warmup, payload_bytes, spin_us=0, roudi=True):
        super().__init__(work, count, warmup)
        self.program, self.bytes = program, str(payload_bytes)
        # With roudi, this side starts the machine's RouDi; another side (roudi False) shares
        # it, its pair apart by a service instance of its own.
        self.roudi, self.instance = roudi, f"spin{spin_us}"
        self.spin = ["--spin-us", str(spin_us), "--instance", self.instance]
        self.start(self._start_roudi_and_echo)

    def _start_roudi_and_echo(self):
        if self.roudi:
            roudi = self.procs.start([self.program, "roudi"], dict(os.environ),
                                     os.path.join(self.work, "iceoryx-roudi.log"))
            wait_for_line(roudi, "ready", 30, "RouDi")
        self.echo = self.procs.start([self.program, "echo", "--bytes", self.bytes, *self.spin],
                                     dict(os.environ),
                                     os.path.join(self.work, f"iceoryx-{self.instance}-echo.log"))
        wait_for_line(self.echo, "ready", 30, "the iceoryx echo")

    def run(self, index):
        output = os.path.join(self.work, f"iceoryx-{self.instance}-rtt-{index}.bin")
        return run_ping(self, [self.program, "ping", "--bytes", self.bytes, "--count",
                               str(self.count), "--warmup", str(self.warmup), "--output", output,
                               *self.spin],
                        dict(os.environ), f"iceoryx-{self.instance}-ping-{index}.log", output)


def run_ping(side, args, env, log_name, output):
    """Runs one round's ping of a raw side (`side` has procs, echo, work, count and the totals) to
    its end; adds its CPU (and the echo's meanwhile) and round trips to the side's totals; the
    round-trip times it wrote."""
    echo_before = cpu_us(side.echo.pid)
    ping = side.procs.start(args, env, os.path.join(side.work, log_name))
    name = os.path.basename(args[0])
    try:
        out, _ = ping.communicate(timeout=60 + side.count * 0.01)
    except subprocess.TimeoutExpired:
        raise RuntimeError(f"{name} ping did not finish") from None
    if ping.returncode != 0:
        raise RuntimeError(f"{name} ping failed ({ping.returncode}); see {side.work}")
    summary_ = json.loads(out)
    # The echo's CPU over the ping's whole life (its start-up included: the echo idles then).
    side.cpu_us += summary_["cpu_us"] + cpu_us(side.echo.pid) - echo_before
    side.round_trips += summary_["completed"]
    side.resent += summary_["resent"]
    return read_u64(output)


def wait_for_line(child, line, timeout, what):
    """Waits until `child`'s stdout (its file) has `line`."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with open(child.stdout_path) as f:
                if line in f.read().split():
                    return
        except FileNotFoundError:
            pass
        child.poll()
        if child.returncode is not None:
            raise RuntimeError(f"{what} ended ({child.returncode}) before it was ready")
        time.sleep(0.05)
    raise RuntimeError(f"{what} was not ready within {timeout} s")


class LatencyRaw(RawPingSide):
    """`rsca-bench-raw echo` for the whole run; each round runs `rsca-bench-raw ping` to its end.
    The two share a session of their own, as BenchPing_1 and BenchEcho_1 share the session of the
    node that started them (local_domain.Processes says why that matters)."""

    def __init__(self, domain, raw, work, qos, count, warmup, wake, hosts=(None, None),
                 spin_us=0):
        super().__init__(work, count, warmup)
        self.domain, self.raw, self.wake = domain, raw, wake
        self.ping_host, self.echo_host = hosts  # network hosts (port_bench.py --hosts), or here
        # After data, both look for more this long before they sleep (rsca's
        # RSCA_RECEIVE_SPIN_US); the files of each spin apart.
        self.spin = ["--spin-us", str(spin_us)]
        self.label = f"{wake}-spin{spin_us}"
        self.ping_topic = f"rsca_bench_raw_ping_{wake}_{spin_us}_{os.getpid()}"
        self.echo_topic = f"rsca_bench_raw_echo_{wake}_{spin_us}_{os.getpid()}"
        self.qos = json.dumps(qos)
        self.start(self._start_echo)

    def _start_echo(self):
        self.echo = self.procs.start(
            on_host(self.echo_host,
                    [self.raw, "echo", "--in", self.ping_topic, "--out", self.echo_topic, "--qos",
                     self.qos, "--wake", self.wake, *self.spin]), self.domain.env,
            os.path.join(self.work, f"raw-{self.label}-echo.log"))

    def run(self, index):
        output = os.path.join(self.work, f"raw-{self.label}-rtt-{index}.bin")
        return run_ping(self, on_host(self.ping_host, [
                            self.raw, "ping", "--out", self.ping_topic, "--in", self.echo_topic,
                            "--qos", self.qos, "--wake", self.wake, "--count", str(self.count),
                            "--warmup", str(self.warmup), "--output", output, *self.spin]),
                        self.domain.env, f"raw-{self.label}-ping-{index}.log", output)


# The latency benchmark's sides: the rsca components on two nodes (over DDS) and on one (through
# its shared memory), the raw programs with a waitset (the baseline of the ratio lines), the raw
# programs woken the way rsca's receive loop wakes, and a raw iceoryx ping-pong.
SIDES = ("rsca", "rsca_direct", "rsca_same_host", "raw", "raw_listener", "iceoryx")
# Each side runs in two modes, in the same run: "spin", every receiving thread looks for more data
# for SPIN_US after data before it sleeps (rsca's default, RSCA_RECEIVE_SPIN_US; the raw programs
# with --spin-us), and "sleep", every one sleeps at once (RSCA_RECEIVE_SPIN_US=0, --spin-us 0).
SPIN_US = 50
MODES = {"spin": SPIN_US, "sleep": 0}
