#!/usr/bin/env python3
"""Launch, CLI round trip and footprint of a real local domain (run by tools/bench, never by ctest).

Starts `rsca domain up --nodes 2` on a DDS domain id and run folder of its own, then measures:
- launch: `rsca --json launch ProducerConsumer` (create + connect + start, every component
  running), as the domain timed it and as the CLI saw it (wall clock, including the CLI's own
  process start and DDS discovery); release (teardown) likewise;
- baseline: a plain fork/exec + wait of the same two component executables (`--help`), the cost
  of starting the processes with no middleware;
- ls: `rsca --json ls apps`, a whole CLI process per call, including DDS discovery;
- footprint: RSS and PSS of the idle daemons, and their CPU use over an idle interval.
The domain is always taken down, also on failure.
"""
import json
import os
import statistics
import subprocess
import sys
import time

from local_domain import Domain, bench_arguments, cpu_ticks, memory_kb, summary


def bench_launch(domain, sad, runs):
    domain.cli("install", sad)
    domain_ms, cli_ms, release_ms, steps = [], [], [], {}
    for i in range(runs):
        reply, wall = domain.cli("launch", "ProducerConsumer", "--name", f"bench{i}")
        cli_ms.append(wall)
        domain_ms.append(reply["launch"]["ms"])
        for s in reply["launch"]["steps"]:
            steps.setdefault(s["step"], []).append(s["ms"])
        _, wall = domain.cli("release", f"bench{i}")
        release_ms.append(wall)
    return {"launch_domain_ms": summary(domain_ms), "launch_cli_ms": summary(cli_ms),
            "release_cli_ms": summary(release_ms),
            "steps_ms_median": {k: statistics.median(v) for k, v in steps.items()}}


def bench_baseline(bin_dir, runs):
    programs = [os.path.join(bin_dir, p) for p in ("rsca-producer", "rsca-consumer")]
    times = []
    for _ in range(runs):
        started = time.perf_counter()
        procs = [subprocess.Popen([p, "--help"], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL) for p in programs]
        for p in procs:
            p.wait()
        times.append((time.perf_counter() - started) * 1e3)
    return summary(times)


def bench_footprint(domain, idle_s):
    pids = domain.daemon_pids()
    before = {name: cpu_ticks(pid) for name, pid in pids.items()}
    time.sleep(idle_s)  # the measurement itself: CPU used while nothing happens
    hz = os.sysconf("SC_CLK_TCK")
    out = {}
    for name, pid in pids.items():
        cpu = (cpu_ticks(pid) - before[name]) / hz / idle_s * 100
        out[name] = dict(memory_kb(pid), idle_cpu_percent=cpu)
    return out


def main():
    parser = bench_arguments(__doc__)
    args = parser.parse_args()
    runs = 5 if args.quick else 30
    rsca = os.path.join(args.bin, "rsca")
    sad = os.path.join(args.sdrroot, "dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml")
    results = {}
    with Domain(rsca, nodes=2) as domain:
        results["footprint"] = bench_footprint(domain, 3 if args.quick else 10)
        results["ls_apps_cli_ms"] = summary([domain.cli("ls", "apps")[1] for _ in range(runs)])
        results.update(bench_launch(domain, sad, runs))
    results["baseline_fork_exec_2_ms"] = bench_baseline(args.bin, runs)
    with open(args.out, "w") as f:
        json.dump(results, f, indent=2)

    def row(name, s, unit="ms"):
        print(f"| {name} | {s['median']:.1f} {unit} | {s['p95']:.1f} {unit} | {s['runs']} |")

    print("| measure | median | p95 | runs |")
    print("| --- | --- | --- | --- |")
    row("launch ProducerConsumer, in the domain (create+connect+start)", results["launch_domain_ms"])
    row("launch ProducerConsumer, `rsca launch` wall clock", results["launch_cli_ms"])
    row("baseline: fork/exec+wait of the 2 component executables", results["baseline_fork_exec_2_ms"])
    row("release, `rsca release` wall clock", results["release_cli_ms"])
    row("`rsca ls apps` wall clock (incl. discovery)", results["ls_apps_cli_ms"])
    print()
    print("launch steps (median ms): " + ", ".join(
        f"{k} {v:.1f}" for k, v in results["steps_ms_median"].items()))
    print()
    print("| daemon (idle) | RSS | PSS | private | CPU |")
    print("| --- | --- | --- | --- | --- |")
    for name, m in results["footprint"].items():
        print(f"| {name} | {m['rss_kb'] / 1024:.1f} MiB | {m['pss_kb'] / 1024:.1f} MiB | "
              f"{m['private_kb'] / 1024:.1f} MiB | {m['idle_cpu_percent']:.2f} % |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
