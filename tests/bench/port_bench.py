#!/usr/bin/env python3
"""Data-path benchmarks of rsca against raw Cyclone DDS (run by tools/bench, never by ctest).

Both start a real local domain (rsca-domaind and two rsca-noded, local_domain.Domain) on the SDR
root tests/bench/profiles, with a DDS domain id of its own, and have the domain launch dedicated
benchmark components (tests/bench/components) from a SAD: each component is a process of its own,
its ports wired by the domain. In the same run, rsca-bench-raw (tests/bench/raw/raw_dds.cpp) does
the same exchanges on the bare Cyclone C API with the same IDL types, the same QoS (the one the
domain gave the connections, read back with `rsca ls connections`) and the same Cyclone
configuration (it joins the DDS domain of the daemons the way every rsca process does).
Payloads are 64 bytes serialized; times are CLOCK_MONOTONIC (tests/bench/bench_common.hpp).

latency: strict ping-pong between BenchPing_1 and BenchEcho_1 (uses port -> provides port,
  both ways), and between `rsca-bench-raw ping` and `rsca-bench-raw echo`, once woken by a waitset
  (the baseline of the ratio lines) and once by a listener as rsca's receive loop is; each raw
  pair in one session, as the two components are in their node's (docs/architecture.md says why
  that matters). Rounds of 2000 warm-up round trips (not measured) and 2000 measured ones
  (--quick: 1000), 6 rounds of each side (--quick: 3), each round running the sides in another
  order so that a change of the machine's load falls on all alike. Median, p99 (and more) of the round
  trip and the CPU time both processes spend per round trip; the output ends with the ratio lines.
fanout: BenchPublisher_1 publishes on the event channel BenchFanOut to N BenchSubscriber_i
  processes (N = 1, 10, 50, 100; --quick: 1 and 10), raw DDS the same with one raw publisher and N
  raw subscriber processes on one topic, in one session per node as the components were placed
  (a node's components share its session).
  Latency: events at a low rate (100 Hz), per event the time until the last subscriber has it
  (max over subscribers of receive time minus send time), p50 and p99. Sustained rate: steps of
  rising rates (250 to 128000 events/s, each after a pause); per step, the events every
  subscriber received, per second from the step's first send to its last receipt ("events/s to
  all", the best step counts), and whether any subscriber missed any ("loss-free up to": the
  highest rate with no loss in it or below; with the default keep-last 16 a subscriber held up
  for 16 periods loses the oldest events).

Every process started is stopped at the end, also on failure.
"""
import argparse
import array
import contextlib
import copy
import itertools
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

from local_domain import Domain, Processes, percentile

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
    output, starts the application, waits for the file and stops it."""

    def __init__(self, domain, work, count, warmup):
        self.domain, self.work, self.count, self.warmup = domain, work, count, warmup
        sad = os.path.join(SDRROOT, "dom/waveforms/BenchPortLatency/BenchPortLatency.sad.xml")
        domain.cli("install", sad)
        reply, _ = domain.cli("launch", "BenchPortLatency", "--name", "latency", "--no-start")
        self.pids = {c["id"]: c["pid"] for c in reply["components"]}
        self.qos = connection_qos(domain, "latency")
        domain.cli("configure", "latency/BenchPing_1", f"count={count}", f"warmup={warmup}")
        self.cpu_us = 0.0
        self.round_trips = 0
        self.resent = 0

    def run(self, index):
        output = os.path.join(self.work, f"rsca-rtt-{index}.bin")
        self.domain.cli("configure", "latency/BenchPing_1", f"output={output}")
        before = sum(cpu_us(p) for p in self.pids.values())
        self.domain.cli("start", "latency")
        wait_for_file(output, 8 * self.count, 60 + self.count * 0.01, "BenchPing_1")
        self.cpu_us += sum(cpu_us(p) for p in self.pids.values()) - before
        props, _ = self.domain.cli("query", "latency/BenchPing_1", "completed", "resent")
        self.domain.cli("stop", "latency")
        self.round_trips += props["properties"]["completed"]
        self.resent += props["properties"]["resent"]
        return read_u64(output)

    def close(self):
        self.domain.cli("release", "latency", check=False)


class LatencyRaw:
    """`rsca-bench-raw echo` for the whole run; each round runs `rsca-bench-raw ping` to its end.
    The two share a session of their own, as BenchPing_1 and BenchEcho_1 share the session of the
    node that started them (local_domain.Processes says why that matters)."""

    def __init__(self, domain, raw, work, qos, count, warmup, wake):
        self.domain, self.raw, self.work, self.count, self.warmup = domain, raw, work, count, warmup
        self.wake = wake
        self.procs = Processes(shared_session=True)
        self.ping_topic = f"rsca_bench_raw_ping_{wake}_{os.getpid()}"
        self.echo_topic = f"rsca_bench_raw_echo_{wake}_{os.getpid()}"
        self.qos = json.dumps(qos)
        try:
            self.echo = self.procs.start(
                [raw, "echo", "--in", self.ping_topic, "--out", self.echo_topic, "--qos",
                 self.qos, "--wake", wake], domain.env, os.path.join(work, f"raw-{wake}-echo.log"))
        except BaseException:
            self.procs.close()
            raise
        self.cpu_us = 0.0
        self.round_trips = 0
        self.resent = 0

    def run(self, index):
        output = os.path.join(self.work, f"raw-{self.wake}-rtt-{index}.bin")
        echo_before = cpu_us(self.echo.pid)
        ping = self.procs.start(
            [self.raw, "ping", "--out", self.ping_topic, "--in", self.echo_topic, "--qos",
             self.qos, "--wake", self.wake, "--count", str(self.count), "--warmup",
             str(self.warmup), "--output", output], self.domain.env,
            os.path.join(self.work, f"raw-{self.wake}-ping-{index}.log"))
        try:
            out, _ = ping.communicate(timeout=60 + self.count * 0.01)
        except subprocess.TimeoutExpired:
            raise RuntimeError("rsca-bench-raw ping did not finish") from None
        if ping.returncode != 0:
            raise RuntimeError(f"rsca-bench-raw ping failed ({ping.returncode}); see {self.work}")
        summary_ = json.loads(out)
        # The echo's CPU over the ping's whole life (its start-up included: the echo idles then).
        self.cpu_us += summary_["cpu_us"] + cpu_us(self.echo.pid) - echo_before
        self.round_trips += summary_["completed"]
        self.resent += summary_["resent"]
        return read_u64(output)

    def close(self):
        self.procs.close()


# The latency benchmark's sides: the rsca components, the raw programs with a waitset (the baseline
# of the ratio lines), and the raw programs woken the way rsca's receive loop wakes.
SIDES = ("rsca", "raw", "raw_listener")


def bench_latency(args):
    # Each round runs the sides in another order, so that a change of the machine's load during
    # the run falls on all alike and none always follows the same other: all six orders, or
    # (--quick) three in which each side comes first once.
    orders = list(itertools.permutations(SIDES))
    if args.quick:
        orders = orders[::2]
    rounds = len(orders)
    count, warmup = (1000, 2000) if args.quick else (2000, 2000)  # per round
    rsca = os.path.join(args.bin, "rsca")
    raw = os.path.join(args.bin, "rsca-bench-raw")
    work = tempfile.mkdtemp(prefix="rsca-portbench-")
    lease = lease_env(args.lease_ms)
    rtts = {name: array.array("Q") for name in SIDES}
    before = host_state()
    try:
        with Domain(rsca, nodes=2, sdrroot=SDRROOT, env=lease) as domain, \
                contextlib.ExitStack() as closing:
            sizes = raw_sizes(raw, domain.env)
            sides = {"rsca": LatencyRsca(domain, work, count, warmup)}
            closing.callback(sides["rsca"].close)
            for name, wake in (("raw", "waitset"), ("raw_listener", "listener")):
                sides[name] = LatencyRaw(domain, raw, work, sides["rsca"].qos, count, warmup,
                                         wake)
                closing.callback(sides[name].close)
            for index, order in enumerate(orders):
                for name in order:
                    rtts[name].extend(sides[name].run(index))
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    qos = sides["rsca"].qos
    results = {
        "payload_bytes": sizes["ping_sample_bytes"], "qos": qos, "rounds": rounds,
        "warmup_per_round": warmup, "round_trips": rounds * count,
        "dds_lease_ms": args.lease_ms or "default", "host_before": before}
    for name, side in sides.items():
        results[name] = dict(latency_stats(rtts[name]), resent=side.resent,
                             cpu_us_per_round_trip=side.cpu_us / max(1, side.round_trips))
    r, w, wl = results["rsca"], results["raw"], results["raw_listener"]
    results["ratio_p50"] = ratio(r["p50_us"], w["p50_us"])
    results["ratio_p99"] = ratio(r["p99_us"], w["p99_us"])
    results["ratio_p50_listener"] = ratio(r["p50_us"], wl["p50_us"])
    results["ratio_p99_listener"] = ratio(r["p99_us"], wl["p99_us"])
    with open(args.out, "w") as f:
        json.dump(results, f, indent=2)

    print(f"Round trip of a {results['payload_bytes']}-byte SampleSeq between two processes on one "
          f"host, strict ping-pong, {rounds} rounds of {warmup} warm-up and {count} measured round "
          f"trips each, the sides in another order each round; each raw pair in one session, "
          f"as the components are in their node's; QoS {qos['reliability']}, "
          f"{qos['durability']}, {qos['history']} {qos.get('depth', '')}.")
    print()
    print("| round trip | rsca (uses -> provides port) | raw Cyclone DDS (waitset) | rsca/raw "
          "| raw, rsca's wake (listener) | rsca/that |")
    print("| --- | --- | --- | --- | --- | --- |")
    rows = [("min_us", "min"), ("p50_us", "p50"), ("p90_us", "p90"), ("p99_us", "p99"),
            ("p999_us", "p99.9"), ("max_us", "max"), ("mean_us", "mean"),
            ("cpu_us_per_round_trip", "CPU per round trip (both processes)")]
    for key, label in rows:
        print(f"| {label} | {r[key]:.1f} us | {w[key]:.1f} us | {ratio(r[key], w[key]):.2f} "
              f"| {wl[key]:.1f} us | {ratio(r[key], wl[key]):.2f} |")
    print()
    print(f"ratio rsca/raw-listener p50 = {results['ratio_p50_listener']:.2f}")
    print(f"ratio rsca/raw-listener p99 = {results['ratio_p99_listener']:.2f}")
    print(f"ratio rsca/raw p50 = {results['ratio_p50']:.2f}")
    print(f"ratio rsca/raw p99 = {results['ratio_p99']:.2f}")
    return 0


# ---- fan-out ----------------------------------------------------------------------------------

class Schedule:
    def __init__(self, quick):
        self.warmup = 100
        self.latency_count = 200 if quick else 2000
        self.latency_rate_hz = 100.0
        self.step_rates_hz = [250.0 * 2 ** k for k in range(10)]  # 250 .. 128000
        self.step_ms = 200 if quick else 1000
        self.gap_ms = 100 if quick else 300

    def step_counts(self):
        # As the publishers compute them (C++: static_cast<uint64_t>(r * ms / 1000.0 + 0.5)).
        return [int(r * self.step_ms / 1000.0 + 0.5) for r in self.step_rates_hz]

    def total(self):
        return self.warmup + self.latency_count + sum(self.step_counts())

    def seconds(self):
        return ((self.warmup + self.latency_count) / self.latency_rate_hz +
                len(self.step_rates_hz) * (self.step_ms + self.gap_ms) / 1000.0)

    def raw_args(self):
        return ["--warmup", str(self.warmup), "--latency-count", str(self.latency_count),
                "--latency-rate-hz", repr(self.latency_rate_hz),
                "--step-rates-hz", ",".join(repr(r) for r in self.step_rates_hz),
                "--step-ms", str(self.step_ms), "--gap-ms", str(self.gap_ms)]


SAD_HEADER = ('<?xml version="1.0" encoding="UTF-8"?>\n<!DOCTYPE softwareassembly PUBLIC '
              '"-//JTRS//DTD SCA V2.2.2 SAD//EN" "softwareassembly.dtd">\n')


def fanout_sads(n, batch, schedule, work):
    """The applications of a fan-out to N subscribers, made from BenchFanOut.sad.xml: its
    subscriber (placement and connection) copied N times, in applications of at most `batch`
    subscribers (a launch starts all its processes at once, and every new DDS participant sets
    off discovery traffic with all the others: see wait_discovery_settled), the publisher in the
    last one; the run's
    properties (outputs, schedule) in componentproperties. They go to an SDR root of their own
    in `work`, whose components are those of tests/bench/profiles. Returns [(name, SAD path)]
    and the SDR root."""
    template = ET.parse(os.path.join(SDRROOT, "dom/waveforms/BenchFanOut/BenchFanOut.sad.xml"))
    sdr = os.path.join(work, "sdr")
    os.makedirs(os.path.join(sdr, "dom/waveforms"), exist_ok=True)
    if not os.path.exists(os.path.join(sdr, "dom/components")):
        os.symlink(os.path.join(SDRROOT, "dom/components"), os.path.join(sdr, "dom/components"))

    def placement_of(root, refid):
        return next(p for p in root.find("partitioning")
                    if p.find("componentfileref").get("refid") == refid)

    def set_properties(instantiation, values):
        props = ET.Element("componentproperties")
        for key, value in values:
            if isinstance(value, list):
                seq = ET.SubElement(props, "simplesequenceref", refid=key)
                vals = ET.SubElement(seq, "values")
                for v in value:
                    ET.SubElement(vals, "value").text = repr(v)
            else:
                ET.SubElement(props, "simpleref", refid=key, value=str(value))
        instantiation.insert(list(instantiation).index(instantiation.find("usagename")) + 1,
                             props)

    capacity = schedule.total()
    apps = []
    batches = [list(range(i, min(i + batch, n + 1))) for i in range(1, n + 1, batch)]
    for k, members in enumerate(batches, 1):
        root = copy.deepcopy(template.getroot())
        last = k == len(batches)
        name = f"BenchFanOut_{n}" + ("" if len(batches) == 1 else f"_{k}")
        root.set("name", name)
        root.set("id", f"DCE:0d7c7d0e-5b7a-4c55-{n:04x}-{k:012x}")
        partitioning, connections = root.find("partitioning"), root.find("connections")
        sub_placement = placement_of(root, "BenchSubscriber_spd")
        sub_connection = next(c for c in connections if c.get("id") == "subscribe_1")
        partitioning.remove(sub_placement)
        connections.remove(sub_connection)
        pub_placement = placement_of(root, "BenchPublisher_spd")
        if last:
            set_properties(pub_placement.find("componentinstantiation"), [
                ("subscribers", n), ("warmup", schedule.warmup),
                ("latency_count", schedule.latency_count),
                ("latency_rate_hz", repr(schedule.latency_rate_hz)),
                ("step_rates_hz", schedule.step_rates_hz), ("step_ms", schedule.step_ms),
                ("gap_ms", schedule.gap_ms), ("output", f"{work}/rsca-pub.bin")])
        else:
            partitioning.remove(pub_placement)
            connections.remove(next(c for c in connections if c.get("id") == "publish"))
            root.find("assemblycontroller/componentinstantiationref").set(
                "refid", f"BenchSubscriber_{members[0]}")
        for position, i in enumerate(members):
            placement = copy.deepcopy(sub_placement)
            instantiation = placement.find("componentinstantiation")
            instantiation.set("id", f"BenchSubscriber_{i}")
            instantiation.find("usagename").text = f"BenchSubscriber_{i}"
            set_properties(instantiation, [("capacity", capacity),
                                           ("output", f"{work}/rsca-sub-{i}.bin")])
            partitioning.insert(position, placement)
            connection = copy.deepcopy(sub_connection)
            connection.set("id", f"subscribe_{i}")
            connection.find("providesport/componentinstantiationref").set(
                "refid", f"BenchSubscriber_{i}")
            connections.append(connection)
        folder = os.path.join(sdr, "dom/waveforms", name)
        os.makedirs(folder, exist_ok=True)
        path = os.path.join(folder, f"{name}.sad.xml")
        ET.indent(root)
        with open(path, "w") as f:
            f.write(SAD_HEADER + ET.tostring(root, encoding="unicode") + "\n")
        apps.append((name, path))
    return apps, sdr


def udp_counters():
    """The host's UDP InDatagrams and RcvbufErrors (/proc/net/snmp)."""
    with open("/proc/net/snmp") as f:
        lines = [line.split() for line in f if line.startswith("Udp:")]
    values = dict(zip(lines[0][1:], (int(v) for v in lines[1][1:])))
    return values["InDatagrams"], values["RcvbufErrors"]


def wait_discovery_settled(limit=30.0):
    """Waits (at most `limit` s) until the DDS discovery that the last launch set off is over:
    for 2 s no UDP datagram dropped for a full receive buffer and under 3000 datagrams/s. A new
    participant leaves every other one heartbeating its discovery data to all of its readers
    (docs/architecture.md on discovery cost); launching more while that lasts feeds the storm,
    loses datagrams, and components then register only after a resend."""
    deadline = time.monotonic() + limit
    calm, previous = 0, udp_counters()
    while calm < 4 and time.monotonic() < deadline:
        time.sleep(0.5)  # the sampling interval
        current = udp_counters()
        quiet = current[1] == previous[1] and (current[0] - previous[0]) * 2 < 3000
        calm = calm + 1 if quiet else 0
        previous = current


def fanout_rsca(domain, n, batch, schedule, work):
    sads, sdr = fanout_sads(n, batch, schedule, work)
    pub_out = os.path.join(work, "rsca-pub.bin")
    subs_out = [os.path.join(work, f"rsca-sub-{i}.bin") for i in range(1, n + 1)]
    for path in [pub_out] + subs_out:
        if os.path.exists(path):
            os.remove(path)
    launched, launch_ms, placement = [], [], {}
    try:
        for name, sad in sads:  # the subscribers first, the publisher with the last of them
            domain.cli("--sdrroot", sdr, "install", sad)
            for attempt in range(1, LAUNCH_ATTEMPTS + 1):
                wait_discovery_settled()
                try:
                    reply, ms = domain.cli("launch", name, "--name", name.lower(), "--strategy",
                                           "spread")
                    note_placement(placement, reply)
                    break
                except RuntimeError as e:  # rolled back by the domain: nothing is left of it
                    if attempt == LAUNCH_ATTEMPTS:
                        raise
                    print(f"launch of {name} failed (attempt {attempt}), trying again: {e}",
                          file=sys.stderr, flush=True)
            launched.append(name.lower())
            launch_ms.append(ms)
        app = launched[-1]
        wait_for_file(pub_out, 8 * schedule.total(), 120 + 3 * schedule.seconds(),
                      "BenchPublisher_1")
        time.sleep(1.0)  # what is still in flight arrives
        qos = connection_qos(domain, app)
        for a in launched:
            domain.cli("stop", a)
        for path in subs_out:
            wait_for_file(path, 8 * schedule.total(), 30, "a BenchSubscriber")
        props, _ = domain.cli("query", f"{app}/BenchPublisher_1")
    finally:
        for a in launched:
            domain.cli("release", a, check=False)
        for name, _ in sads:
            domain.cli("uninstall", name, check=False)
    return (read_u64(pub_out), [read_u64(p) for p in subs_out], qos,
            dict(props.get("properties", props), applications=len(launched),
                 launch_cli_ms=launch_ms, placement=placement))


def note_placement(placement, reply):
    """Counts, per node, the subscribers and the publisher a launch reply placed there."""
    for c in reply.get("components", []):
        node = placement.setdefault(c.get("node", "?"), {"publisher": 0, "subscribers": 0})
        node["publisher" if c.get("id", "").startswith("BenchPublisher") else "subscribers"] += 1


def raw_sessions(n, placement):
    """How the raw fan-out's processes are grouped in sessions: as the components were on the
    nodes (one session per node: a node's components share its session), or when that is not
    known (the rsca side failed), two halves with the publisher in the first. Returns a list of
    (publisher here, subscribers here)."""
    if (placement and sum(p["subscribers"] for p in placement.values()) == n
            and sum(p["publisher"] for p in placement.values()) == 1):
        return [(p["publisher"] > 0, p["subscribers"]) for p in placement.values()]
    return [(True, (n + 1) // 2), (False, n // 2)]


def fanout_raw(domain, raw, n, schedule, qos, work, placement):
    topic = f"rsca_bench_raw_fanout_{n}_{os.getpid()}"
    qos_json = json.dumps(qos)
    pub_out = os.path.join(work, "raw-pub.bin")
    subs_out = [os.path.join(work, f"raw-sub-{i}.bin") for i in range(1, n + 1)]
    with contextlib.ExitStack() as closing:
        subs, pub, outs = [], None, iter(enumerate(subs_out, 1))
        for with_publisher, count in raw_sessions(n, placement):
            session = closing.enter_context(Processes(shared_session=True))
            for i, out in itertools.islice(outs, count):
                subs.append(session.start(
                    [raw, "sub", "--topic", topic, "--qos", qos_json, "--capacity",
                     str(schedule.total()), "--output", out], domain.env,
                    os.path.join(work, f"raw-sub-{i}.log")))
            if with_publisher:
                pub = session.start(
                    [raw, "pub", "--topic", topic, "--qos", qos_json, "--subscribers", str(n),
                     "--output", pub_out, *schedule.raw_args()], domain.env,
                    os.path.join(work, "raw-pub.log"))
        try:
            out, _ = pub.communicate(timeout=120 + 3 * schedule.seconds())
        except subprocess.TimeoutExpired:
            raise RuntimeError("rsca-bench-raw pub did not finish") from None
        if pub.returncode != 0:
            raise RuntimeError(f"rsca-bench-raw pub failed ({pub.returncode}); see {work}")
        time.sleep(1.0)  # what is still in flight arrives
        sub_outs = Processes.stop(subs, timeout=30)
    bad = [i for i, s in enumerate(subs, 1) if s.returncode != 0]
    if bad:
        raise RuntimeError(f"rsca-bench-raw sub {bad} failed; see {work}")
    pub_props = json.loads(out)
    pub_props["unexpected"] = sum(json.loads(o)["unexpected"] for o in sub_outs if o.strip())
    return read_u64(pub_out), [read_u64(p) for p in subs_out], pub_props


def analyse_fanout(send, subs, schedule):
    first = schedule.warmup
    lat, lost = [], 0
    for seq in range(first, first + schedule.latency_count):
        if send[seq] == 0:
            lost += 1
            continue
        last = 0
        for s in subs:
            r = s[seq]
            if r == 0:
                last = 0
                break
            last = max(last, r)
        if last == 0:
            lost += 1
        else:
            lat.append(last - send[seq])
    result = {"latency": latency_stats(lat) if lat else None, "latency_events_lost": lost}
    steps = []
    at = first + schedule.latency_count
    for rate, count in zip(schedule.step_rates_hz, schedule.step_counts()):
        a, b = at, at + count
        at = b
        sent = send[a:b]
        step = {"rate_hz": rate, "events": count, "unsent": sent.count(0)}
        steps.append(step)
        if step["unsent"] == count:
            step.update(missing=count * len(subs), to_all=0, loss_free=False)
            continue
        sent_times = [t for t in sent if t]
        first_send = sent_times[0]
        step["send_rate_hz"] = ((len(sent_times) - 1) * 1e9 / (sent_times[-1] - first_send)
                                if len(sent_times) > 1 else None)
        # Which events every subscriber received: a subscriber that missed none (counted at C
        # speed) changes nothing.
        to_all = [t != 0 for t in sent]
        missing, last = 0, first_send
        for sub in subs:
            got = sub[a:b]
            lost_here = got.count(0)
            missing += lost_here
            last = max(last, max(got))
            if lost_here:
                to_all = [x and y != 0 for x, y in zip(to_all, got)]
        step["missing"] = missing  # receipts missing, over all subscribers
        step["loss_free"] = step["unsent"] == 0 and missing == 0
        step["to_all"] = sum(to_all)
        # Events every subscriber received, per second from the step's first send to its last
        # receipt by any subscriber.
        step["to_all_per_s"] = step["to_all"] * 1e9 / (last - first_send) if last > first_send \
            else 0.0
    result["steps"] = steps
    result["events_per_s_to_all"] = max((s.get("to_all_per_s", 0.0) for s in steps), default=0.0)
    # The highest rate such that it and every rate below it lost nothing (0: the first did).
    loss_free = 0.0
    for s in steps:
        if not s["loss_free"]:
            break
        loss_free = s["rate_hz"]
    result["loss_free_up_to_hz"] = loss_free
    return result


def bench_fanout(args):
    schedule = Schedule(args.quick)
    counts = ([int(c) for c in args.subscribers.split(",")] if args.subscribers
              else [1, 10] if args.quick else [1, 10, 50, 100])
    rsca = os.path.join(args.bin, "rsca")
    raw = os.path.join(args.bin, "rsca-bench-raw")
    work = tempfile.mkdtemp(prefix="rsca-portbench-")
    results = {"schedule": vars(schedule), "subscribers": {}}
    try:
        lease = lease_env(args.lease_ms)
        results["dds_lease_ms"] = args.lease_ms or "default"
        # The domain waits up to a minute (not 10 s) for a launched component to register, and 30 s
        # (not 5 s) for its answers, and the CLI as long for the domain's: with 50 and more
        # component processes, discovery of a new one takes longer (FANOUT_LEASE_MS,
        # docs/architecture.md on discovery cost).
        with Domain(rsca, nodes=2, sdrroot=SDRROOT, env=lease,
                    domaind_args=["--registration-timeout-ms", "60000",
                                  "--call-timeout-ms", "30000"],
                    cli_args=["--timeout-ms", "30000"]) as domain:
            results["payload_bytes"] = raw_sizes(raw, domain.env)["event_bytes"]
            qos = {}  # until the domain gave one: the same defaults (dds/port_qos.hpp)
            for n in counts:
                print(f"fan-out to {n} subscriber(s)...", file=sys.stderr, flush=True)
                entry = {"host_before": host_state()}
                # Each side on its own: a side that fails (e.g. a launch the domain rolled back
                # three times) is reported as such, the other still measured.
                placement = None
                try:
                    send, subs, qos, props = fanout_rsca(domain, n, args.batch, schedule, work)
                    entry["rsca"] = dict(analyse_fanout(send, subs, schedule), publisher=props)
                    placement = props["placement"]
                    del send, subs
                except RuntimeError as e:
                    entry["rsca"] = {"error": str(e)}
                    print(f"rsca, {n} subscribers: {e}", file=sys.stderr, flush=True)
                try:
                    send, subs, raw_props = fanout_raw(domain, raw, n, schedule, qos, work,
                                                       placement)
                    entry["raw"] = dict(analyse_fanout(send, subs, schedule), publisher=raw_props)
                    del send, subs
                except RuntimeError as e:
                    entry["raw"] = {"error": str(e)}
                    print(f"raw, {n} subscribers: {e}", file=sys.stderr, flush=True)
                for f in os.listdir(work):  # the next count writes its own
                    if f.endswith(".bin"):
                        os.remove(os.path.join(work, f))
                results["qos"] = qos
                r, w = entry["rsca"], entry["raw"]
                if r.get("latency") and w.get("latency"):
                    entry["ratio_p50"] = ratio(r["latency"]["p50_us"], w["latency"]["p50_us"])
                    entry["ratio_p99"] = ratio(r["latency"]["p99_us"], w["latency"]["p99_us"])
                if "error" not in r and "error" not in w:
                    entry["ratio_events_per_s"] = ratio(r["events_per_s_to_all"],
                                                        w["events_per_s_to_all"])
                results["subscribers"][str(n)] = entry
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    entries = results["subscribers"]
    with_ratios = [e for e in entries.values() if "ratio_p50" in e]
    results["ratio_p50_worst"] = max((e["ratio_p50"] for e in with_ratios), default=math.inf)
    results["ratio_p99_worst"] = max((e["ratio_p99"] for e in with_ratios), default=math.inf)
    with open(args.out, "w") as f:
        json.dump(results, f, indent=2)

    qos = results.get("qos", {})
    print(f"Fan-out of {results['payload_bytes']}-byte PropertyEvents through an event channel to N "
          f"subscriber processes (rsca) / N raw DDS readers on one topic (raw), one host; QoS "
          f"{qos.get('reliability')}, {qos.get('durability')}, {qos.get('history')} "
          f"{qos.get('depth', '')}. Latency: {schedule.latency_count} events at "
          f"{schedule.latency_rate_hz:.0f} Hz, per event the time until every subscriber has "
          f"it. DDS participant lease {results['dds_lease_ms']} ms for every process, rsca and "
          f"raw alike (see FANOUT_LEASE_MS). Subscribers launched {args.batch} per application. "
          f"Sustained rate: steps of {schedule.step_ms} ms at "
          f"{schedule.step_rates_hz[0]:.0f}..{schedule.step_rates_hz[-1]:.0f} events/s; "
          "events/s to all = the best step's events received by every subscriber per second "
          "(first send to last receipt); loss-free up to = the highest step rate such that no "
          "subscriber missed an event in it or any step below.")
    print()
    print("| subscribers | p50 rsca | p50 raw | rsca/raw | p99 rsca | p99 raw | rsca/raw "
          "| events/s to all, rsca | raw | rsca/raw | loss-free up to, rsca | raw |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")

    def us(side, key):
        if "error" in side:
            return "failed"
        return f"{side['latency'][key]:.0f} us" if side["latency"] else "lost"

    def rate(side, key, unit=""):
        return "failed" if "error" in side else f"{side[key]:.0f}{unit}"

    def r2(e, key):
        return f"{e[key]:.2f}" if key in e else "-"

    for n, e in entries.items():
        r, w = e["rsca"], e["raw"]
        print(f"| {n} | {us(r, 'p50_us')} | {us(w, 'p50_us')} | {r2(e, 'ratio_p50')} "
              f"| {us(r, 'p99_us')} | {us(w, 'p99_us')} | {r2(e, 'ratio_p99')} "
              f"| {rate(r, 'events_per_s_to_all')} | {rate(w, 'events_per_s_to_all')} "
              f"| {r2(e, 'ratio_events_per_s')} | {rate(r, 'loss_free_up_to_hz', '/s')} "
              f"| {rate(w, 'loss_free_up_to_hz', '/s')} |")
    print()
    for n, e in entries.items():
        for side in ("rsca", "raw"):
            if "error" in e[side]:
                print(f"{n} subscribers, {side} failed: {e[side]['error']}")
            elif e[side]["latency_events_lost"]:
                print(f"{n} subscribers, {side}: {e[side]['latency_events_lost']} latency events "
                      "not received by every subscriber")
        if busy_note(e):
            print(f"{n} subscribers: {busy_note(e)}")
    print()
    for n, e in entries.items():
        if "ratio_events_per_s" in e:
            print(f"subscribers={n}: ratio rsca/raw events/s = {e['ratio_events_per_s']:.2f}")
    for n, e in entries.items():
        if "ratio_p50" in e:
            print(f"subscribers={n}: ratio rsca/raw p50 = {e['ratio_p50']:.2f}")
            print(f"subscribers={n}: ratio rsca/raw p99 = {e['ratio_p99']:.2f}")
    if with_ratios:
        print(f"ratio rsca/raw p50 = {results['ratio_p50_worst']:.2f}")
        print(f"ratio rsca/raw p99 = {results['ratio_p99_worst']:.2f}")
    else:
        print("ratio rsca/raw p50 = n/a (no subscriber count measured on both sides)")
        print("ratio rsca/raw p99 = n/a (no subscriber count measured on both sides)")
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("benchmark", choices=["latency", "fanout"])
    parser.add_argument("--bin", required=True, help="the build's bin folder")
    parser.add_argument("--out", required=True, help="JSON results go here")
    parser.add_argument("--quick", action="store_true", help="fewer samples; fan-out to 1 and 10 only")
    parser.add_argument("--subscribers", help="fanout: subscriber counts, e.g. 1,10")
    parser.add_argument("--batch", type=int, default=5,
                        help="fanout: subscribers per application launched (default 5)")
    parser.add_argument("--lease-ms", type=int, default=None,
                        help="DDS lease of every process of the run, rsca and raw alike "
                        "(fanout default 10000; latency default: the project's, 1000 for the "
                        "daemons, 10000 for components and raw programs)")
    parser.add_argument("--keep", action="store_true", help="keep the raw measurement files")
    args = parser.parse_args()
    if args.lease_ms is None and args.benchmark == "fanout":
        args.lease_ms = FANOUT_LEASE_MS
    return bench_latency(args) if args.benchmark == "latency" else bench_fanout(args)


if __name__ == "__main__":
    sys.exit(main())
