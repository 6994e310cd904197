#!/usr/bin/env python3
"""Adding images to a finished run (`manisweep extend`) against reconstructing them all at once.

A dataset's images are split in two: the first FIRST views (in the order the model is read:
COLMAP's image ids), and the rest. Its model
(read as COLMAP text) restricted to the first part is reconstructed; the run is then extended
with the whole model, whose old cameras have the same poses (as COLMAP's image_registrator or
point_triangulator leave them); and the whole model is reconstructed at once. Every run takes
the same options (the defaults, or those after --; 2 workers). OUT gets the times, the meshes'
vertices and their photo-consistency (`manisweep consistency` with the whole model, every
camera), and the goals of docs/design/extend.md: the extended mesh within 1 point of the full
run's, no camera of the first part lower than before the extension, the extension's time at
most 60% of the full run's (machine, commit, command, once).

On a synthetic dataset (one with gt.ply), the closed meshes' MAE against the ground truth from
--eval-views is measured too (the paper's Sigma 0.06 unless --sigma).

    bench/extend_split.py --dataset ../shared/data/castle-P30 --first 15 --out OUT.json
        [--work DIR] [--first-format text|h5] [--first-run DIR] [--full-run DIR]
        [--eval-views 10,40,80,100]
        [-- --no-refine ...]
    bench/extend_split.py --table OUT.json
"""
import argparse
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from accuracy_variants import (ROOT, print_table_if_asked, provenance, run,  # noqa: E402
                               split_run_options, write_result)
from real_sets import consistency, images_of  # noqa: E402

def text_model(manisweep, dataset, work, log):
    """The dataset's model as COLMAP text beside a link to its images; returns its folder."""
    d = os.path.join(work, "models", "whole")
    sparse = os.path.join(d, "sparse")
    if not os.path.exists(os.path.join(sparse, "points3D.txt")):
        os.makedirs(sparse, exist_ok=True)
        source = os.path.join(dataset, "scene.h5")
        if not os.path.exists(source):
            source = os.path.join(dataset, "sparse")
        run([manisweep, "convert", "--input", source, "--output", sparse, "--to", "colmap-text"],
            log)
    images = os.path.join(d, "images")
    if not os.path.exists(images):
        os.symlink(os.path.abspath(images_of(dataset)), images)
    return d


def first_part(manisweep, whole, first, fmt, work, log):
    """The whole model's first FIRST views (`convert --keep-views`: their poses, and the points at
    least two of them see), as COLMAP text (fmt "text") or scene.h5 ("h5"). Returns what
    reconstruct reads: the text model's folder, or the scene.h5 file."""
    d = os.path.join(work, "models", f"first{first}-{fmt}")
    if fmt == "h5":
        path = os.path.join(d, "scene.h5")
        if not os.path.exists(path):
            os.makedirs(d, exist_ok=True)
            run([manisweep, "convert", "--input", whole, "--output", path,
                 "--keep-views", f"0-{first - 1}"], log)
        return path
    sparse = os.path.join(d, "sparse")
    if not os.path.exists(os.path.join(sparse, "points3D.txt")):
        os.makedirs(sparse, exist_ok=True)
        run([manisweep, "convert", "--input", whole, "--output", sparse, "--to", "colmap-text",
             "--keep-views", f"0-{first - 1}"], log)
    link = os.path.join(d, "images")
    if not os.path.exists(link):
        os.symlink(os.path.abspath(os.path.join(whole, "images")), link)
    return d


def timed(cmd, log):
    start = time.monotonic()
    run(cmd, log)
    return round(time.monotonic() - start, 1)


def view_names(model):
    """The COLMAP model's image names by image id: the order manisweep reads its views in, so
    consistency's camera ids."""
    with open(os.path.join(model, "sparse", "images.txt")) as f:
        lines = [line for line in f if not line.startswith("#")]
    heads = [lines[i].split() for i in range(0, len(lines) - 1, 2)]
    return [h[9] for h in sorted(heads, key=lambda h: int(h[0]))]


def mae(manisweep, dataset, mesh, views, sigma, work, log):
    """The closed mesh's MAE (camera z) against the dataset's gt.ply from each of VIEWS, and
    their median."""
    values = []
    for v in views:
        path = os.path.join(work, "evaluate.json")
        run([manisweep, "evaluate", "--input", os.path.join(dataset, "scene.h5"),
             "--ground-truth", os.path.join(dataset, "gt.ply"), "--camera", str(v),
             "--sigma", str(sigma), "-m", mesh, "--json", path], log)
        values.append(mae_of(json.load(open(path))))
    return {"views": views, "mae": values, "median": statistics.median(values)}


def mae_of(evaluation):
    """The MAE in `manisweep evaluate --json`'s output (one mesh, one view)."""
    if isinstance(evaluation, dict):
        if "mae" in evaluation:
            return float(evaluation["mae"])
        children = evaluation.values()
    elif isinstance(evaluation, list):
        children = evaluation
    else:
        children = []
    for child in children:
        found = mae_of(child)
        if found is not None:
            return found
    return None


def main():
    argv, options = split_run_options(sys.argv[1:])
    a = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--dataset")
    a.add_argument("--first", type=int)
    a.add_argument("--out")
    a.add_argument("--work", default="/tmp/manisweep_extend_split")
    a.add_argument("--first-format", choices=["text", "h5"], default="text",
                   help="the first part's model: COLMAP text or scene.h5 (a format that must not "
                        "matter)")
    a.add_argument("--first-run", help="a finished run of the first part with the same options")
    a.add_argument("--full-run", help="a finished run of the whole model with the same options")
    a.add_argument("--eval-views", help="synthetic sets: views for the MAE, e.g. 10,40,80,100")
    a.add_argument("--sigma", type=float, default=0.06)
    a.add_argument("--manisweep", default=os.path.join(ROOT, "build", "app", "manisweep"))
    a.add_argument("--table", help="print the table of an existing JSON and exit")
    args = a.parse_args(argv)
    if print_table_if_asked(args.table, table):
        return 0
    if not (args.dataset and args.first and args.out):
        a.error("needs --dataset, --first and --out")
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "extend_split.log")
    ms = args.manisweep
    whole = text_model(ms, args.dataset, args.work, log)
    names = view_names(whole)
    if not 0 < args.first < len(names):
        a.error(f"--first {args.first}: the model has {len(names)} images")
    first = first_part(ms, whole, args.first, args.first_format, args.work, log)
    first_names = names[:args.first]
    runs = os.path.join(args.work, "runs")
    common = ["--workers", "2"] + options
    out = {"first": args.first_run or os.path.join(runs, "first"),
           "extended": os.path.join(runs, "extended"),
           "full": args.full_run or os.path.join(runs, "full")}
    given = {label for label, d in (("first", args.first_run), ("full", args.full_run)) if d}
    for label, d in out.items():
        if label not in given and os.path.exists(os.path.join(d, "run.h5")):
            sys.exit(f"{d} holds a run already: choose another --work")
    seconds = {}
    if "first" not in given:
        seconds["first"] = timed([ms, "reconstruct", "--input", first, "--output", out["first"]]
                                 + common, log)
    seconds["extend"] = timed([ms, "extend", "--run", out["first"], "--input", whole,
                               "--output", out["extended"]] + common, log)
    if "full" not in given:
        seconds["full"] = timed([ms, "reconstruct", "--input", whole, "--output", out["full"]]
                                + common, log)
    # A given run's time is the one its summary recorded (the same machine, another moment).
    for label in given:
        summary = json.load(open(os.path.join(out[label], "summary.json")))
        seconds[label] = round(summary["seconds_this_process"], 1)
    first_ids = [str(i) for i in range(args.first)]
    kinds = ["final.ply"] + (["refined.ply"] if "--no-refine" not in options else [])
    meshes = {(label, kind): os.path.join(out[label], kind) for label in out for kind in kinds}
    tables = consistency(ms, whole, list(meshes.values()), log)
    measured = dict(zip(meshes, tables))
    rows = {}
    for (label, kind), t in measured.items():
        summary = json.load(open(os.path.join(out[label], "summary.json")))
        rows[f"{label} {kind}"] = {
            "consistency": t["all"], "cameras": t["cameras"],
            "iterations": len([i for i in summary["iterations"] if i["iteration"] > 0]),
        }
    result = {**provenance("extend_split"), "dataset": os.path.basename(os.path.normpath(
        args.dataset)), "first": first_names, "first_format": args.first_format,
        "options": options, "seconds": seconds,
        "given_runs": sorted(given),
        "meshes": rows}
    goals = {}
    for kind in kinds:
        ext, full, before = (rows[f"{k} {kind}"] for k in ("extended", "full", "first"))
        drops = {c: round(ext["cameras"][c] - before["cameras"][c], 2) for c in first_ids}
        goals[kind] = {
            "extended_minus_full": round(ext["consistency"] - full["consistency"], 2),
            "first_part_lowest_change": min(drops.values()),
            "first_part_changes": drops,
        }
    goals["time_ratio"] = round(seconds["extend"] / seconds["full"], 3)
    if args.eval_views:
        views = [int(v) for v in args.eval_views.split(",")]
        result["mae"] = {f"{label} {kind}": mae(ms, args.dataset, path, views, args.sigma,
                                                args.work, log)
                         for (label, kind), path in meshes.items()}
    result["goals"] = goals
    write_result(args.out, result, table)
    return 0


def table(result):
    s = result["seconds"]
    lines = [f"{result['dataset']}: first {len(result['first'])} images, then the rest; "
             f"options: {' '.join(result['options']) or '(defaults)'}",
             "| run | seconds | mesh | photo-consistency | MAE (median of views) |",
             "|---|---|---|---|---|"]
    for name, row in result["meshes"].items():
        label, kind = name.split()
        seconds = s.get("extend" if label == "extended" else label)
        if label in result.get("given_runs", []):
            seconds = f"{seconds} (earlier)"
        mae = result.get("mae", {}).get(name)
        lines.append(f"| {label} | {seconds} | {kind} | {row['consistency']:.1f}% | "
                     f"{mae['median']:.4f} |" if mae else
                     f"| {label} | {seconds} | {kind} | {row['consistency']:.1f}% | |")
    for kind, g in result["goals"].items():
        if kind == "time_ratio":
            lines.append(f"extension time / full run: {g:.2f}")
        else:
            lines.append(f"{kind}: extended − full {g['extended_minus_full']:+.1f} points; "
                         f"lowest first-part camera {g['first_part_lowest_change']:+.1f}")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
