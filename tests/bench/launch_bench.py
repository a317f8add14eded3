#!/usr/bin/env python3
"""Launch and teardown at scale on a real local domain (run by tools/bench, never by ctest).

Starts `rsca domain up --nodes 10` on a DDS domain id and run folder of its own, writes chains of
N Relay components with tools/gen-app, as processes (N = 10, 100, 500) and as shared libraries in
component hosts (N = 10, 100, 1000), spread over the nodes (10, or 1 for 100 processes connected
through the node's shared memory). Everything is timed the same way on both sides: the wall
clock (time.perf_counter) around a whole command run from here, `rsca launch` (until every
component runs and every connection is matched, the CLI's start and its DDS discovery included)
against `rsca-bench-fork` (tests/bench/fork_baseline.cpp, C++):
- cold: the first launch of the chain on a fresh domain (no fork server loaded yet) against the
  first `rsca-bench-fork exec`, N fork/execs of the Relay executable at once, each waited for;
  COLD_DOMAINS fresh domains (--quick: 1), in alternate order (rsca first on even ones);
- warm: the launches that follow on the last of them (fork servers loaded) against
  `rsca-bench-fork fork`, N forks at once of a process with the component runtime loaded, each
  exiting at once: the floor of a launch from fork servers (a zygote's); 10 runs (500 and 1000:
  3; --quick: 2), in alternate order (rsca first on even runs), each launch released and its
  processes gone before the next step;
- a launch that fails counts in the medians as an infinite time (and so in the ratios), and is
  counted; so does a baseline whose children did not all start (and, for exec, execute).
It prints `launch ratio cold N processes on M nodes = R` (cold rsca / fork/exec medians) and
`launch ratio N processes on M nodes = R` (warm rsca / fork floor medians), and besides, for
information: the domain's own launch timer and steps, the CLI's release, one bare participant's
join of the running domain (`rsca-bench-raw discovery --participants 1 --existing K`) and N bare
Cyclone participants discovering each other (`rsca-bench-raw discovery`).
--executed gives the nodes DCDs whose GPP executes every process instead (fork_server false), the
launch as it was before fork servers, for a before/after in one session (its "warm" launches
execute too).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

from local_domain import Domain, cpu_ticks, dds_env, memory_kb, summary, wait_gone

# How long the DDS baseline waits for N participants to discover each other: --quick stops at
# the 2 s a launch of 100 processes has (issue 7), to stay within its two minutes.
DISCOVERY_TIMEOUT_MS = 30000
DISCOVERY_TIMEOUT_MS_QUICK = 2000
# Fresh domains, each for one cold launch (and its baseline); the warm runs on the last.
COLD_DOMAINS = 3
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def generate(n, hosted, out):
    name = f"Chain{n}{'Hosted' if hosted else ''}"
    path = subprocess.run([os.path.join(ROOT, "tools/gen-app"), "--shape", "chain",
                           "--components", str(n), "--out", out, "--name", name] +
                          (["--shared-library"] if hosted else []),
                          check=True, capture_output=True, text=True).stdout.strip()
    return path, name


def fork_baseline_ms(fork, mode, n, relay):
    """`rsca-bench-fork exec|fork --count N`, timed from here as the CLI is: (wall ms, its own
    JSON); a baseline whose children did not all start (or execute) counts as infinite."""
    command = [fork, mode, "--count", str(n)] + (["--", relay] if mode == "exec" else [])
    began = time.perf_counter()
    out = subprocess.run(command, capture_output=True, text=True, timeout=120)
    wall = (time.perf_counter() - began) * 1e3
    try:
        own = json.loads(out.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        own = {"error": (out.stderr or out.stdout)[:300]}
    return (wall if out.returncode == 0 else math.inf), own


def discovery_baseline(raw, n, env, timeout_ms):
    """`rsca-bench-raw discovery` for N participants, under a discovery tag of its own."""
    env = dict(env, RSCA_DDS_TAG=env["RSCA_DDS_TAG"] + "-discovery")
    out = subprocess.run([raw, "discovery", "--participants", str(n), "--timeout-ms",
                          str(timeout_ms)], env=env, capture_output=True, text=True,
                         timeout=timeout_ms / 1000 + 60)
    try:
        return json.loads(out.stdout)
    except ValueError:
        return {"participants": n, "error": (out.stderr or out.stdout)[:300]}


def join_baseline_ms(raw, domain, runs):
    """The join of one new participant to the running domain (issue 20's baseline): a bare
    participant, joined as a component process joins, until it has discovered the domain daemon
    and every node daemon. Median of `runs`, or None when it never settled."""
    times = []
    for _ in range(runs):
        out = subprocess.run([raw, "discovery", "--participants", "1", "--existing",
                              str(1 + domain.nodes), "--timeout-ms", "10000"], env=domain.env,
                             capture_output=True, text=True, timeout=70)
        try:
            d = json.loads(out.stdout)
        except ValueError:
            continue
        if d.get("settled") == 1:
            times.append(d["settled_max_ms"])
    return summary(times) if times else None


def host_footprint(domain, app):
    """The component hosts of a running application: how many, components per host, RSS per host
    and their CPU use over 2 s of idling (all hosts together, % of one core)."""
    shown, _ = domain.cli("show", app)
    components = shown.get("components", [])
    pids = sorted({c["pid"] for c in components if c.get("pid")})
    if not pids:
        return None
    rss = [memory_kb(p)["rss_kb"] for p in pids]
    before = sum(cpu_ticks(p) for p in pids)
    time.sleep(2.0)  # the interval CPU use is measured over
    ticks = sum(cpu_ticks(p) for p in pids) - before
    return {"hosts": len(pids), "components_per_host": len(components) / len(pids),
            "rss_kb_per_host": sorted(rss)[len(rss) // 2],
            "cpu_percent_idle": 100.0 * ticks / os.sysconf("SC_CLK_TCK") / 2.0}


def executing_nodes(count, folder):
    """DCDs of nodes node1..N whose GPP executes every process (fork_server false): the launch as
    it was before fork servers, for --executed."""
    with open(os.path.join(ROOT, "profiles/dev/nodes/node1/DeviceManager.dcd.xml")) as f:
        template = f.read()
    dcds = []
    for i in range(1, count + 1):
        text = (template.replace('name="node1"', f'name="node{i}"')
                .replace("node1:GPP_1", f"node{i}:GPP_1")
                .replace("f84aba57-3d9f-41c9-97e2-603b07e7eb5c", f"rsca-bench-executing-{i}")
                .replace("<usagename>GPP_1</usagename>",
                         '<usagename>GPP_1</usagename><componentproperties><simpleref '
                         'refid="fork_server" value="false"/></componentproperties>'))
        path = os.path.join(folder, f"node{i}.dcd.xml")
        with open(path, "w") as f:
            f.write(text)
        dcds.append((f"node{i}", path))
    return dcds


def in_turn(index, first, second):
    """Runs the two sides of a pair, rsca's (`first`) first on even indexes, else second."""
    for side in ((first, second) if index % 2 == 0 else (second, first)):
        side()


class Samples:
    """What one configuration measured: CLI wall clocks of launches (inf for a failed one) and of
    their baselines, by warmth, and what the domain said of each launch."""

    def __init__(self):
        self.cli = {"cold": [], "warm": []}
        self.base = {"cold": [], "warm": []}
        self.base_own = {"cold": [], "warm": []}  # rsca-bench-fork's own JSON
        self.domain_ms = {"cold": [], "warm": []}
        self.release = []
        self.steps = {}
        self.failures = []
        self.footprint = None


def launch_and_release(domain, name, instance, warmth, samples, hosted):
    """One `rsca launch` and its release; the release waits for the launched processes to be
    gone, so that the next step (a launch or a baseline) never meets the last one's ends."""
    reply, wall = domain.cli("launch", name, "--name", instance, "--strategy", "spread",
                             check=False)
    if "launch" not in reply:  # failed and rolled back: counted, and said why
        samples.cli[warmth].append(math.inf)
        samples.failures.append(reply.get("error", {}).get("message", str(reply))[:300])
        print(f"launch of {name} failed: {samples.failures[-1]}", file=sys.stderr)
        return
    samples.cli[warmth].append(wall)
    samples.domain_ms[warmth].append(reply["launch"]["ms"])
    for s in reply["launch"]["steps"]:
        samples.steps.setdefault(s["step"], []).append(s["ms"])
    if hosted and samples.footprint is None:
        samples.footprint = host_footprint(domain, instance)
    pids = {c["pid"] for c in reply.get("components", []) if c.get("pid")}
    _, wall = domain.cli("release", instance)
    samples.release.append(wall)
    if not wait_gone(sorted(pids), 30):
        print(f"{instance}: processes still there 30 s after the release", file=sys.stderr)


def bench_config(args, n, hosted, nodes, sdr, cold_domains, runs):
    """One configuration: `cold_domains` fresh domains, each with its cold pair; the warm pairs on
    the last one."""
    sad, name = generate(n, hosted, sdr)
    relay = os.path.join(args.bin, "rsca-relay")
    fork = os.path.join(args.bin, "rsca-bench-fork")
    raw = os.path.join(args.bin, "rsca-bench-raw")
    samples, join = Samples(), None
    dcds = executing_nodes(nodes, sdr) if args.executed else None

    def baseline(warmth):
        if hosted:  # N components in a few host processes: N processes are no baseline of it
            return
        wall, own = fork_baseline_ms(fork, "exec" if warmth == "cold" else "fork", n, relay)
        samples.base[warmth].append(wall)
        samples.base_own[warmth].append(own)
    for c in range(cold_domains):
        with Domain(os.path.join(args.bin, "rsca"), nodes=nodes, node_dcds=dcds) as domain:
            domain.cli("install", "--sdrroot", sdr, sad)
            in_turn(c, lambda: launch_and_release(domain, name, f"{name}_cold{c}", "cold",
                                                  samples, hosted),
                    lambda: baseline("cold"))
            if c < cold_domains - 1:
                continue
            for i in range(runs):
                in_turn(i, lambda: launch_and_release(domain, name, f"{name}_{i}", "warm",
                                                      samples, hosted),
                        lambda: baseline("warm"))
            if not hosted:
                join = join_baseline_ms(raw, domain, runs)
    result = {"components": n, "kind": "hosted" if hosted else "processes", "nodes": nodes,
              "failures": samples.failures, "host_footprint": samples.footprint,
              "join_ms": join, "baseline_own": samples.base_own}
    for warmth in ("cold", "warm"):
        result[f"launch_cli_{warmth}_ms"] = summary(samples.cli[warmth])
        if samples.base[warmth]:
            result[f"baseline_{warmth}_ms"] = summary(samples.base[warmth])
            result[f"ratio_{warmth}"] = (result[f"launch_cli_{warmth}_ms"]["median"] /
                                         result[f"baseline_{warmth}_ms"]["median"])
        if samples.domain_ms[warmth]:
            result[f"launch_domain_{warmth}_ms"] = summary(samples.domain_ms[warmth])
    if samples.release:
        result["release_cli_ms"] = summary(samples.release)
    result["steps_ms_median"] = {k: sorted(v)[len(v) // 2] for k, v in samples.steps.items()}
    return result


def print_results(results, args):
    print("How measured: wall clock (time.perf_counter) around whole commands on both sides, "
          "`rsca launch` (CLI start and DDS discovery included) and `rsca-bench-fork` (C++); "
          "cold = the first launch on a fresh domain (no fork server loaded) against N fork/execs "
          "of the Relay executable; warm = the launches after it against N forks of a process "
          "with the component runtime loaded (a zygote's floor); the two sides of each pair in "
          "alternate order, each launch released and its processes gone before the next step; "
          "a failed launch counts as an infinite time in the medians"
          f"{'; nodes executing every process (--executed)' if args.executed else ''}.")
    print()
    print("| components | as | nodes | cold launch (CLI) median | fork/exec median | cold/fork-exec "
          "| warm launch (CLI) median | p95 | fork floor median | warm/fork | launch (domain's "
          "timer, warm) median | release (CLI) median | failed launches |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in results:
        if "skipped" in r:
            print(f"| {r['components']} | {r['kind']} | {r['nodes']} | {r['skipped']} "
                  "| | | | | | | | | |")
            continue
        cold, warm = r["launch_cli_cold_ms"], r["launch_cli_warm_ms"]
        dom = r.get("launch_domain_warm_ms", {}).get("median", math.inf)
        rel = r.get("release_cli_ms", {}).get("median", math.inf)

        def base(warmth):  # hosted components have no process baseline
            if f"ratio_{warmth}" not in r:
                return "- | -"
            return f"{r[f'baseline_{warmth}_ms']['median']:.1f} ms | {r[f'ratio_{warmth}']:.2f}"
        print(f"| {r['components']} | {r['kind']} | {r['nodes']} | {cold['median']:.1f} ms "
              f"({cold['runs']}) | {base('cold')} | {warm['median']:.1f} ms ({warm['runs']}) | "
              f"{warm['p95']:.1f} ms | {base('warm')} | {dom:.1f} ms | {rel:.1f} ms "
              f"| {len(r['failures'])} |")
    for r in results:
        d = r.get("raw_discovery")
        if not d:
            continue
        if "settled_max_ms" in d and d["settled"] == d["participants"]:
            seen = (f"all discovered all others after {d['settled_max_ms']:.0f} ms (median "
                    f"{d['settled_median_ms']:.0f} ms)")
        else:
            seen = (f"{d.get('settled', 0)} of {d['participants']} had discovered all others "
                    f"within {d.get('timeout_ms', 0)} ms {d.get('error', '')}")
        print(f"DDS baseline at {r['components']} processes: {d['participants']} bare Cyclone "
              f"participants forked at once: {seen}")
    for r in results:
        if r.get("join_ms"):
            print(f"join of one bare participant to the domain of {r['components']} processes on "
                  f"{r['nodes']} nodes: median {r['join_ms']['median']:.0f} ms (not in the ratios)")
    executed = " with every process executed (no fork server)" if args.executed else ""
    for r in results:
        if r["kind"] != "processes" or "skipped" in r:
            continue
        failed = f", {len(r['failures'])} failed launch(es) counted" if r["failures"] else ""
        print(f"launch ratio cold {r['components']} processes on {r['nodes']} nodes = "
              f"{r['ratio_cold']:.2f} (first launch on a fresh domain "
              f"{r['launch_cli_cold_ms']['median']:.0f} ms, N fork/execs "
              f"{r['baseline_cold_ms']['median']:.0f} ms; CLI wall clock both{failed}){executed}")
        print(f"launch ratio {r['components']} processes on {r['nodes']} nodes = "
              f"{r['ratio_warm']:.2f} (warm launch {r['launch_cli_warm_ms']['median']:.0f} ms, "
              f"N forks of a loaded process {r['baseline_warm_ms']['median']:.0f} ms; CLI wall "
              f"clock both{failed}){executed}")
    measured = [r for r in results if "skipped" not in r]
    for a, b in zip(measured, measured[1:]):
        if a["kind"] != b["kind"]:
            continue
        growth = b["launch_cli_warm_ms"]["median"] / a["launch_cli_warm_ms"]["median"]
        print(f"launch growth {a['components']} -> {b['components']} components: x{growth:.1f} "
              f"(x{b['components'] / a['components']:.0f} would be linear)")
    hosted = [r for r in results if r.get("host_footprint")]
    for r in hosted:
        f = r["host_footprint"]
        print(f"component hosts at {r['components']} hosted: {f['hosts']} hosts of "
              f"{f['components_per_host']:.0f} components, {f['rss_kb_per_host'] / 1024:.1f} MB RSS "
              f"each, {f['cpu_percent_idle']:.1f} % of a core idle (all hosts)")
    if len(hosted) >= 2:
        a, b = hosted[0]["host_footprint"], hosted[-1]["host_footprint"]
        if b["components_per_host"] > a["components_per_host"]:
            per = (b["rss_kb_per_host"] - a["rss_kb_per_host"]) / (
                b["components_per_host"] - a["components_per_host"])
            print(f"per hosted component: {per:.0f} KB RSS")
    for r in measured:
        if r["failures"]:
            print(f"{len(r['failures'])} launch(es) of {r['components']} {r['kind']} failed: "
                  f"{r['failures'][0][:200]}")
        print(f"steps (median ms) at {r['components']} {r['kind']}: " +
              ", ".join(f"{k} {v:.1f}" for k, v in r["steps_ms_median"].items()))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--only", default="",
                        help="measure only these, e.g. 100p1,500p10 (components, p or h for "
                             "processes or hosted, nodes)")
    parser.add_argument("--executed", action="store_true",
                        help="nodes whose GPP executes every process (fork_server false), as "
                             "launches were before fork servers")
    parser.add_argument("--cold-domains", type=int, default=None,
                        help=f"fresh domains for the cold launches (default {COLD_DOMAINS}, "
                             "--quick 1)")
    args = parser.parse_args()
    # (components, hosted, nodes): processes on one node connect through its shared memory; on
    # ten, a chain spread over them crosses nodes at every link.
    configs = [(10, False, 10), (100, False, 1), (100, False, 10), (500, False, 10),
               (10, True, 10), (100, True, 10), (1000, True, 10)]
    runs = 2 if args.quick else 10
    cold_domains = args.cold_domains or (1 if args.quick else COLD_DOMAINS)
    results = []
    # Fresh domains for each configuration: one whose launches overload the host (its nodes miss
    # their leases) leaves the next one untouched.
    with tempfile.TemporaryDirectory(prefix="rsca-gen-") as sdr:
        only = [o for o in args.only.split(",") if o]
        for n, hosted, nodes in configs:
            kind = "hosted components" if hosted else "processes"
            if only and f"{n}{'h' if hosted else 'p'}{nodes}" not in only:
                continue
            if args.quick and n >= 100 and not hosted and nodes > 1:
                # Processes over DDS between nodes take long on this machine (docs/measurements.md),
                # too long for --quick; the DDS baseline below still runs.
                results.append({"components": n, "kind": "processes", "nodes": nodes,
                                "failures": [],
                                "skipped": "not tried with --quick (the full run tries it)"})
            else:
                print(f"launch of {n} {kind} on {nodes} nodes...", file=sys.stderr)
                results.append(bench_config(args, n, hosted, nodes, sdr, cold_domains,
                                            min(runs, 3) if n >= 500 else runs))
            if not hosted and n <= 100:  # with no domain up: only the baseline's processes run
                results[-1]["raw_discovery"] = discovery_baseline(
                    os.path.join(args.bin, "rsca-bench-raw"), n, dds_env(),
                    DISCOVERY_TIMEOUT_MS_QUICK if args.quick else DISCOVERY_TIMEOUT_MS)
    method = {"clock": "time.perf_counter around whole commands, both sides",
              "cold": "first launch on a fresh domain vs rsca-bench-fork exec (N fork/execs)",
              "warm": "later launches vs rsca-bench-fork fork (N forks of a loaded process)",
              "order": "alternate within each pair; each launch released, its processes gone",
              "failures": "a failed launch is an infinite sample", "executed": args.executed}
    with open(args.out, "w") as f:
        json.dump({"method": method, "launch": results}, f, indent=2)
    print_results(results, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
