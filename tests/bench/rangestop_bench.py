#!/usr/bin/env python3
"""The RSCA paper's three-way comparison (run by tools/bench, never by ctest): the same StopCrash
control loop (drive toward the wall at 0.3 m/s, the IR range read every 20 ms, stop below 0.6 m)
run three ways, in real time, each over 20 runs (--quick: 1), the ways taking turns run by run
(run i: each way once with seed 1 + i, in an order rotated by one each run; METHOD says how each
is measured, and the output says it too):

- inprocess: one process, direct calls (tests/bench/rangestop/rangestop_inprocess.cpp): the world
  stepped in real time on one thread, a sensor thread every period calling the controller, which
  calls the drive. Delay: from the reading's timestamp to the drive's call.
- tcp: two processes over loopback TCP with TCP_NODELAY (tests/bench/rangestop/rangestop_tcp.cpp):
  the robot (world, sensor, drive) sends each reading with its timestamp, the controller answers
  with a command carrying it back. Delay: from the reading's timestamp to the command's arrival.
- dds (not the paper's; a baseline of what rsca is built on): raw Cyclone DDS ping-pong between
  the controller's and the robot's host with RangeStop's QoS, one round trip a sensor period
  (class Dds). Delay: the round trip, a reading there and a command back.
- rsca: a real local domain (rsca-domaind, rsca-noded for node1, a GPP, and rsca-noded for the
  robot's DCD), RangeStop launched: StopCrash in a process of its own on node1, the IRSensor and
  the DriveSystem devices in the robot's node daemon, connected over Cyclone DDS. Delay: each
  command's, taken at the drive (the DriveSystem's command log: every recent command's delay and
  the world's time at its arrival), from the run's start until the robot rests, as for the
  baselines; the commands StopCrash sends after rest are cut off (and counted). The mean and the
  percentiles are computed here over every run's commands. Each run lasts what the last baseline
  run took to rest (its world time), and a little longer if StopCrash has not stopped yet.
  Between runs the application is stopped, the Robot given the run's seed and reset (its world
  re-created, the robot back at its start), and the application started again (StopCrash.start()
  clears its latch). The CLI is not called while StopCrash runs: every CLI call is a DDS
  participant whose discovery every process of the domain feels (on an idle 2-core host, the
  DriveSystem's p99 was 1.0 ms over a quiet minute, 2.8 ms over that minute and one of CLI queries
  back to back). So the script sleeps for the last baseline run's time to rest (without one:
  the drive toward the wall plus a margin, REST_MARGIN_S), stops the application, checks that
  StopCrash had stopped the robot, and then polls the Robot until it rests.

Run i (from 0) uses seed 1 + i in all three ways (the sensor's noise). The stopping distance is the
exact distance from the sensor to the wall at rest (world.true_range(0); the Robot's
distance_to_wall). The prediction is sim::stop_tolerance with latency = the sensor period: the
robot should rest no nearer than threshold - tolerance, give or take the noise (sigma 5 mm).
Delay percentiles are sorted[n/2] and sorted[n*99/100] over every run's commands, for every way.

With --hosts (root; tools/hosts), as the paper ran it, across two network hosts: the robot (its
node daemon for rsca, the robot process for tcp) on one, the controller (for rsca the node
`controller`, whose GPP leaves StopCrash free on its CPUs as the TCP controller process is, or with
--pinned node1, which pins it to the CPU admission chose; running StopCrash,
the controller process) on the other, the domain daemon on a third; DDS and TCP over the hosts'
network interfaces. It prints `ratio rsca/tcp delay p50 = R` (issue 21's target: at most 1.2),
and with the dds way `ratio rsca/dds delay p50 = R`.

Every process started is stopped at the end, also on failure.
"""
import argparse
import contextlib
import json
import os
import platform
import subprocess
import sys
import time

from local_domain import Domain, NetHosts, skipped_without_hosts
from rangestop_baselines import Dds, Inprocess, Tcp, baseline_result, delay_summary, distance_summary

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
WAYS = ("inprocess", "tcp", "dds", "rsca")
# The dds way's round trips a run: about the readings of one run of the others (the drive toward
# the threshold at 0.3 m/s, 20 ms a reading).
DDS_ROUND_TRIPS_A_RUN = 250
LAUNCH_ATTEMPTS = 3
# After the drive toward the threshold at full speed: the start (~0.1 s), the braking (~0.15 s),
# and the rest of the margin for a late start on a busy host.
REST_MARGIN_S = 2.0
# A run that the last baseline run's time has not brought to a stop goes on in steps of this, and
# once it has stopped, for the braking as well (about 0.15 s at 0.3 m/s).
LATE_STEP_S = 0.1
BRAKING_S = 0.2


class RobotDomain(Domain):
    """local_domain.Domain with the robot's node as well: `rsca domain up --nodes 1 --node DCD`
    (node1, a GPP, and the robot with its Robot, IRSensor and DriveSystem devices)."""

    def __init__(self, rsca, dcd, sdrroot, hosts=None, pinned=False):
        env = {"RSCA_SDRROOT": sdrroot}
        node_dcds = None
        if hosts:  # started by hand, each daemon on its host (CONTROLLER_HOST, ROBOT_HOST)
            env["RSCA_DDS_INTERFACE"] = "eth0"
            # The controller's node leaves StopCrash free on its host's CPUs, as the TCP way's
            # controller process is (dev/nodes/controller); --pinned: node1, which pins it to the
            # CPU admission chose.
            controller = ("node1", "dev/nodes/node1") if pinned else ("controller",
                                                                       "dev/nodes/controller")
            node_dcds = [(controller[0],
                          os.path.join(sdrroot, controller[1], "DeviceManager.dcd.xml")),
                         ("robot", dcd)]
        super().__init__(rsca, nodes=2 if hosts else 1, sdrroot=sdrroot, env=env, hosts=hosts,
                         node_dcds=node_dcds)
        self.dcd = dcd

    def __enter__(self):
        if self.hosts:
            return super().__enter__()
        try:
            subprocess.run([self.rsca, *self._global(), "domain", "up", "--nodes",
                            str(self.nodes), "--node", self.dcd], env=self.env, check=True,
                           stdout=subprocess.DEVNULL, timeout=120)
        except BaseException:
            self.daemons = self.daemon_pids()
            self.__exit__(None, None, None)
            raise
        self.daemons = self.daemon_pids()
        return self


def props(domain, target, *names, check=True):
    reply, _ = domain.cli("query", target, *names, check=check)
    return reply.get("properties", {})


def wait_for_rest(domain, args, run):
    """The Robot slower than 1 mm/s, past where it started, on 3 polls in a row (tools/demo)."""
    deadline = time.monotonic() + 60
    still = 0
    while time.monotonic() < deadline:
        try:
            robot = props(domain, "robot:Robot_1", "speed", "distance_to_wall")
        except (RuntimeError, ValueError):  # a CLI call that failed on a busy host: poll again
            robot = {}
        if (robot and abs(robot["speed"]) < 1e-3
                and robot["distance_to_wall"] < args.wall_distance - 0.1):
            still += 1
            if still >= 3:
                return
        else:
            still = 0
        time.sleep(0.2)  # pacing a poll of the robot's state
    raise RuntimeError(f"rsca run {run}: the robot did not come to rest within 60 s")


def drive_commands(domain):
    """The DriveSystem's count of commands so far (with a timestamp)."""
    return props(domain, "robot:DriveSystem_1", "latency_samples")["latency_samples"]


def run_delays(domain, before, rest, run):
    """The delays of the commands since command number `before` that arrived by `rest` (world
    time; all of them when the robot's rest was not found), and how many came after, from the
    DriveSystem's command log."""
    log = props(domain, "robot:DriveSystem_1", "latency_samples", "command_log_first",
                "command_log_delay_us", "command_log_sim_time")
    first = log["command_log_first"]
    if first > before:
        raise RuntimeError(f"rsca run {run}: the drive's command log no longer holds the run's "
                           f"first command ({before}; it starts at {first})")
    delays = log["command_log_delay_us"][before - first:]
    times = log["command_log_sim_time"][before - first:]
    kept = [d for d, t in zip(delays, times) if rest is None or t <= rest]
    return kept, len(delays) - len(kept)


def rest_sim_time(robot):
    """When the robot came to rest after the stop, in the world's time, as the baselines end a run
    (slower than 1 mm/s for 50 ms once a stop was commanded; from the Robot's trace), or None."""
    times, speeds, commands = (robot.get(k, []) for k in ("trace_time", "trace_speed",
                                                            "trace_command"))
    driven, stopped, still_since = False, False, None
    for t, v, c in zip(times, speeds, commands):
        driven = driven or c != 0.0  # before the first command, the robot waits at rest
        stopped = stopped or driven and c == 0.0
        if stopped and abs(v) < 1e-3:
            still_since = t if still_since is None else still_since
            if t - still_since >= 0.05:
                return t
        else:
            still_since = None
    return None


class Rsca:
    """The rsca way: a domain for the whole session, RangeStop launched once; each run stops the
    application, gives the Robot the run's seed, resets it (its world re-created, the robot back
    at its start) and starts the application again (StopCrash.start() clears its latch)."""

    def __init__(self, args, logs):
        self.args, self.logs = args, logs
        # The drive toward the threshold at full speed.
        self.drive_s = max(0.0, (args.wall_distance - args.threshold) / args.speed)
        dcd = os.path.join(args.sdrroot, "dev/nodes/robot/DeviceManager.dcd.xml")
        self.domain = RobotDomain(os.path.join(args.bin, "rsca"), dcd, args.sdrroot,
                                  hosts=args.net_hosts, pinned=args.pinned)
        self.drive = {}
        # How long the last baseline run took from its start to the robot's rest (world time),
        # the phase every way is recorded over; None until a baseline has run.
        self.phase_s = None

    def __enter__(self):
        domain = self.domain.__enter__()
        try:
            domain.cli("configure", "robot:IRSensor_1", f"period_ms={self.args.period_ms}")
            domain.cli("install", os.path.join(self.args.sdrroot,
                                               "dom/waveforms/RangeStop/RangeStop.sad.xml"))
            for attempt in range(1, LAUNCH_ATTEMPTS + 1):
                try:
                    domain.cli("launch", "RangeStop", "--no-start")
                    break
                except RuntimeError as e:  # rolled back by the domain: nothing is left of it
                    if attempt == LAUNCH_ATTEMPTS:
                        raise
                    print(f"launch of RangeStop failed (attempt {attempt}), trying again: {e}",
                          file=sys.stderr, flush=True)
                    time.sleep(5)  # a pause before trying again on a host that was too busy
            domain.cli("configure", "RangeStop/StopCrash_1", f"speed={self.args.speed}",
                       f"threshold={self.args.threshold}")
        except BaseException:
            self.domain.__exit__(*sys.exc_info())
            raise
        return self

    def __exit__(self, *exc):
        domain = self.domain
        try:
            if exc[0] is None:
                self.drive = props(domain, "robot:DriveSystem_1")
        finally:
            domain.cli("release", "RangeStop", check=False)
            for log in os.listdir(domain.run_dir):
                if log.endswith(".log"):
                    with open(os.path.join(domain.run_dir, log), "rb") as src, \
                            open(os.path.join(self.logs, f"rsca-{log}"), "wb") as dst:
                        dst.write(src.read())
            domain.__exit__(*exc)

    def run(self, run, seed):
        domain, args = self.domain, self.args
        domain.cli("configure", "robot:Robot_1", f"seed={seed}")
        domain.cli("configure", "robot:Robot_1", "reset=true")
        commands_before = drive_commands(domain)
        domain.cli("start", "RangeStop")
        # The run, undisturbed by the CLI: as long as the last baseline run took to rest (the
        # same phase; the world's clock started at the reset, before `start`, so the robot has
        # had that and the start's time more), or without one the drive and a margin.
        time.sleep(self.phase_s or self.drive_s + REST_MARGIN_S)
        # A late start on a busy host: a little longer, until StopCrash has stopped the robot
        # (bounded by the margin), and its braking.
        late = 0.0
        while (self.phase_s and late < REST_MARGIN_S and
               not props(domain, "RangeStop/StopCrash_1", "stopped")["stopped"]):
            late += LATE_STEP_S
            time.sleep(LATE_STEP_S)
        if late:
            time.sleep(BRAKING_S)
        domain.cli("stop", "RangeStop")
        stopped_at = props(domain, "robot:Robot_1", "sim_time")["sim_time"]
        stop = props(domain, "RangeStop/StopCrash_1", "stopped", "stop_range", "commands_sent")
        if not stop["stopped"]:
            raise RuntimeError(f"rsca run {run}: StopCrash had not stopped the robot by the "
                               f"end of the run")
        wait_for_rest(domain, args, run)
        robot = props(domain, "robot:Robot_1", "distance_to_wall", "sim_time", "seed",
                      "trace_time", "trace_speed", "trace_command")
        rest = rest_sim_time(robot)
        delays, after_rest = run_delays(domain, commands_before, rest, run)
        return None, {"way": "rsca", "run": run, "seed": seed,
                      "distance_to_wall": robot["distance_to_wall"],
                      "stop_range": stop["stop_range"], "sim_time": robot["sim_time"],
                      "commands_sent_total": stop["commands_sent"], "robot_seed": robot["seed"],
                      "commands": len(delays), "rest_sim_time": rest,
                      "stopped_sim_time": stopped_at, "commands_after_rest": after_rest,
                      "delays_us": delays}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", required=True, help="the build's bin folder")
    parser.add_argument("--sdrroot", default=os.path.join(ROOT, "profiles"))
    parser.add_argument("--out", required=True, help="the JSON results file")
    parser.add_argument("--quick", action="store_true", help="1 run a way instead of 20")
    parser.add_argument("--runs", type=int, help="runs a way (overrides --quick)")
    parser.add_argument("--ways", default=",".join(WAYS), help="a subset of " + ",".join(WAYS))
    # The experiment's settings: RangeStop's (the SAD, the robot's DCD). The rsca way sets
    # StopCrash and the IRSensor to them; the wall distance is the DCD's and is not changed.
    parser.add_argument("--speed", type=float, default=0.3)
    parser.add_argument("--threshold", type=float, default=0.6)
    parser.add_argument("--period-ms", type=int, default=20)
    parser.add_argument("--wall-distance", type=float, default=2.0, help=argparse.SUPPRESS)
    parser.add_argument("--hosts", action="store_true",
                        help="robot and controller on two network hosts (root; tools/hosts)")
    parser.add_argument("--pinned", action="store_true",
                        help="with --hosts: StopCrash pinned to the CPU admission chose (node1's "
                             "GPP), not free on its host's CPUs as the TCP way's controller is")
    args = parser.parse_args()
    args.net_hosts = None
    if args.hosts:
        if skipped_without_hosts(args.out):
            return 0
        with NetHosts(3) as net:
            args.net_hosts = net.hosts
            return experiment(args, parser)
    return experiment(args, parser)


# How the ways are measured, said in the output and the JSON.
METHOD = ("The ways take turns run by run (run i: every way once, with seed 1 + i, in an order "
          "rotated by one each run), with rsca among them all while its domain is up; the "
          "baselines' delays are "
          "each command's, taken at the drive, from the run's start until the robot rests "
          "(slower than 1 mm/s for 50 ms of world time after the stop), and their percentiles "
          "are computed here (sorted[n/2], sorted[n*99/100]) over every run; clock: the system "
          "clock of the reading's stamp and of the drive. rsca the same: each command's delay "
          "from the DriveSystem's command log, cut where the robot rested (the world's time at "
          "each command's arrival against the rest in the Robot's trace), percentiles computed "
          "here alike. dds: round trips, no robot.")


def run_interleaved(args, ways, runs, logs):
    """Every way's session open at once; run i runs each way once, in an order rotated by i.
    Returns each way's runs, the baseline programs' headers, wall clock by way, the sessions."""
    classes = {"inprocess": Inprocess, "tcp": Tcp, "dds": Dds, "rsca": Rsca}
    per_way, headers = {w: [] for w in ways}, {}
    clock = {w: 0.0 for w in ways}
    with contextlib.ExitStack() as stack:
        sessions = {}
        for w in ways:
            session = classes[w](args, logs)
            sessions[w] = (stack.enter_context(session) if hasattr(session, "__enter__")
                           else session)
        for i in range(runs):
            for w in ways[i % len(ways):] + ways[:i % len(ways)]:
                print(f"run {i}: {w}...", file=sys.stderr, flush=True)
                began = time.monotonic()
                header, result = sessions[w].run(i, 1 + i)
                clock[w] += time.monotonic() - began
                if header:
                    headers[w] = header
                if w in ("inprocess", "tcp") and "rsca" in sessions:
                    sessions["rsca"].phase_s = result["sim_time"]
                per_way[w].append(result)
                if "distance_to_wall" in result:
                    print(f"{w} run {i}: rests {result['distance_to_wall']:.4f} m from the wall",
                          file=sys.stderr, flush=True)
    return per_way, headers, clock, sessions


def way_result(way, header, runs, session):
    """One way's figures over all its runs."""
    if way in ("inprocess", "tcp"):
        return baseline_result(header, runs)
    if way == "dds":
        delays = [d for r in runs for d in r["delays_us"]]
        return {"delay_us": delay_summary(delays), "round_trips": len(delays)}
    drive = session.drive
    delays = [d for r in runs for d in r["delays_us"]]
    return {
        "runs": runs,
        "delay_us": delay_summary(delays),
        "commands_after_rest_cut": sum(r["commands_after_rest"] for r in runs),
        "runs_without_rest_found": sum(1 for r in runs if r["rest_sim_time"] is None),
        "drive": {k: drive[k] for k in ("commands_received", "safety_stops", "command_timeout_ms")
                  if k in drive},
        "stop_distance_m": distance_summary([r["distance_to_wall"] for r in runs]),
    }


def experiment(args, parser):
    args.sdrroot = os.path.abspath(args.sdrroot)
    runs = args.runs or (1 if args.quick else 20)
    ways = [w for w in args.ways.split(",") if w]
    for w in ways:
        if w not in WAYS:
            parser.error(f"unknown way {w} (known: {', '.join(WAYS)})")

    # The processes' logs go beside the results they explain, not into a folder of /tmp of their
    # own that every run would leave behind.
    logs = os.path.splitext(os.path.abspath(args.out))[0] + "-logs"
    os.makedirs(logs, exist_ok=True)
    started = time.time()
    results = {"settings": {"speed": args.speed, "threshold": args.threshold,
                            "period_ms": args.period_ms, "wall_distance": args.wall_distance,
                            "runs": runs, "seeds": [1, runs],
                            "where": "two network hosts" if args.net_hosts else "one host"},
               "host": {"cpus": os.cpu_count(), "machine": platform.machine(),
                        "loadavg_before": os.getloadavg()},
               "ways": {}}
    per_way, headers, clock, sessions = run_interleaved(args, ways, runs, logs)
    for w in ways:
        results["ways"][w] = way_result(w, headers.get(w), per_way[w], sessions[w])
        results["ways"][w]["wall_clock_s"] = clock[w]
    results["method"] = METHOD
    for w in ("inprocess", "tcp"):  # the prediction, from sim::stop_tolerance
        if w in results["ways"]:
            header = results["ways"][w]["header"]
            results["prediction"] = {"stop_tolerance_m": header["predicted_tolerance"],
                                     "braking_distance_m": header["braking_distance"],
                                     "latency_s": args.period_ms / 1000,
                                     "min_rest_distance_m":
                                         args.threshold - header["predicted_tolerance"]}
            break
    results["host"]["loadavg_after"] = os.getloadavg()
    results["wall_clock_s"] = time.time() - started
    results["logs"] = logs
    with open(args.out, "w") as f:
        json.dump(results, f, indent=2)

    print(f"How measured: {METHOD}")
    print()
    print("| way | runs | delay mean µs | p50 | p99 | stop distance mean m | sd | min | max |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for w in ways:
        r = results["ways"][w]
        d = r["delay_us"]
        if "stop_distance_m" not in r:  # dds: round trips, no robot
            print(f"| {w} (round trip) | {r['round_trips']} | {d['mean']:.1f} | {d['p50']:.1f} | "
                  f"{d['p99']:.1f} | | | | |")
            continue
        s = r["stop_distance_m"]
        print(f"| {w} | {len(r['runs'])} | {d['mean']:.1f} | {d['p50']:.1f} "
              f"| {d['p99']:.1f} | "
              f"{s['mean']:.4f} | {s['sd']:.4f} | {s['min']:.4f} | {s['max']:.4f} |")
    if "prediction" in results:
        p = results["prediction"]
        print()
        print(f"predicted tolerance (sim::stop_tolerance, latency = {args.period_ms} ms): "
              f"{1000 * p['stop_tolerance_m']:.1f} mm ({1000 * p['braking_distance_m']:.1f} mm "
              f"braking): the robot should rest at or beyond {p['min_rest_distance_m']:.4f} m "
              f"from the wall, give or take the sensor's noise")
    where = "across hosts " if args.net_hosts else ""
    for baseline in ("tcp", "dds"):  # rsca's p50 against each baseline of the run
        if "rsca" not in results["ways"] or baseline not in results["ways"]:
            continue
        ratio = (results["ways"]["rsca"]["delay_us"]["p50"] /
                 results["ways"][baseline]["delay_us"]["p50"])
        results[f"ratio_rsca_{baseline}_p50"] = ratio
        with open(args.out, "w") as f:
            json.dump(results, f, indent=2)
        print(f"{'' if baseline == 'dds' else chr(10)}ratio {where}rsca/{baseline} delay p50 = "
              f"{ratio:.2f}")
    for baseline in ("inprocess", "tcp"):  # means over each way's runs, computed here
        if "rsca" in results["ways"] and baseline in results["ways"]:
            ratio = (results["ways"]["rsca"]["delay_us"]["mean"] /
                     results["ways"][baseline]["delay_us"]["mean"])
            results[f"ratio_rsca_{baseline}_mean"] = ratio
            print(f"ratio {where}rsca/{baseline} delay mean = {ratio:.2f}")
    with open(args.out, "w") as f:
        json.dump(results, f, indent=2)
    if "rsca" in results["ways"]:
        r = results["ways"]["rsca"]
        print(f"rsca delay over {r['delay_us']['samples']} commands of its runs up to rest; "
              f"cut after rest: {r['commands_after_rest_cut']}; runs whose rest was not found "
              f"(kept whole): {r['runs_without_rest_found']}; drive safety stops: "
              f"{r['drive'].get('safety_stops')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
