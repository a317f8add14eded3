"""The fan-out benchmark's pieces (tests/bench/port_bench.py fanout): its schedule, the SADs of a
fan-out to N subscribers made from BenchFanOut.sad.xml, waiting for DDS discovery to settle
between launches, the rsca side (launched applications) and the raw side (rsca-bench-raw pub and
sub in one session per node), and the analysis of what each subscriber received when."""
import contextlib
import copy
import itertools
import json
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

from local_domain import Processes
from port_bench_helpers import (LAUNCH_ATTEMPTS, SDRROOT, connection_qos, latency_stats,
                                read_u64, wait_for_file)


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
    launched, launch_ms, placement, steps = [], [], {}, []
    try:
        for name, sad in sads:  # the subscribers first, the publisher with the last of them
            domain.cli("--sdrroot", sdr, "install", sad)
            for attempt in range(1, LAUNCH_ATTEMPTS + 1):
                wait_discovery_settled()
                try:
                    reply, ms = domain.cli("launch", name, "--name", name.lower(), "--strategy",
                                           "spread")
                    note_placement(placement, reply)
                    steps.append({s["step"]: s["ms"] for s in reply.get("launch", {}).get("steps", [])})
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
                 launch_cli_ms=launch_ms, launch_steps_ms=steps, placement=placement))


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
