#!/usr/bin/env python3
"""Memory of the daemons over many operations (run by tools/bench, never by ctest).

Starts `rsca domain up --nodes 2` on a DDS domain id and run folder of its own and measures how
the resident memory (RSS) of rsca-domaind and each rsca-noded grows:
- cycles: `rsca launch ProducerConsumer` then `rsca release`, N times (500; --quick: 60);
- cli: `rsca ls nodes`, M times (1500; --quick: 200), each a CLI process of its own that the
  domain answers and never sees again.
Each phase begins after a warm-up (the allocator's arenas, DDS's caches and the first discovery
of every kind of process fill once), and the RSS is sampled every tenth of the phase, each time
after the domain has been left idle for a few seconds (--settle-s; the daemons give free memory
back every 5 s, common/daemon_heap.hpp), so that what is in flight does not count: the figures are
the growth from the first sample to the last, and the slope of a least-squares line through all
the samples (per cycle or per command), which one noisy sample does not move.
Issue 18's target: the cycles phase grows every daemon by less than 1 MB in all.
"""
import json
import os
import statistics
import sys
import time

from local_domain import Domain, bench_arguments, memory_kb


def rss_of(domain, settle_s):
    time.sleep(settle_s)  # idle: what the daemons hold between operations, not in flight
    return {name: memory_kb(pid)["rss_kb"] for name, pid in domain.daemon_pids().items()}


def slope(xs, ys):
    """Least-squares slope of ys over xs."""
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    var = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / var if var else 0.0


def phase(domain, label, count, warmup, step, settle_s):
    """Runs `step(i)` warm-up + count times; RSS sampled after the warm-up and every tenth."""
    for i in range(warmup):
        step(i)
    every = max(1, count // 10)
    xs, samples = [0], [rss_of(domain, settle_s)]
    for i in range(1, count + 1):
        step(warmup + i)
        if i % every == 0 or i == count:
            xs.append(i)
            samples.append(rss_of(domain, settle_s))
        if i % (every * 2) == 0:
            print(f"{label}: {i}/{count}", file=sys.stderr, flush=True)
    out = {}
    for name in samples[0]:
        ys = [s[name] for s in samples]
        out[name] = {"rss_first_kb": ys[0], "rss_last_kb": ys[-1], "growth_kb": ys[-1] - ys[0],
                     "slope_kb_per_op": slope(xs, ys), "samples_kb": ys, "at": xs}
    return out


def main():
    parser = bench_arguments(__doc__)
    parser.add_argument("--cycles", type=int)
    parser.add_argument("--commands", type=int)
    parser.add_argument("--settle-s", type=float, default=6.0)
    args = parser.parse_args()
    cycles = args.cycles or (60 if args.quick else 500)
    commands = args.commands if args.commands is not None else (200 if args.quick else 1500)
    rsca = os.path.join(args.bin, "rsca")
    sad = os.path.join(args.sdrroot,
                       "dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml")
    result = {"cycles": cycles, "commands": commands}
    with Domain(rsca, 2) as domain:
        domain.cli("install", sad)

        def cycle(i):
            domain.cli("launch", "ProducerConsumer", "--name", f"soak{i}")
            domain.cli("release", f"soak{i}")

        result["cycles_phase"] = phase(domain, "launch/release", cycles, 20, cycle, args.settle_s)
        if commands:
            result["cli_phase"] = phase(domain, "ls nodes", commands, 50,
                                        lambda i: domain.cli("ls", "nodes"), args.settle_s)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=2)

    print("| daemon | phase | operations | RSS first | RSS last | growth | slope | target |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for key, label, n, unit in (("cycles_phase", "launch+release", cycles, "cycle"),
                                ("cli_phase", "rsca ls nodes", commands, "command")):
        for name, r in result.get(key, {}).items():
            target = ""
            if key == "cycles_phase" and n >= 500:
                target = "< 1024 KB: " + ("met" if r["growth_kb"] < 1024 else "NOT MET")
            elif key == "cycles_phase":
                target = "(set over 500 cycles)"
            print(f"| {name} | {label} | {n} | {r['rss_first_kb']} KB | {r['rss_last_kb']} KB | "
                  f"{r['growth_kb']:+d} KB | {r['slope_kb_per_op']:+.2f} KB/{unit} | {target} |")


if __name__ == "__main__":
    main()
