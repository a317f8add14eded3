#!/usr/bin/env python3
"""Launch and teardown at scale on a real local domain (run by tools/bench, never by ctest).

Starts `rsca domain up --nodes 10` on a DDS domain id and run folder of its own, writes chains of
N Relay components with tools/gen-app, as processes (N = 10, 100) and as shared libraries in
component hosts (N = 10, 100, 1000), and for each launches and releases the chain 10 times
(500 and 1000: 3; --quick: 2, and processes over DDS between nodes only at 10), spread over
the nodes (10, or 1 for 100 processes connected through the node's shared memory):
- launch: until every component runs and every connection is matched (the domain's connect step
  waits for that before start), as the domain timed it and as the CLI saw it;
- teardown: `rsca release`, CLI wall clock (an upper bound: it includes the CLI's own start and
  DDS discovery, about 40 ms);
- baseline: a plain fork/exec of N processes of the same executable, started at once and waited
  for (they exit at once: no exec parameters), the cost of process creation alone;
- join (processes only): one bare participant joining the running domain, until it has
  discovered its daemons (`rsca-bench-raw discovery --participants 1 --existing K`); with the
  fork/exec baseline it gives issue 20's ratio, `launch ratio N processes on M nodes = R` with
  R = launch median / (fork/exec median + join median);
- DDS baseline (processes only): `rsca-bench-raw discovery`, N processes forked at once, each with
  a bare Cyclone DDS participant joined as a component process joins, and the time until each has
  discovered all the others: what launching N component processes costs DDS alone.
Growth from one N to the next says whether launch time is about linear in N.
A node forks the processes of an executable from a fork server of it (gpp/fork_servers.hpp);
--executed gives the nodes DCDs whose GPP executes every process instead (fork_server false), the
launch as it was before fork servers, for a before/after in one session.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

from local_domain import Domain, cpu_ticks, dds_env, memory_kb, summary

# How long the DDS baseline waits for N participants to discover each other: --quick stops at
# the 2 s a launch of 100 processes has (issue 7), to stay within its two minutes.
DISCOVERY_TIMEOUT_MS = 30000
DISCOVERY_TIMEOUT_MS_QUICK = 2000
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def generate(n, hosted, out):
    name = f"Chain{n}{'Hosted' if hosted else ''}"
    path = subprocess.run([os.path.join(ROOT, "tools/gen-app"), "--shape", "chain",
                           "--components", str(n), "--out", out, "--name", name] +
                          (["--shared-library"] if hosted else []),
                          check=True, capture_output=True, text=True).stdout.strip()
    return path, name


def baseline_ms(relay, n):
    began = time.perf_counter()
    procs = [subprocess.Popen([relay], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
             for _ in range(n)]
    for p in procs:
        p.wait()
    return (time.perf_counter() - began) * 1e3


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


def bench_n(domain, n, hosted, runs, sdr, relay, raw):
    sad, name = generate(n, hosted, sdr)
    domain.cli("install", "--sdrroot", sdr, sad)
    launch_domain, launch_cli, release_cli, base, steps, failures = [], [], [], [], {}, []
    footprint = None
    for i in range(runs):
        reply, wall = domain.cli("launch", name, "--name", f"{name}_{i}", "--strategy",
                                 "spread", check=False)
        if "launch" not in reply:  # failed and rolled back: say why, and go on
            failures.append(reply.get("error", {}).get("message", str(reply))[:300])
            print(f"launch of {name} failed: {failures[-1]}", file=sys.stderr)
            continue
        launch_cli.append(wall)
        launch_domain.append(reply["launch"]["ms"])
        for s in reply["launch"]["steps"]:
            steps.setdefault(s["step"], []).append(s["ms"])
        if hosted and footprint is None:
            footprint = host_footprint(domain, f"{name}_{i}")
        _, wall = domain.cli("release", f"{name}_{i}")
        release_cli.append(wall)
        base.append(baseline_ms(relay, n))
    if not launch_domain:
        return {"components": n, "kind": "hosted" if hosted else "processes",
                "nodes": domain.nodes, "failures": failures}
    return {"components": n, "kind": "hosted" if hosted else "processes", "nodes": domain.nodes,
            "failures": failures,
            "launch_domain_ms": summary(launch_domain), "launch_cli_ms": summary(launch_cli),
            "release_cli_ms": summary(release_cli), "baseline_fork_exec_ms": summary(base),
            "steps_ms_median": {k: sorted(v)[len(v) // 2] for k, v in steps.items()},
            "host_footprint": footprint,
            "join_ms": None if hosted else join_baseline_ms(raw, domain, runs)}


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
    args = parser.parse_args()
    # (components, hosted, nodes): processes on one node connect through its shared memory; on
    # ten, a chain spread over them crosses nodes at every link.
    configs = [(10, False, 10), (100, False, 1), (100, False, 10), (500, False, 10),
               (10, True, 10), (100, True, 10), (1000, True, 10)]
    runs = 2 if args.quick else 10
    rsca = os.path.join(args.bin, "rsca")
    results = []
    # A domain of its own for each configuration: one whose launches overload the host (its
    # nodes miss their leases) leaves the next one untouched.
    with tempfile.TemporaryDirectory(prefix="rsca-gen-") as sdr:
        only = [o for o in args.only.split(",") if o]
        for n, hosted, nodes in configs:
            kind = "hosted components" if hosted else "processes"
            if only and f"{n}{'h' if hosted else 'p'}{nodes}" not in only:
                continue
            if args.quick and n >= 100 and not hosted and nodes > 1:
                # Processes over DDS between nodes take long on this machine (docs/measurements.md),
                # too long for --quick; the DDS baseline below still runs.
                results.append({"components": n, "kind": kind, "nodes": nodes, "failures": [],
                                "skipped": "not tried with --quick (the full run tries it)"})
            else:
                print(f"launch of {n} {kind} on {nodes} nodes...", file=sys.stderr)
                dcds = executing_nodes(nodes, sdr) if args.executed else None
                with Domain(rsca, nodes=nodes, node_dcds=dcds) as domain:
                    n_runs = min(runs, 3) if n >= 500 else runs
                    results.append(bench_n(domain, n, hosted, n_runs, sdr,
                                           os.path.join(args.bin, "rsca-relay"),
                                           os.path.join(args.bin, "rsca-bench-raw")))
            if not hosted and n <= 100:  # with no domain up: only the baseline's processes run
                results[-1]["raw_discovery"] = discovery_baseline(
                    os.path.join(args.bin, "rsca-bench-raw"), n, dds_env(),
                    DISCOVERY_TIMEOUT_MS_QUICK if args.quick else DISCOVERY_TIMEOUT_MS)
    with open(args.out, "w") as f:
        json.dump({"launch": results}, f, indent=2)
    print("| components | as | nodes | launch (domain) median | p95 | launch (CLI) median | "
          "release (CLI) median | p95 | fork/exec baseline median |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in results:
        if "launch_domain_ms" not in r:
            why = r.get("skipped") or f"every launch failed: {r['failures'][0][:120]}"
            print(f"| {r['components']} | {r['kind']} | {r['nodes']} | {why} | | | | | |")
            continue
        print(f"| {r['components']} | {r['kind']} | {r['nodes']} | "
              f"{r['launch_domain_ms']['median']:.1f} ms | "
              f"{r['launch_domain_ms']['p95']:.1f} ms | {r['launch_cli_ms']['median']:.1f} ms | "
              f"{r['release_cli_ms']['median']:.1f} ms | {r['release_cli_ms']['p95']:.1f} ms | "
              f"{r['baseline_fork_exec_ms']['median']:.1f} ms |")
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
    # Issue 20: R = launch median / (fork/exec median + join median), same run.
    for r in results:
        if r.get("join_ms") and "launch_domain_ms" in r:
            base = r["baseline_fork_exec_ms"]["median"] + r["join_ms"]["median"]
            print(f"launch ratio {r['components']} processes on {r['nodes']} nodes = "
                  f"{r['launch_domain_ms']['median'] / base:.2f} (launch "
                  f"{r['launch_domain_ms']['median']:.0f} ms, fork/exec "
                  f"{r['baseline_fork_exec_ms']['median']:.0f} ms, join of one participant "
                  f"{r['join_ms']['median']:.0f} ms)"
                  f"{' with every process executed (no fork server)' if args.executed else ''}")
    for a, b in zip(results, results[1:]):
        if a["kind"] != b["kind"] or "launch_domain_ms" not in a or "launch_domain_ms" not in b:
            continue
        growth = b["launch_domain_ms"]["median"] / a["launch_domain_ms"]["median"]
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
    for r in results:
        if r["failures"]:
            print(f"{len(r['failures'])} launch(es) of {r['components']} {r['kind']} failed")
        if "steps_ms_median" not in r:
            continue
        print(f"steps (median ms) at {r['components']} {r['kind']}: " +
              ", ".join(f"{k} {v:.1f}" for k, v in r["steps_ms_median"].items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
