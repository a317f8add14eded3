#!/usr/bin/env python3
"""How much of a set of REDHAWK profiles rsca reads (issue 23; a measurement, not a test).

Runs `rsca validate --json` over each folder given (an SDR root, or any folder of *.sad.xml,
*.spd.xml, ... files) and reports: profiles accepted and refused, the refusals by rule (with one
example each), the warnings by rule, and whether every refusal names its file, line, column and
rule. Issue 23's target: at least 98% of the REDHAWK 2.2 set accepted, no crash, every refusal
located. Needs no domain: `python3 tests/bench/profile_acceptance.py --bin build/bin DIR...`.
"""
import argparse
import collections
import json
import subprocess
import sys


def validate(rsca, folder, strict):
    args = [rsca, "--json", "validate", folder] + (["--strict"] if strict else [])
    run = subprocess.run(args, capture_output=True, text=True, timeout=600)
    if run.returncode < 0 or run.returncode not in (0, 1):
        sys.exit(f"rsca validate {folder} ended with {run.returncode}: {run.stderr[-2000:]}")
    return json.loads(run.stdout)


def summarise(report):
    refusals = collections.Counter()
    examples = {}
    warnings = collections.Counter()
    unlocated = []
    for f in report["files"]:
        for d in f["diagnostics"]:
            if d["severity"] == "warning":
                warnings[d["rule"]] += 1
                continue
            refusals[d["rule"]] += 1
            examples.setdefault(d["rule"], f"{d['file']}:{d['line']}:{d['column']}: {d['message']}")
            # A problem with a whole file (line 0) is located by its file alone.
            if not d["file"] or not d["rule"] or (d["line"] > 0 and d["column"] <= 0):
                unlocated.append(d)
    return refusals, examples, warnings, unlocated


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", default="build/bin", help="where rsca is")
    parser.add_argument("--strict", action="store_true", help="validate with --strict too")
    parser.add_argument("--out", help="write the figures as JSON here")
    parser.add_argument("folders", nargs="+")
    args = parser.parse_args()
    rsca = f"{args.bin}/rsca"
    figures = {}
    for folder in args.folders:
        report = validate(rsca, folder, False)
        total = report["valid"] + report["invalid"]
        refusals, examples, warnings, unlocated = summarise(report)
        share = 100.0 * report["valid"] / total if total else 0.0
        print(f"{folder}: {total} profiles, {report['valid']} accepted ({share:.1f}%), "
              f"{report['invalid']} refused")
        for rule, n in refusals.most_common():
            print(f"  refused, {rule}: {n} (e.g. {examples[rule][:160]})")
        for rule, n in warnings.most_common():
            print(f"  warning, {rule}: {n}")
        print(f"  refusals without file, line, column or rule: {len(unlocated)}")
        entry = {"profiles": total, "accepted": report["valid"], "accepted_percent": share,
                 "refusals": dict(refusals), "warnings": dict(warnings),
                 "unlocated_refusals": len(unlocated)}
        if args.strict:
            strict = validate(rsca, folder, True)
            entry["accepted_strict"] = strict["valid"]
            print(f"  with --strict: {strict['valid']} accepted")
        figures[folder] = entry
    if args.out:
        with open(args.out, "w") as out:
            json.dump(figures, out, indent=2)


if __name__ == "__main__":
    main()
