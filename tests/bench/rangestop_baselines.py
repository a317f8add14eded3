"""The RangeStop benchmark's baseline ways (rangestop_bench.py): the in-process loop, a TCP stream
and raw Cyclone DDS between the simulated robot and its controller, and the summaries of their
runs. Each way is run one run at a time, so that the ways take turns run by run."""
import json
import os
import select
import statistics

from local_domain import Processes, dds_env, on_host
from port_bench_helpers import read_u64

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
# The dds way's round trips a run: about the readings of one run of the others (the drive toward
# the threshold at 0.3 m/s, 20 ms a reading).
DDS_ROUND_TRIPS_A_RUN = 250

def p50_p99(values):
    """As the DriveSystem computes them (devices/robot/robot_device.cpp, record_latency)."""
    s = sorted(values)
    return s[len(s) // 2], s[min(len(s) - 1, len(s) * 99 // 100)]


def delay_summary(values):
    p50, p99 = p50_p99(values)
    return {"mean": statistics.fmean(values), "p50": p50, "p99": p99, "max": max(values),
            "samples": len(values)}


def distance_summary(values):
    return {"mean": statistics.fmean(values),
            "sd": statistics.stdev(values) if len(values) > 1 else 0.0,
            "min": min(values), "max": max(values)}


def parse_lines(text, program):
    lines = [json.loads(line) for line in text.splitlines() if line.strip()]
    if not lines or "settings" not in lines[0]:
        raise RuntimeError(f"{program}: no header in its output: {text[:300]!r}")
    return lines[0], lines[1:]


def baseline_result(header, runs):
    delays = [d for r in runs for d in r["delays_us"]]
    return {
        "header": header,
        "runs": [dict({k: v for k, v in r.items() if k != "delays_us"},
                      delay_us=delay_summary(r["delays_us"])) for r in runs],
        "delay_us": delay_summary(delays),
        "stop_distance_m": distance_summary([r["distance_to_wall"] for r in runs]),
    }


def common_args(args, seed):
    """One run of a baseline program with the run's seed (the ways take turns run by run)."""
    return ["--runs", "1", "--first-seed", str(seed), "--speed", str(args.speed),
            "--threshold", str(args.threshold), "--period-ms", str(args.period_ms)]


def one_run(header_and_runs, run, seed):
    """The run a baseline program printed (its only one), as run `run` with `seed`."""
    header, runs = header_and_runs
    if len(runs) != 1:
        raise RuntimeError(f"expected one run, got {len(runs)}")
    return header, dict(runs[0], run=run, seed=seed)


class Inprocess:
    """The inprocess way, one run a call."""

    def __init__(self, args, logs):
        self.args, self.logs = args, logs
        self.exe = os.path.join(args.bin, "rsca-bench-rangestop-inprocess")

    def run(self, run, seed):
        with Processes() as procs:
            log = os.path.join(self.logs, f"inprocess-{run}.log")
            p = procs.start([self.exe, *common_args(self.args, seed)], os.environ, log)
            out, _ = p.communicate(timeout=90)
            if p.returncode != 0:
                raise RuntimeError(f"{self.exe} failed ({p.returncode}), see {log}")
        return one_run(parse_lines(out, self.exe), run, seed)


def read_line(proc, timeout, what):
    ready, _, _ = select.select([proc.stdout], [], [], timeout)
    line = proc.stdout.readline() if ready else ""
    if not line:
        raise RuntimeError(f"{what}: nothing on its output within {timeout} s")
    return json.loads(line)


# With --hosts: the network hosts' namespaces and addresses (tools/hosts: host i is 10.77.0.i),
# the domain daemon on the first, the controller on the second, the robot on the third.
DOMAIN_HOST, CONTROLLER_HOST, ROBOT_HOST = 0, 1, 2


def host_address(index):
    return f"10.77.0.{index + 1}"


class Tcp:
    """The tcp way, one run a call: a controller and a robot process each run."""

    def __init__(self, args, logs):
        self.args, self.logs = args, logs
        self.exe = os.path.join(args.bin, "rsca-bench-rangestop-tcp")

    def run(self, run, seed):
        hosts = self.args.net_hosts
        address = host_address(CONTROLLER_HOST) if hosts else "127.0.0.1"
        with Processes() as procs:
            controller = procs.start(
                on_host(hosts and hosts[CONTROLLER_HOST],
                        [self.exe, "--role", "controller", "--address", address,
                         *common_args(self.args, seed)]),
                os.environ, os.path.join(self.logs, f"tcp-controller-{run}.log"))
            port = read_line(controller, 10, "the TCP controller")["listening"]
            robot = procs.start(
                on_host(hosts and hosts[ROBOT_HOST],
                        [self.exe, "--role", "robot", "--port", str(port), "--address", address,
                         *common_args(self.args, seed)]),
                os.environ, os.path.join(self.logs, f"tcp-robot-{run}.log"))
            out, _ = robot.communicate(timeout=90)
            if robot.returncode != 0:
                raise RuntimeError(f"{self.exe} --role robot failed ({robot.returncode}), "
                                   f"see {self.logs}/tcp-robot-{run}.log")
            controller.wait(timeout=10)  # it leaves when the robot hangs up
        return one_run(parse_lines(out, self.exe), run, seed)


class Dds:
    """Raw Cyclone DDS between the controller's host and the robot's, with RangeStop's QoS
    (reliable, keep last 1) and its pace: `rsca-bench-raw echo` where the controller runs (for
    the whole session), and a `rsca-bench-raw ping` each run where the robot runs, a ping every
    sensor period, each answered before the next (--interval-us), about as many as the readings
    of a run of the others. A round trip is what the other ways' delay is: a reading to the
    controller and a command back, two hops, with DDS's own threads woken from idle as a periodic
    loop wakes them. Not a baseline rsca could beat by design (rsca carries its data on Cyclone
    DDS), but it tells what of rsca's delay is DDS's."""

    def __init__(self, args, logs):
        self.args, self.logs = args, logs
        self.exe = os.path.join(args.bin, "rsca-bench-raw")
        self.env = dds_env()
        if args.net_hosts:
            self.env["RSCA_DDS_INTERFACE"] = "eth0"
        self.qos = json.dumps({"reliability": "reliable", "history": "keeplast", "depth": 1})
        self.topics = [f"rsca_bench_rangestop_{name}_{os.getpid()}"
                       for name in ("reading", "command")]
        self.procs = Processes()

    def __enter__(self):
        hosts = self.args.net_hosts
        self.procs.start(on_host(hosts and hosts[CONTROLLER_HOST],
                                 [self.exe, "echo", "--in", self.topics[0], "--out",
                                  self.topics[1], "--qos", self.qos]),
                         self.env, os.path.join(self.logs, "dds-echo.log"))
        return self

    def __exit__(self, *exc):
        self.procs.close()

    def run(self, run, seed):
        hosts = self.args.net_hosts
        output = os.path.join(self.logs, f"dds-rtt-{run}.bin")
        ping = self.procs.start(
            on_host(hosts and hosts[ROBOT_HOST],
                    [self.exe, "ping", "--out", self.topics[0], "--in", self.topics[1], "--qos",
                     self.qos, "--count", str(DDS_ROUND_TRIPS_A_RUN), "--warmup", "20",
                     "--interval-us", str(self.args.period_ms * 1000), "--output", output]),
            self.env, os.path.join(self.logs, f"dds-ping-{run}.log"))
        ping.communicate(timeout=60 + DDS_ROUND_TRIPS_A_RUN * self.args.period_ms / 1000 * 2)
        if ping.returncode != 0:
            raise RuntimeError(f"{self.exe} ping failed ({ping.returncode}), see "
                               f"{self.logs}/dds-ping-{run}.log")
        return None, {"run": run, "seed": seed,
                      "delays_us": [ns / 1e3 for ns in read_u64(output)]}
