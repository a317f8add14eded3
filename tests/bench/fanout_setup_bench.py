#!/usr/bin/env python3
"""The fan-out's set-up alone (issue 20): BenchFanOut_N (N subscriber processes and a publisher,
port_bench_fanout.fanout_sads) launched spread on two nodes and released, R times (default 4), on
a domain of its own; per launch the CLI's wall time, the domain's steps, and the CPU time the
daemons and the component processes used (run by hand, never by ctest).

Usage: python3 tests/bench/fanout_setup_bench.py --bin build/bin [--subscribers 100] [--runs 4]
"""
import argparse
import os

from local_domain import Domain, alive, cpu_ticks, work_dir
from port_bench_fanout import Schedule, fanout_sads, wait_discovery_settled
from port_bench_helpers import SDRROOT


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", required=True)
    parser.add_argument("--subscribers", type=int, default=100)
    parser.add_argument("--runs", type=int, default=4)
    args = parser.parse_args()
    work = work_dir("rsca-fanout-setup-", components_write=True)
    sads, sdr = fanout_sads(args.subscribers, args.subscribers, Schedule(True), work)
    name, sad = sads[0]
    with Domain(os.path.join(args.bin, "rsca"), nodes=2, sdrroot=SDRROOT,
                env={"RSCA_DDS_LEASE_MS": "10000"}) as domain:
        domain.cli("--sdrroot", sdr, "install", sad)
        for run in range(args.runs):
            wait_discovery_settled()
            daemons = domain.daemon_pids()
            before = {k: cpu_ticks(p) for k, p in daemons.items()}
            reply, ms = domain.cli("launch", name, "--name", "fan", "--strategy", "spread")
            steps = {s["step"]: round(s["ms"]) for s in reply.get("launch", {}).get("steps", [])}
            used = {k: (cpu_ticks(p) - before[k]) * 10 for k, p in daemons.items()}
            ticks = sorted(cpu_ticks(p) for p in domain.components if alive(p))
            print(f"launch {run + 1}: CLI {ms:.0f} ms, steps {steps}")
            print(f"  CPU: daemons {used} ms; {len(ticks)} component processes {sum(ticks) * 10} ms "
                  f"in all, median {ticks[len(ticks) // 2] * 10} ms", flush=True)
            domain.cli("release", "fan")
            domain.components.clear()


if __name__ == "__main__":
    main()
