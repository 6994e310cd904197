#!/usr/bin/env python3
"""What sweeping does to real photographs, as a distribution over input formats.

Real sets have no ground-truth mesh, so the figure is photo-consistency (`manisweep
consistency`: the share of all pixels whose NCC against a neighbour reprojected through the
mesh is above 0.8). For each DATASET (a folder with sparse/ and images, e.g.
../shared/data/fountain-P11) this reads the model in each format that must not matter (the
dataset's own COLMAP model, and the same converted to scene.h5 and to COLMAP text), runs
`manisweep reconstruct --no-refine` (the defaults, or the options after --), and measures the
initial and the swept mesh, all cameras and each camera. OUT gets every run with, per dataset,
the median and the worst gain (swept minus initial, points of photo-consistency), the lowest
per-camera gain, the vertices, and where the found points went (inserted, conflicts,
duplicates) over the iterations (machine, commit, command, once).

    bench/real_sets.py --dataset ../shared/data/fountain-P11 [--dataset ...] --out OUT.json
        [--work DIR] [--formats colmap,h5,text] [--table OUT.json] [-- --sweep.tile-size-px 50 ...]
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from accuracy_variants import (ROOT, print_table_if_asked, provenance, run,  # noqa: E402
                               split_run_options, write_result)

FORMATS = ["colmap", "h5", "text"]
ROW = re.compile(r"^(\d+|all)\s+(\d+)\s+([\d.]+)%\s+([\d.]+)%\s+([\d.]+)%\s+([\d.]+)%$")


def images_of(dataset):
    """Where the dataset's images are: images/, or beside sparse/ (the Middlebury sets)."""
    images = os.path.join(dataset, "images")
    return images if os.path.isdir(images) else dataset


def model_path(manisweep, dataset, fmt, work, log):
    """The dataset's model in FMT: its own sparse/ folder, or a conversion beside its images."""
    sparse = os.path.join(dataset, "sparse")
    if fmt == "colmap":
        return sparse
    d = os.path.join(work, "models", os.path.basename(os.path.normpath(dataset)), fmt)
    target = os.path.join(d, "scene.h5") if fmt == "h5" else os.path.join(d, "sparse")
    if not os.path.exists(target):
        os.makedirs(d, exist_ok=True)
        if fmt == "text":
            os.makedirs(target, exist_ok=True)
        run([manisweep, "convert", "--input", sparse, "--output", target]
            + (["--to", "colmap-text"] if fmt == "text" else []), log)
        images = os.path.join(d, "images")
        if not os.path.exists(images):
            os.symlink(os.path.abspath(images_of(dataset)), images)
    return target if fmt == "h5" else d


def consistency(manisweep, dataset, meshes, log):
    """Per mesh: {"all": share, "cameras": {id: share}} (shares of all pixels, in percent)."""
    cmd = [manisweep, "consistency", "--input", os.path.join(dataset, "sparse"), "--per-camera"]
    for m in meshes:
        cmd += ["-m", m]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    with open(log, "a") as f:
        f.write("+ " + " ".join(cmd) + "\n" + out)
    tables, current = [], None
    for line in out.splitlines():
        m = ROW.match(line.strip())
        if not m:
            continue
        if current is None:
            current = {"cameras": {}}
        if m.group(1) == "all":
            current["all"] = float(m.group(3))
            tables.append(current)
            current = None
        else:
            current["cameras"][m.group(1)] = float(m.group(3))
    if len(tables) != len(meshes):
        sys.exit(f"consistency printed {len(tables)} tables for {len(meshes)} meshes (see {log})")
    return tables


def measure(manisweep, dataset, fmt, work, options, log):
    name = os.path.basename(os.path.normpath(dataset))
    out = os.path.join(work, "runs", f"{name}-{fmt}")
    run([manisweep, "reconstruct", "--input", model_path(manisweep, dataset, fmt, work, log),
         "--output", out, "--workers", "2", "--no-refine"] + options, log)
    summary = json.load(open(os.path.join(out, "summary.json")))
    iterations = [i for i in summary["iterations"] if i["iteration"] > 0]
    initial, swept = consistency(manisweep, dataset, [os.path.join(out, "initial.ply"),
                                                      os.path.join(out, "final.ply")], log)
    gains = {c: round(swept["cameras"][c] - initial["cameras"][c], 2) for c in initial["cameras"]}
    row = {
        "dataset": name, "format": fmt,
        "initial": initial["all"], "swept": swept["all"],
        "gain": round(swept["all"] - initial["all"], 2),
        "camera_gains": gains, "lowest_camera_gain": min(gains.values()),
        "vertices_initial": summary["iterations"][0]["vertices"],
        "vertices_swept": iterations[-1]["vertices"] if iterations else None,
        "seconds": summary.get("seconds_this_process"),
    }
    for key in ("points_found", "points_inserted", "discarded_conflict", "discarded_duplicate",
                "discarded_outside", "witness_rays"):
        row[key] = sum(i.get(key, 0) for i in iterations)
    print(f"{name} {fmt}: {row['initial']:.1f}% -> {row['swept']:.1f}% ({row['gain']:+.1f}), "
          f"lowest camera {row['lowest_camera_gain']:+.1f}, {row['vertices_initial']} -> "
          f"{row['vertices_swept']} vertices", flush=True)
    return row


def summarise(rows):
    by_set = {}
    for r in rows:
        by_set.setdefault(r["dataset"], []).append(r)
    return {name: {"runs": len(rs),
                   "gain_median": statistics.median(r["gain"] for r in rs),
                   "gain_worst": min(r["gain"] for r in rs),
                   "lowest_camera_gain": min(r["lowest_camera_gain"] for r in rs),
                   "vertex_ratio_worst": min(r["vertices_swept"] / r["vertices_initial"]
                                             for r in rs)}
            for name, rs in by_set.items()}


def table(result):
    lines = [f"options: {' '.join(result['options']) or '(defaults)'}",
             "| set | format | initial | swept | gain | lowest camera | vertices | inserted / "
             "conflicts / duplicates |", "|---|---|---|---|---|---|---|---|"]
    for r in result["runs"]:
        lines.append(f"| {r['dataset']} | {r['format']} | {r['initial']:.1f}% | {r['swept']:.1f}% "
                     f"| {r['gain']:+.1f} | {r['lowest_camera_gain']:+.1f} | "
                     f"{r['vertices_initial']:,} → {r['vertices_swept']:,} | "
                     f"{r['points_inserted']:,} / {r['discarded_conflict']:,} / "
                     f"{r['discarded_duplicate']:,} |")
    for name, s in result["summary"].items():
        lines.append(f"{name}: gain median {s['gain_median']:+.1f}, worst {s['gain_worst']:+.1f} "
                     f"over {s['runs']} runs; lowest camera {s['lowest_camera_gain']:+.1f}; "
                     f"vertices ×{s['vertex_ratio_worst']:.2f} at least")
    return "\n".join(lines)


def main():
    argv, options = split_run_options(sys.argv[1:])
    a = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--dataset", action="append", default=[])
    a.add_argument("--out")
    a.add_argument("--work", default="/tmp/manisweep_real_sets")
    a.add_argument("--formats", default=",".join(FORMATS))
    a.add_argument("--manisweep", default=os.path.join(ROOT, "build", "app", "manisweep"))
    a.add_argument("--table", help="print the table of an existing JSON and exit")
    args = a.parse_args(argv)
    if print_table_if_asked(args.table, table):
        return 0
    if not args.dataset or not args.out:
        a.error("needs --dataset and --out")
    formats = args.formats.split(",")
    if not set(formats) <= set(FORMATS):
        a.error(f"--formats: each of {','.join(FORMATS)}")
    for d in args.dataset:
        if not os.path.isdir(os.path.join(d, "sparse")):
            a.error(f"{d}: needs a sparse/ model beside its images")
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "real_sets.log")
    rows = [measure(args.manisweep, d, fmt, args.work, options, log)
            for d in args.dataset for fmt in formats]
    result = {**provenance("real_sets"), "options": options, "summary": summarise(rows),
              "runs": rows}
    write_result(args.out, result, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
