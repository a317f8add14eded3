#!/usr/bin/env python3
"""Launch across network hosts (issue 21; run by tools/bench, never by ctest).

Makes three network hosts with tools/hosts (namespaces joined by a bridge; needs root): the domain
daemon on the first, node1 and node2 on the others, DDS on each host's network interface. Then
launches ProducerConsumer spread over the two node hosts and releases it, 20 times (--quick: 5),
from a CLI on the domain's host, over DDS, and 20 times from a CLI through node1's control socket.
Reports, for each, the CLI's wall time from `rsca launch` to its reply (the domain replies once
every component runs and every connection is matched) and the domain's own time for the launch
(the sum of its steps). Issue 21's target: under 150 ms.
"""
import os
import statistics
import sys
import json

from local_domain import Domain, NetHosts, bench_arguments, skipped_without_hosts, summary

SAD = "dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml"


def launches(domain, runs):
    cli_ms, domain_ms = [], []
    for _ in range(runs):
        reply, ms = domain.cli("launch", "ProducerConsumer", "--strategy", "spread")
        nodes = {c["node"] for c in reply.get("components", [])}
        if nodes != {"node1", "node2"}:
            raise RuntimeError(f"placed on {sorted(nodes)}, not across both hosts")
        cli_ms.append(ms)
        domain_ms.append(sum(s["ms"] for s in reply.get("launch", {}).get("steps", [])))
        domain.cli("release", "ProducerConsumer")
        domain.components.clear()
    return {"cli_ms": summary(cli_ms), "domain_ms": summary(domain_ms)}


def main():
    args = bench_arguments(__doc__).parse_args()
    if skipped_without_hosts(args.out):
        return
    runs = 5 if args.quick else 20
    rsca = os.path.join(args.bin, "rsca")
    env = {"RSCA_DDS_INTERFACE": "eth0"}
    results = {}
    with NetHosts(3) as net:
        for way, cli_host in (("over DDS from the domain's host", net.hosts[0]),
                              ("through node1's socket", None)):
            with Domain(rsca, nodes=2, sdrroot=args.sdrroot, env=env, hosts=net.hosts,
                        cli_host=cli_host) as domain:
                domain.cli("install", os.path.join(args.sdrroot, SAD))
                results[way] = launches(domain, runs)
    json.dump(results, open(args.out, "w"), indent=2)
    print("ProducerConsumer launched across two network hosts (from `rsca launch` to running and "
          f"matched), {runs} launches each:\n")
    print("| CLI | CLI median | p95 | domain median | p95 |")
    print("| --- | --- | --- | --- | --- |")
    for way, r in results.items():
        print(f"| {way} | {r['cli_ms']['median']:.1f} ms | {r['cli_ms']['p95']:.1f} ms | "
              f"{r['domain_ms']['median']:.1f} ms | {r['domain_ms']['p95']:.1f} ms |")
    best = min(r["cli_ms"]["median"] for r in results.values())
    print(f"\nlaunch across hosts ProducerConsumer median = {best:.1f} ms (target < 150 ms)")


if __name__ == "__main__":
    sys.exit(main())
