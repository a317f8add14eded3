#!/usr/bin/env python3
"""Code delivered to a node (issue 21; run by tools/bench, never by ctest).

A 10 MiB component executable (the build's rsca-producer, stripped, with a section of random
bytes added so that each round is a new file) is launched on node2, whose cache does not have it:
the domain hashes it, node2 fetches it from the domain, verifies it and starts it. Then the same
application is launched again: node2 finds the package in its cache. With root, on network hosts
(tools/hosts: the domain daemon on one, node1 and node2 on others); else on this host. Reports the
CLI's wall time from `rsca launch` to running and matched, the launch's execute step, and, as the
baseline of the same run, a plain TCP copy of the same file between the same two hosts. Issue 21's
target: the first launch under 1 s, the second from the cache.

With --first-launch (issue 37): the build's own ProducerConsumer launched in a fresh domain (new
repository, empty node cache), each round twice, once with the domain delivering the files as they
are (rsca-domaind --delivery as-is: uncompressed, and whatever debug information the build left
in them; rsca_add_component splits it off at build time since issue 37, so this is no longer the
126 MB of before) and once as it does by default (stripped of debug information,
compressed): the MB delivered (the files' and on the wire) and the CLI's time of the launch.
Issue 37's target: at most 4 MB on the wire and under 300 ms.
"""
import json
import os
import re
import secrets
import shutil
import socket
import subprocess
import sys
import tempfile
import time

from local_domain import Domain, NetHosts, bench_arguments, on_host, summary

SAD = "dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml"
SIZE = 10 * 1024 * 1024


def make_executable(bin_dir, folder):
    """rsca-producer, stripped, padded to SIZE with a section of fresh random bytes."""
    stripped = os.path.join(folder, "stripped")
    subprocess.run(["strip", "-o", stripped, os.path.join(bin_dir, "rsca-producer")], check=True)
    pad = os.path.join(folder, "pad")
    with open(pad, "wb") as f:
        f.write(secrets.token_bytes(SIZE - os.path.getsize(stripped) - 4096))
    target = os.path.join(folder, "rsca-producer")
    subprocess.run(["objcopy", "--add-section", f".rsca_pad={pad}", stripped, target + ".new"],
                   check=True)
    os.chmod(target + ".new", 0o755)
    os.replace(target + ".new", target)
    return os.path.getsize(target)


def execute_ms(reply):
    for step in reply.get("launch", {}).get("steps", []):
        if step["step"] == "execute":
            return step["ms"], step["detail"]
    return None, ""


def launch_once(domain, name):
    reply, ms = domain.cli("launch", "ProducerConsumer", "--name", name,
                           "--assign", "Producer_1=node2:GPP_1", "--assign", "Consumer_1=node1:GPP_1")
    step_ms, detail = execute_ms(reply)
    domain.cli("release", name)
    domain.components.clear()
    return ms, step_ms, detail


def tcp_copy_ms(path, sender, receiver, address):
    """A plain TCP copy of `path` from host `sender` to host `receiver` (here when both None)."""
    port = 40000 + os.getpid() % 20000
    recv = subprocess.Popen(on_host(receiver, [sys.executable, "-c", (
        "import socket,sys\n"
        f"s=socket.socket(); s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)\n"
        f"s.bind(('{address}', {port})); s.listen(1); print('ready', flush=True)\n"
        "c,_=s.accept(); n=0\n"
        "while True:\n"
        "    b=c.recv(1<<20)\n"
        "    if not b: break\n"
        "    n+=len(b)\n"
        "c.sendall(str(n).encode()); c.close()\n")]), stdout=subprocess.PIPE, text=True)
    recv.stdout.readline()  # listening
    out = subprocess.run(on_host(sender, [sys.executable, "-c", (
        "import socket,sys,time\n"
        f"data=open('{path}','rb').read(); t=time.perf_counter()\n"
        f"c=socket.create_connection(('{address}', {port})); c.sendall(data)\n"
        "c.shutdown(socket.SHUT_WR); n=int(c.recv(64)); print((time.perf_counter()-t)*1e3, n)\n")]),
        capture_output=True, text=True, check=True)
    recv.wait(timeout=30)
    ms, n = out.stdout.split()
    if int(n) != os.path.getsize(path):
        raise RuntimeError("the TCP baseline lost bytes")
    return float(ms)


def rounds(domain, bin_dir, folder, runs, tcp):
    first, first_exec, again, again_exec, copies = [], [], [], [], []
    size = make_executable(bin_dir, folder)
    launch_once(domain, "Warm")  # node1 fetches the consumer once; discovery settles
    for r in range(runs):
        size = make_executable(bin_dir, folder)  # a new build: not in node2's cache
        ms, step, detail = launch_once(domain, f"First{r}")
        if "delivered" not in detail:
            raise RuntimeError(f"round {r}: nothing delivered ({detail})")
        first.append(ms)
        first_exec.append(step)
        ms, step, detail = launch_once(domain, f"Again{r}")
        if "delivered" in detail:
            raise RuntimeError(f"round {r}: the second launch fetched again ({detail})")
        again.append(ms)
        again_exec.append(step)
        copies.append(tcp(os.path.join(folder, "rsca-producer")))
    return {"size_bytes": size, "first_launch_ms": summary(first),
            "first_execute_ms": summary(first_exec), "cached_launch_ms": summary(again),
            "cached_execute_ms": summary(again_exec), "tcp_copy_ms": summary(copies)}


def delivered_mb(detail):
    """(MB of the files, MB on the wire) of an execute step's detail; (0, 0) when none."""
    m = re.search(r"([0-9.]+) MB of their files delivered \(([0-9.]+) MB on the wire\)", detail)
    return (float(m.group(1)), float(m.group(2))) if m else (0.0, 0.0)


def first_launches(args, runs):
    """Each round: a fresh domain per way of delivery, its first launch of ProducerConsumer."""
    rsca = os.path.join(args.bin, "rsca")
    results = {}
    for delivery in ("as-is", "stripped"):
        launch_ms, files_mb, wire_mb = [], [], []
        for _ in range(runs):
            with Domain(rsca, nodes=1, sdrroot=args.sdrroot,
                        domaind_args=["--delivery", delivery]) as domain:
                domain.cli("install", os.path.join(args.sdrroot, SAD))
                reply, ms = domain.cli("launch", "ProducerConsumer")
                step_ms, detail = execute_ms(reply)
                files, wire = delivered_mb(detail)
                if files == 0:
                    raise RuntimeError(f"nothing delivered ({detail})")
                launch_ms.append(ms)
                files_mb.append(files)
                wire_mb.append(wire)
                domain.cli("release", "ProducerConsumer")
        results[delivery] = {"launch_ms": summary(launch_ms), "files_mb": summary(files_mb),
                             "wire_mb": summary(wire_mb)}
    json.dump(results, open(args.out, "w"), indent=2)
    print(f"First launch of ProducerConsumer in a fresh domain, from the build in {args.bin}, "
          f"{runs} rounds:\n")
    print("| delivery | launch (CLI) median | p95 | MB of files | MB on the wire |")
    print("| --- | --- | --- | --- | --- |")
    for delivery, label in (("as-is", "as-is (the build's files, uncompressed)"),
                            ("stripped", "stripped, compressed (default)")):
        r = results[delivery]
        print(f"| {label} | {r['launch_ms']['median']:.1f} ms | {r['launch_ms']['p95']:.1f} ms | "
              f"{r['files_mb']['median']:.1f} | {r['wire_mb']['median']:.1f} |")
    s = results["stripped"]
    print(f"\nfirst launch delivered on the wire = {s['wire_mb']['median']:.1f} MB (target <= 4 MB), "
          f"launch median = {s['launch_ms']['median']:.1f} ms (target < 300 ms)")
    return 0


def main():
    parser = bench_arguments(__doc__)
    parser.add_argument("--first-launch", action="store_true",
                        help="the build's ProducerConsumer in a fresh domain, as-is and stripped")
    args = parser.parse_args()
    if args.first_launch:
        return first_launches(args, 3 if args.quick else 5)
    runs = 3 if args.quick else 10
    rsca = os.path.join(args.bin, "rsca")
    folder = tempfile.mkdtemp(prefix="rsca-delivery-")
    try:
        domaind = ["--exec-path", folder, "--exec-path", args.bin]
        why = NetHosts.unavailable()
        if why:
            print(f"no network hosts ({why}): on this host")
            with Domain(rsca, nodes=2, sdrroot=args.sdrroot, domaind_args=domaind) as domain:
                domain.cli("install", os.path.join(args.sdrroot, SAD))
                results = rounds(domain, args.bin, folder, runs,
                                 lambda p: tcp_copy_ms(p, None, None, "127.0.0.1"))
                results["where"] = "one host, loopback"
        else:
            with NetHosts(3) as net, Domain(rsca, nodes=2, sdrroot=args.sdrroot,
                                            env={"RSCA_DDS_INTERFACE": "eth0"},
                                            domaind_args=domaind, hosts=net.hosts) as domain:
                domain.cli("install", os.path.join(args.sdrroot, SAD))
                # node2 is on the third host, 10.77.0.3; the domain on the first.
                results = rounds(domain, args.bin, folder, runs,
                                 lambda p: tcp_copy_ms(p, net.hosts[0], net.hosts[2], "10.77.0.3"))
                results["where"] = "across network hosts"
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    json.dump(results, open(args.out, "w"), indent=2)
    r = results
    print(f"A {r['size_bytes'] / 2**20:.1f} MiB component executable, {runs} rounds, "
          f"{r['where']}:\n")
    print("| | median | p95 |")
    print("| --- | --- | --- |")
    for key, label in (("first_launch_ms", "first launch (CLI, to running and matched)"),
                       ("first_execute_ms", "its execute step (hash, fetch, verify, start)"),
                       ("cached_launch_ms", "second launch (CLI), from the cache"),
                       ("cached_execute_ms", "its execute step"),
                       ("tcp_copy_ms", "baseline: plain TCP copy of the file")):
        print(f"| {label} | {r[key]['median']:.1f} ms | {r[key]['p95']:.1f} ms |")
    ratio = r["first_execute_ms"]["median"] / r["tcp_copy_ms"]["median"]
    print(f"\ndelivery 10 MiB first launch median = {r['first_launch_ms']['median']:.1f} ms "
          f"(target < 1000 ms)")
    print(f"ratio delivery execute/tcp copy p50 = {ratio:.2f}")


if __name__ == "__main__":
    sys.exit(main())
