#!/usr/bin/python3
"""Whole `manisweep reconstruct` runs: wall time, peak memory, and each iteration's seconds and
vertices from summary.json, as one JSON.

Each --run is `LABEL|INPUT|OPTIONS`: INPUT is a scene path (empty: the embedded default scene)
and OPTIONS the reconstruct options beyond `--input --output`. Runs are made --repeats times,
interleaved (A B A B ...), since the machine is shared; the table gives each run's mean seconds
per sweep iteration (range over repeats), the whole run's seconds and peak memory.

  bench/whole_runs.py --out docs/results/whole_runs_fountain-P11.json \\
      --run "half|../shared/data/fountain-P11/sparse|--workers 2 --max-iterations 2 --no-refine" \\
      --run "default scene||--workers 2"
  bench/whole_runs.py --table docs/results/whole_runs_fountain-P11.json
"""
import argparse
import json
import os
import shlex
import shutil
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from accuracy_variants import ROOT, parse_bench_args, provenance, write_result  # noqa: E402
from peer_compare import timed  # noqa: E402


def parse_run(text):
    parts = text.split("|")
    if len(parts) != 3 or not parts[0]:
        raise SystemExit(f"--run {text!r}: expected LABEL|INPUT|OPTIONS")
    return {"label": parts[0], "input": parts[1], "options": parts[2]}


def one_run(manisweep, spec, work, repeat):
    out = os.path.join(work, f"{spec['label'].replace(' ', '_')}_{repeat}")
    shutil.rmtree(out, ignore_errors=True)
    cmd = [manisweep, "reconstruct", "--output", out, "--no-report"]
    if spec["input"]:
        cmd += ["--input", spec["input"]]
    print(f"whole_runs: {spec['label']}, run {repeat + 1}", flush=True)
    seconds, peak = timed(cmd + shlex.split(spec["options"]), out + ".log")
    summary = json.load(open(os.path.join(out, "summary.json")))
    iterations = [{"iteration": i["iteration"], "vertices": i.get("vertices"),
                   "seconds_total": i.get("seconds_total"), "seconds_sweep": i.get("seconds_sweep"),
                   "seconds_insert": i.get("seconds_insert")}
                  for i in summary["iterations"]]
    shutil.rmtree(out, ignore_errors=True)  # meshes of full-size runs are large
    return {"label": spec["label"], "repeat": repeat, "seconds": seconds,
            "peak_rss_bytes": peak, "iterations": iterations}


def rng(values, fmt):
    lo, hi = fmt.format(min(values)), fmt.format(max(values))
    return lo if lo == hi else f"{lo}–{hi}"


def shown_path(path):
    """An input as the docs show it: relative to the repository, or the embedded default."""
    return os.path.relpath(path, ROOT) if path else "(embedded default)"


def table(result):
    lines = [f"{result['machine']['cpu']}, {result['machine']['cores']} cores, commit "
             f"{result['commit']}", "",
             "| run | input | options | runs | seconds per iteration (mean) | vertices at the end | "
             "whole run | peak memory |", "|---|---|---|---|---|---|---|---|"]
    for spec in result["runs"]:
        rows = [r for r in result["rows"] if r["label"] == spec["label"]]
        per_iteration = [statistics.mean(i["seconds_total"] for i in r["iterations"]
                                         if i["iteration"] > 0) for r in rows
                         if any(i["iteration"] > 0 for i in r["iterations"])]
        vertices = [r["iterations"][-1]["vertices"] for r in rows]
        lines.append(
            f"| {spec['label']} | {shown_path(spec['input'])} | `{spec['options']}` | "
            f"{len(rows)} | {rng(per_iteration, '{:.1f} s') if per_iteration else '—'} | "
            f"{rng(vertices, '{:,}')} | {rng([r['seconds'] for r in rows], '{:.0f} s')} | "
            f"{rng([r['peak_rss_bytes'] / 2**30 for r in rows], '{:.2f} GB')} |")
    return "\n".join(lines)


def main():
    a = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    a.add_argument("--manisweep", default=os.path.join(ROOT, "build/app/manisweep"))
    a.add_argument("--run", action="append", default=[], metavar="LABEL|INPUT|OPTIONS")
    a.add_argument("--repeats", type=int, default=1)
    a.add_argument("--work", default="bench_results/whole_runs")
    args = parse_bench_args(a, table)
    if not args.run:
        a.error("--run is required")
    specs = [parse_run(r) for r in args.run]
    os.makedirs(args.work, exist_ok=True)
    result = provenance("whole_runs")
    result.update({"runs": specs, "rows": []})
    for repeat in range(args.repeats):
        for spec in specs:
            result["rows"].append(one_run(args.manisweep, spec, args.work, repeat))
    write_result(args.out, result, table)


if __name__ == "__main__":
    main()
