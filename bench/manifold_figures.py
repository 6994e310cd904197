#!/usr/bin/python3
"""The manifold reconstruction's speed and memory, and the paper's baseline beside it, as one JSON.

Speed: `manifold_bench` on synthetic blobs (48 cameras on a ring, 5 rays per point), each size
run --repeats times; the table shows the median and the range. Poisson: the manifold and
screened Poisson (Kazhdan, Debian's python3-open3d, bench/poisson_baseline.py) built from the
same points, each timed as a whole process with its peak memory, and both outputs judged by
check-mesh (topology only: `--no-self-intersections --allow-float-issues`; the comparison is
about manifoldness).

  bench/manifold_figures.py --out docs/results/manifold_figures.json \\
      [--speed 100000:6 1000000:1] [--variant LABEL=MANIFOLD_OPTIONS ...]
      [--poisson 10000 100000 1000000] [--build build]
  bench/manifold_figures.py --table docs/results/manifold_figures.json

The speed runs insert 10^4 points after the build and walk rays on 2 threads (the machines
these figures are for have 2 cores).
"""
import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from accuracy_variants import parse_bench_args, provenance, write_result  # noqa: E402
from peer_compare import timed  # noqa: E402

SPEED_COLUMNS = [
    ("DT", "seconds_triangulation", "{:.2f} s"),
    ("trace", "seconds_ray_tracing", "{:.2f} s"),
    ("grow", "seconds_growing", "{:.2f} s"),
    ("build total", "seconds_build", "{:.2f} s"),
    ("B/point (peak RSS)", "peak_rss_bytes_per_point", "{:.0f}"),
    ("cell steps per ray", "cell_steps_per_ray", "{:.0f}"),
    ("10^4 insertions", "seconds_insert", "{:.2f} s"),
    ("cells per re-walked ray", "cells_per_rewalked_ray", "{:.1f}"),
]


def run_speed(bench, points, repeats, variant, work):
    """`repeats` runs of one size with the variant's manifold options; manifold_bench's rows."""
    label, options = variant
    rows = []
    for i in range(repeats):
        path = os.path.join(work, f"speed_{label}_{points}_{i}.json")
        print(f"manifold_figures: manifold_bench {points} {options}, run {i + 1} of {repeats}",
              flush=True)
        timed([bench, str(points), "--insert", "10000", "--threads", "2", "--json", path] +
              shlex.split(options), os.path.join(work, "manifold_bench.log"))
        rows += [{**r, "variant": label, "options": options} for r in json.load(open(path))]
    return rows


def check_mesh(manisweep, mesh, work):
    """check-mesh's topological verdict on mesh: its JSON report."""
    report = os.path.join(work, os.path.basename(mesh) + ".check.json")
    subprocess.run([manisweep, "check-mesh", mesh, "--no-self-intersections",
                    "--allow-float-issues", "--log-level", "warn", "--json", report],
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    if not os.path.exists(report):
        raise SystemExit(f"check-mesh wrote no report for {mesh}")
    return json.load(open(report))


def verdict(report):
    keys = ["valid", "vertices", "faces", "boundary_edges", "non_manifold_edges",
            "non_manifold_vertices"]
    return {k: report.get(k) for k in keys}


def run_poisson(bench, manisweep, points, work):
    """The manifold and Poisson from the same blob of `points` points."""
    print(f"manifold_figures: {points} points, manifold and Poisson", flush=True)
    seconds_m, rss_m = timed([bench, str(points), "--insert", "0", "--export", work],
                             os.path.join(work, "manifold_bench.log"))
    stem = os.path.join(work, f"blob_{points}")
    seconds_p, rss_p = timed(["/usr/bin/python3", os.path.join(ROOT, "bench/poisson_baseline.py"),
                              stem + "_points.ply", stem + "_poisson.ply"], stem + "_poisson.log")
    return {"points": points,
            "manifold": {"seconds": seconds_m, "peak_rss_bytes": rss_m,
                         **verdict(check_mesh(manisweep, stem + "_manifold.ply", work))},
            "poisson": {"seconds": seconds_p, "peak_rss_bytes": rss_p,
                        **verdict(check_mesh(manisweep, stem + "_poisson.ply", work))}}


def spread(values, fmt):
    """'median (low–high)' of values, or the one value."""
    if len(values) == 1:
        return fmt.format(values[0])
    return (fmt.format(statistics.median(values)) + " (" + fmt.format(min(values)) + "–" +
            fmt.format(max(values)) + ")")


def speed_table(result):
    groups = list(dict.fromkeys((r.get("options", ""), r["points"]) for r in result["speed"]))
    lines = ["| options | points | runs | " + " | ".join(c[0] for c in SPEED_COLUMNS) + " |",
             "|---" * (len(SPEED_COLUMNS) + 3) + "|"]
    for options, n in groups:
        rows = [r for r in result["speed"] if (r.get("options", ""), r["points"]) == (options, n)]
        cells = [spread([r[key] for r in rows], fmt) for _, key, fmt in SPEED_COLUMNS]
        lines.append(f"| {'`' + options + '`' if options else 'defaults'} | {n:,} | {len(rows)} | "
                     + " | ".join(cells) + " |")
    return "\n".join(lines)


def topology(v):
    if v["valid"]:
        return "closed 2-manifold"
    parts = [f"{v[k]} {k.replace('_', ' ')}" for k in
             ("boundary_edges", "non_manifold_edges", "non_manifold_vertices") if v.get(k)]
    return "**not manifold**: " + ", ".join(parts)


def poisson_table(result):
    lines = ["| points | manifold: time | peak RSS | check-mesh | Poisson: time | vertices | "
             "peak RSS | check-mesh |", "|---|---|---|---|---|---|---|---|"]
    for row in result["poisson"]:
        m, p = row["manifold"], row["poisson"]
        lines.append(f"| {row['points']:,} | {m['seconds']:.1f} s | {m['peak_rss_bytes'] / 2**20:,.0f} "
                     f"MB | {topology(m)} | {p['seconds']:.1f} s | {p['vertices']:,} | "
                     f"{p['peak_rss_bytes'] / 2**20:,.0f} MB | {topology(p)} |")
    return "\n".join(lines)


def table(result):
    head = (f"{result['machine']['cpu']}, {result['machine']['cores']} cores, commit "
            f"{result['commit']}")
    parts = [head]
    if result.get("speed"):
        parts += ["", speed_table(result)]
    if result.get("poisson"):
        parts += ["", poisson_table(result)]
    return "\n".join(parts)


def main():
    a = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    a.add_argument("--build", default=os.path.join(ROOT, "build"))
    a.add_argument("--speed", nargs="*", default=["100000:6", "1000000:1"],
                   metavar="POINTS:RUNS")
    a.add_argument("--variant", action="append", metavar="LABEL=OPTIONS",
                   help="manifold options of the speed runs, repeatable (default: the defaults)")
    a.add_argument("--poisson", nargs="*", type=int, default=[10000, 100000, 1000000])
    a.add_argument("--work", help="folder for the meshes (default: a temporary one)")
    args = parse_bench_args(a, table)
    bench = os.path.join(args.build, "bench/manifold_bench")
    manisweep = os.path.join(args.build, "app/manisweep")
    for tool in (bench, manisweep):
        if not os.access(tool, os.X_OK):
            raise SystemExit(f"manifold_figures: {tool} is not built")
    work = args.work or tempfile.mkdtemp(prefix="manifold_figures.")
    os.makedirs(work, exist_ok=True)
    result = provenance("manifold_figures")
    result["speed"] = []
    variants = [v.partition("=")[::2] for v in (args.variant or ["defaults="])]
    for variant in variants:
        for spec in args.speed:
            points, _, runs = spec.partition(":")
            result["speed"] += run_speed(bench, int(points), int(runs or 1), variant, work)
    result["poisson"] = [run_poisson(bench, manisweep, n, work) for n in args.poisson]
    write_result(args.out, result, table)


if __name__ == "__main__":
    main()
