#!/usr/bin/python3
"""Google Benchmark JSON (stdin) -> a markdown table: the benchmark, its real time, and its counters.

JSON rather than CSV: Google Benchmark's CSV reporter aborts when benchmarks of one program report
different counters."""
import json
import sys

runs = json.load(sys.stdin)["benchmarks"]
fixed = {"name", "run_name", "run_type", "repetitions", "repetition_index", "threads", "iterations", "real_time",
         "cpu_time", "time_unit", "family_index", "per_family_instance_index", "aggregate_name", "aggregate_unit",
         "error_occurred", "error_message", "label", "bytes_per_second", "items_per_second"}
counters = []
for r in runs:
    for k in r:
        if k not in fixed and k not in counters:
            counters.append(k)
print("| benchmark | real time | " + " | ".join(counters) + " |")
print("|---|---:|" + "---:|" * len(counters))
for r in runs:
    if r.get("error_occurred"):
        print(f"| {r['name']} | skipped: {r.get('error_message', '')} |" + " |" * len(counters))
        continue
    vals = [f"{r[c]:.4g}" if isinstance(r.get(c), (int, float)) else str(r.get(c, "")) for c in counters]
    name = f"{r['name']} ({r['label']})" if r.get("label") else r["name"]
    print(f"| {name} | {r['real_time']:.3g} {r['time_unit']} | " + " | ".join(vals) + " |")
