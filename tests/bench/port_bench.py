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
  both ways) placed on two nodes (through each node's ring and relay: the default; and with the
  connections asking for direct DDS) and on one node (through its shared memory), between
  `rsca-bench-iceoryx ping` and `echo` (raw iceoryx 2.0.3, woken by its WaitSet; the same-host
  baseline), and between `rsca-bench-raw ping` and `rsca-bench-raw echo`, once woken by a waitset
  (the baseline of the ratio lines) and once by a listener as rsca's receive loop is; each raw
  pair in one session, as the two components are in their node's (docs/architecture.md says why
  that matters). Every side runs in two modes, like for like: both spinning (every receiving
  thread looks for more data 50 us after data before it sleeps: rsca's default
  RSCA_RECEIVE_SPIN_US, the raw programs' --spin-us 50) and both sleeping (RSCA_RECEIVE_SPIN_US=0,
  --spin-us 0), rsca's two modes on two domains side by side. Rounds of 2000 warm-up round trips
  (not measured) and 2000 measured ones (--quick: 1000), 12 rounds (--quick: 3), each running
  every side of both modes in another order, so that a change of the machine's load falls on all
  alike. Median, p99 (and more) of the round trip and the CPU time both processes spend per round
  trip, through the nodes the node daemons' CPU as well; the output ends with the ratio lines,
  each for both modes.
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
import json
import math
import os
import shutil
import sys

from local_domain import Domain, NetHosts, skipped_without_hosts, work_dir
from port_bench_fanout import Schedule, analyse_fanout, fanout_raw, fanout_rsca
from port_bench_helpers import (FANOUT_LEASE_MS, MODES, SDRROOT, SIDES, SPIN_US, LatencyIceoryx,
                                LatencyRaw, LatencyRsca, busy_note, host_state, latency_stats, lease_env, ratio,
                                raw_sizes)


def run_rounds(sides, orders, rtts):
    """Each round runs every side once, in that round's order; the round trips go to rtts."""
    for index, order in enumerate(orders):
        for name in order:
            rtts[name].extend(sides[name].run(index))


def bench_latency_hosts(args):
    """Round trips between two network hosts (tools/hosts): BenchPing_1 and BenchEcho_1 on node1
    and node2, each node on a host of its own, through the nodes and with direct DDS; the raw
    DDS ping on node1's host and its echo on node2's, the baseline (issue 21)."""
    if skipped_without_hosts(args.out):
        return 0
    sides_hosts = ("rsca", "rsca_direct", "raw")
    orders = [sides_hosts[i:] + sides_hosts[:i] for i in range(len(sides_hosts))]
    count, warmup = (1000, 2000) if args.quick else (2000, 2000)
    rsca = os.path.join(args.bin, "rsca")
    raw = os.path.join(args.bin, "rsca-bench-raw")
    work = work_dir("rsca-portbench-", components_write=True)
    env = dict(lease_env(args.lease_ms), RSCA_DDS_INTERFACE="eth0")
    rtts = {name: array.array("Q") for name in sides_hosts}
    try:
        with NetHosts(3) as net, \
                Domain(rsca, nodes=2, sdrroot=SDRROOT, env=env, hosts=net.hosts) as domain, \
                contextlib.ExitStack() as closing:
            sides = {"rsca": LatencyRsca(domain, work, count, warmup)}
            closing.callback(sides["rsca"].close)
            sides["rsca_direct"] = LatencyRsca(domain, work, count, warmup, "direct")
            closing.callback(sides["rsca_direct"].close)
            sides["raw"] = LatencyRaw(domain, raw, work, sides["rsca"].qos, count, warmup,
                                      "waitset", hosts=(net.hosts[1], net.hosts[2]))
            closing.callback(sides["raw"].close)
            run_rounds(sides, orders, rtts)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    results = {name: latency_stats(rtts[name]) for name in sides_hosts}
    r, d, w = results["rsca"], results["rsca_direct"], results["raw"]
    results["ratio_cross_host_p50"] = ratio(r["p50_us"], w["p50_us"])
    results["ratio_cross_host_direct_p50"] = ratio(d["p50_us"], w["p50_us"])
    with open(args.out, "w") as f:
        json.dump(results, f, indent=2)
    print(f"Round trip between two network hosts (namespaces on a bridge, tools/hosts), strict "
          f"ping-pong, {len(orders)} rounds of {warmup} warm-up and {count} measured each.")
    print()
    print("| round trip | rsca, through the nodes | rsca, direct DDS | raw Cyclone DDS (waitset) "
          "| nodes/raw | direct/raw |")
    print("| --- | --- | --- | --- | --- | --- |")
    for key, label in (("min_us", "min"), ("p50_us", "p50"), ("p90_us", "p90"),
                       ("p99_us", "p99"), ("max_us", "max")):
        print(f"| {label} | {r[key]:.1f} us | {d[key]:.1f} us | {w[key]:.1f} us "
              f"| {ratio(r[key], w[key]):.2f} | {ratio(d[key], w[key]):.2f} |")
    print()
    print(f"ratio cross-host rsca/raw p50 = {results['ratio_cross_host_p50']:.2f}")
    print(f"ratio cross-host direct rsca/raw p50 = {results['ratio_cross_host_direct_p50']:.2f}")
    return 0


def latency_orders(quick):
    """The rounds' orders of every side in both modes: the modes interleaved side by side, each
    round a rotation of that list (so that a change of the machine's load during the run falls on
    all alike and none always follows the same other); --quick: three rotations spread over it."""
    names = [f"{side}@{mode}" for side in SIDES for mode in MODES]
    shifts = range(len(names))
    if quick:
        shifts = [i * len(names) // 3 for i in range(3)]
    return [names[i:] + names[:i] for i in shifts]


def mode_domain_env(mode, lease):
    """The environment of the domain of one mode: rsca's receive threads spinning or not, and a
    DDS domain id and discovery tag of the mode's own (the two domains run side by side)."""
    env = dict(lease, RSCA_RECEIVE_SPIN_US=str(MODES[mode]))
    if mode == "sleep":
        env.update(RSCA_DDS_DOMAIN=str(1 + (os.getpid() + 50) % 101),
                   RSCA_DDS_TAG=f"bench-{os.getpid()}-sleep")
    return env


def latency_sides(domain, mode, args, work, count, warmup, closing, sizes):
    """The six sides of one mode, each closed by `closing`; their files in a folder of the
    mode's own (the two modes' rsca sides share names)."""
    spin = MODES[mode]
    work = os.path.join(work, mode)
    os.makedirs(work, exist_ok=True)
    os.chmod(work, 0o1777)  # the components' user writes its results here, as in work_dir()

    def keep(side):
        closing.callback(side.close)
        return side
    raw = os.path.join(args.bin, "rsca-bench-raw")
    sides = {"rsca": keep(LatencyRsca(domain, work, count, warmup))}
    sides["rsca_same_host"] = keep(LatencyRsca(domain, work, count, warmup, "same_host"))
    sides["rsca_direct"] = keep(LatencyRsca(domain, work, count, warmup, "direct"))
    # One RouDi a machine: the first mode's iceoryx side starts it, the other shares it.
    sides["iceoryx"] = keep(LatencyIceoryx(os.path.join(args.bin, "rsca-bench-iceoryx"), work,
                                           count, warmup, sizes["ping_sample_bytes"], spin,
                                           roudi=mode == next(iter(MODES))))
    for name, wake in (("raw", "waitset"), ("raw_listener", "listener")):
        sides[name] = keep(LatencyRaw(domain, raw, work, sides["rsca"].qos, count, warmup, wake,
                                      spin_us=spin))
    return sides


def mode_results(sides, rtts):
    """One mode's figures: each side's round trips and CPU, and the ratios."""
    results = {}
    for name, side in sides.items():
        results[name] = dict(latency_stats(rtts[name]), resent=side.resent,
                             cpu_us_per_round_trip=side.cpu_us / max(1, side.round_trips))
        if hasattr(side, "cpu_nodes_us"):
            results[name]["cpu_nodes_us_per_round_trip"] = (
                side.cpu_nodes_us / max(1, side.round_trips))
    r, w, wl = results["rsca"], results["raw"], results["raw_listener"]
    sh, ix, d = results["rsca_same_host"], results["iceoryx"], results["rsca_direct"]
    for key, a, b, p in (("ratio_p50", r, w, "p50_us"), ("ratio_p99", r, w, "p99_us"),
                         ("ratio_p50_listener", r, wl, "p50_us"),
                         ("ratio_p99_listener", r, wl, "p99_us"),
                         ("ratio_same_host_p50", sh, w, "p50_us"),
                         ("ratio_same_host_iceoryx_p50", sh, ix, "p50_us"),
                         ("ratio_direct_p50", d, w, "p50_us"), ("ratio_direct_p99", d, w, "p99_us")):
        results[key] = ratio(a[p], b[p])
    results["ratio_cpu"] = ratio(r["cpu_us_per_round_trip"], w["cpu_us_per_round_trip"])
    results["ratio_same_host_cpu"] = ratio(sh["cpu_us_per_round_trip"], w["cpu_us_per_round_trip"])
    return results


RATIO_LINES = (("ratio_p50_listener", "ratio rsca/raw-listener p50"),
               ("ratio_p99_listener", "ratio rsca/raw-listener p99"),
               ("ratio_p50", "ratio rsca/raw p50"), ("ratio_p99", "ratio rsca/raw p99"),
               ("ratio_direct_p50", "ratio direct rsca/raw p50"),
               ("ratio_direct_p99", "ratio direct rsca/raw p99"),
               ("ratio_same_host_p50", "ratio same-host rsca/raw p50"),
               ("ratio_same_host_iceoryx_p50", "ratio same-host rsca/iceoryx p50"),
               ("ratio_cpu", "ratio rsca/raw CPU per round trip (nodes counted)"),
               ("ratio_same_host_cpu", "ratio same-host rsca/raw CPU per round trip"))
MODE_WORDS = {"spin": f"both spinning ({SPIN_US} us after data)", "sleep": "both sleeping"}


def print_latency(results, qos):
    print(f"Round trip of a {results['payload_bytes']}-byte SampleSeq between two processes on one "
          f"host, strict ping-pong, {results['rounds']} rounds of {results['warmup_per_round']} "
          f"warm-up and {results['round_trips'] // results['rounds']} measured round trips per "
          f"side, every side in both modes in each round, in another order each round "
          f"(interleaved); clock CLOCK_MONOTONIC in the ping, each side's own; each raw pair in "
          f"one session, as the components are in their node's; QoS {qos['reliability']}, "
          f"{qos['durability']}, {qos['history']} {qos.get('depth', '')}. Modes: "
          f"spin = every receiving thread looks for more data {SPIN_US} us after data, yielding, "
          f"before it sleeps (rsca: RSCA_RECEIVE_SPIN_US={SPIN_US}, its default, which spins after "
          f"same-host data only; raw DDS and iceoryx: --spin-us {SPIN_US}); sleep = every one "
          f"sleeps at once (RSCA_RECEIVE_SPIN_US=0, --spin-us 0); one domain per mode, side by "
          f"side. CPU per round trip: both processes; for rsca through the nodes, the two node "
          f"daemons' CPU too (/proc/PID/stat over the side's whole run, its `start` included).")
    rows = [("min_us", "min"), ("p50_us", "p50"), ("p90_us", "p90"), ("p99_us", "p99"),
            ("p999_us", "p99.9"), ("max_us", "max"), ("mean_us", "mean"),
            ("cpu_us_per_round_trip", "CPU per round trip"),
            ("cpu_nodes_us_per_round_trip",
             "node daemons' CPU per round trip (in the row above through the nodes only)")]
    for mode in MODES:
        m = results["modes"][mode]
        r, w, wl = m["rsca"], m["raw"], m["raw_listener"]
        sh, ix, d = m["rsca_same_host"], m["iceoryx"], m["rsca_direct"]
        print()
        print(f"{MODE_WORDS[mode]}:")
        print()
        print("| round trip | rsca, two nodes (through the nodes) | raw Cyclone DDS (waitset) "
              "| rsca/raw | raw, rsca's wake (listener) | rsca/that | rsca, two nodes (direct DDS) "
              "| direct/raw | rsca, one node (shared memory) | same-host/raw | raw iceoryx "
              "(waitset) | same-host/iceoryx |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")

        def v(side, key):  # a figure the side does not have (node daemons: raw) is "-"
            return f"{side[key]:.1f} us" if key in side else "-"

        def q(a, b, key):
            return f"{ratio(a[key], b[key]):.2f}" if key in a and key in b else "-"
        for key, label in rows:
            print(f"| {label} | {v(r, key)} | {v(w, key)} | {q(r, w, key)} | {v(wl, key)} "
                  f"| {q(r, wl, key)} | {v(d, key)} | {q(d, w, key)} | {v(sh, key)} "
                  f"| {q(sh, w, key)} | {v(ix, key)} | {q(sh, ix, key)} |")
    print()
    for key, line in RATIO_LINES:
        for mode in MODES:
            print(f"{line}, {MODE_WORDS[mode].split(' (')[0]} = {results['modes'][mode][key]:.2f}")
    if busy_note(results):
        print(busy_note(results))


def bench_latency(args):
    orders = latency_orders(args.quick)
    count, warmup = (1000, 2000) if args.quick else (2000, 2000)  # per round
    rsca = os.path.join(args.bin, "rsca")
    raw = os.path.join(args.bin, "rsca-bench-raw")
    work = work_dir("rsca-portbench-", components_write=True)
    lease = lease_env(args.lease_ms)
    rtts = {name: array.array("Q") for order in orders[:1] for name in order}
    before = host_state()
    sides = {}
    try:
        with contextlib.ExitStack() as closing:
            for mode in MODES:
                domain = closing.enter_context(
                    Domain(rsca, nodes=2, sdrroot=SDRROOT, env=mode_domain_env(mode, lease)))
                sizes = raw_sizes(raw, domain.env)
                for name, side in latency_sides(domain, mode, args, work, count, warmup, closing,
                                                sizes).items():
                    sides[f"{name}@{mode}"] = side
            run_rounds(sides, orders, rtts)
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    qos = sides["rsca@spin"].qos
    results = {
        "payload_bytes": sizes["ping_sample_bytes"], "qos": qos, "rounds": len(orders),
        "warmup_per_round": warmup, "round_trips": len(orders) * count,
        "dds_lease_ms": args.lease_ms or "default", "host_before": before,
        "method": {"clock": "CLOCK_MONOTONIC, in each side's ping",
                   "order": "every side of both modes in each round, rotated round by round",
                   "modes": {"spin": f"rsca RSCA_RECEIVE_SPIN_US={SPIN_US} (default; after "
                                     f"same-host data only), raw and iceoryx --spin-us {SPIN_US}",
                             "sleep": "RSCA_RECEIVE_SPIN_US=0, raw and iceoryx --spin-us 0"},
                   "cpu": "utime+stime of both processes (/proc/PID/stat, getrusage); rsca "
                          "relayed: the node daemons' too"},
        "modes": {mode: mode_results({name: sides[f"{name}@{mode}"] for name in SIDES},
                                     {name: rtts[f"{name}@{mode}"] for name in SIDES})
                  for mode in MODES}}
    with open(args.out, "w") as f:
        json.dump(results, f, indent=2)
    print_latency(results, qos)
    return 0


def bench_fanout(args):
    schedule = Schedule(args.quick)
    counts = ([int(c) for c in args.subscribers.split(",")] if args.subscribers
              else [1, 10] if args.quick else [1, 10, 50, 100])
    rsca = os.path.join(args.bin, "rsca")
    raw = os.path.join(args.bin, "rsca-bench-raw")
    iceoryx = os.path.join(args.bin, "rsca-bench-iceoryx")
    work = work_dir("rsca-portbench-", components_write=True)
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
        publisher = e["rsca"].get("publisher", {})
        if publisher.get("launch_cli_ms"):
            # The set-up: every launch of the run's applications (CLI wall clock), and the
            # channel's part of it (the domain's connect steps).
            connect = sum(s.get("connect", 0) for s in publisher.get("launch_steps_ms", []))
            print(f"{n} subscribers: set up in {sum(publisher['launch_cli_ms']):.0f} ms over "
                  f"{len(publisher['launch_cli_ms'])} launch(es), connect steps {connect:.0f} ms")
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
    parser.add_argument("--hosts", action="store_true",
                        help="latency: between two network hosts (tools/hosts; needs root)")
    args = parser.parse_args()
    if args.lease_ms is None and args.benchmark == "fanout":
        args.lease_ms = FANOUT_LEASE_MS
    if args.benchmark == "latency":
        return bench_latency_hosts(args) if args.hosts else bench_latency(args)
    return bench_fanout(args)


if __name__ == "__main__":
    sys.exit(main())
