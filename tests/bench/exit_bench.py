#!/usr/bin/env python3
"""How soon the domain knows a component process died (run by tools/bench, never by ctest).

Starts `rsca domain up --nodes 1` on a DDS domain id and run folder of its own, follows the
domain's events (`rsca --json events`), and N times (--quick: 5, else 20) launches
ProducerConsumer, kills its Producer_1 process with SIGKILL and waits for the domain's
`component.exited` event for it, then releases the application. Two figures per kill:
- decided: from the kill to the event's own timestamp (the domain daemon's clock as it published
  the event; same machine, same clock): kill -> pidfd in the node -> report over DDS -> domain;
- seen: from the kill to a follower reading the event (plus one more DDS hop to the CLI).
Target (issue 20): reported to the domain within 50 ms.
"""
import json
import os
import selectors
import signal
import subprocess
import time

from local_domain import Domain, bench_arguments, summary


class Follower:
    """`rsca --json events`, read a line at a time without Python's buffering (a buffered read
    takes several lines at once, and select() then no longer sees them)."""

    def __init__(self, rsca, env):
        self.proc = subprocess.Popen([rsca, "--json", "events"], env=env, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL)
        self.selector = selectors.DefaultSelector()
        self.selector.register(self.proc.stdout, selectors.EVENT_READ)
        self.pending = b""

    def read_until(self, predicate, timeout_s):
        """Events until one satisfies `predicate`: that one, and when it was read."""
        deadline = time.monotonic() + timeout_s
        while True:
            while b"\n" in self.pending:
                line, self.pending = self.pending.split(b"\n", 1)
                event = json.loads(line)
                if predicate(event):
                    return event, time.time_ns()
            left = deadline - time.monotonic()
            if left <= 0:
                raise RuntimeError(f"no such event within {timeout_s} s")
            if not self.selector.select(timeout=left):
                continue
            chunk = os.read(self.proc.stdout.fileno(), 65536)
            if not chunk:
                raise RuntimeError("the event follower ended")
            self.pending += chunk

    def close(self):
        self.proc.terminate()
        self.proc.wait(10)


def main():
    parser = bench_arguments(__doc__)
    args = parser.parse_args()
    runs = 5 if args.quick else 20
    rsca = os.path.join(args.bin, "rsca")
    sad = os.path.join(args.sdrroot, "dom/waveforms/ProducerConsumer/ProducerConsumer.sad.xml")
    decided, seen = [], []
    with Domain(rsca, nodes=1) as domain:
        domain.cli("install", sad)
        events = Follower(rsca, domain.env)
        try:
            # The follower has joined once it replays the domain's past (the node's arrival).
            events.read_until(lambda e: e["kind"] == "node.added", 30)
            for i in range(runs):
                name = f"exit{i}"
                reply, _ = domain.cli("launch", "ProducerConsumer", "--name", name)
                # The follower has caught up with the domain once it shows this launch.
                events.read_until(lambda e: e["kind"] == "application.created" and
                                  e["details"].get("application") == name, 30)
                pid = next(c["pid"] for c in reply["components"] if c["id"] == "Producer_1")
                killed = time.time_ns()
                os.kill(pid, signal.SIGKILL)
                event, read_at = events.read_until(
                    lambda e: e["kind"] == "component.exited" and
                    e["details"].get("application") == name, 30)
                decided.append((event["timestamp_ns"] - killed) / 1e6)
                seen.append((read_at - killed) / 1e6)
                domain.cli("release", name)
        finally:
            events.close()
    results = {"kill_to_domain_ms": summary(decided), "kill_to_follower_ms": summary(seen)}
    with open(args.out, "w") as f:
        json.dump(results, f, indent=2)
    d, s = results["kill_to_domain_ms"], results["kill_to_follower_ms"]
    print(f"component killed -> domain's component.exited: median {d['median']:.1f} ms, "
          f"max {d['max']:.1f} ms ({runs} kills); seen by a follower: median {s['median']:.1f} ms")


if __name__ == "__main__":
    main()
