#!/usr/bin/python3
"""The initial manifold (`manisweep manifold`: no sweep) under option variants, on synthetic
scenes against their ground truth and on real sets by photo-consistency, as one JSON.

A synthetic scene is `NAME=SYNTH_ARGUMENTS` (a `manisweep synth` command line, made once into
--work); its figure is the closed mesh's MAE (every pixel, a missed one counting 10 Σ) from the
views and at the Σ given with --views/--sigma (default: the city's views 10, 40, 80 at 0.47 m).
A real set is a folder with images/ and sparse/; its figure is the photo-consistency of all
pixels (`manisweep consistency`, images at 1536×1024).

  bench/initial_manifolds.py --out docs/results/initial_manifolds_steiner.json \\
      --scene "street-2e4=city --views 120 --points 20000 --no-images" \\
      --scene ../shared/data/castle-P30 \\
      --variant "off=--manifold.graded-steiner off" --variant "hidden="
  bench/initial_manifolds.py --table docs/results/initial_manifolds_steiner.json
"""
import argparse
import json
import os
import shlex
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from accuracy_variants import ROOT, parse_bench_args, provenance, run, write_result  # noqa: E402,E501
from real_sets import consistency  # noqa: E402


def parse_pair(text, what):
    label, sep, rest = text.partition("=")
    if not sep or not label:
        raise SystemExit(f"--{what} {text!r}: expected LABEL=...")
    return label, rest


def synth_dataset(manisweep, name, synth_args, work, log):
    d = os.path.join(work, "datasets", name)
    if not os.path.exists(os.path.join(d, "synth.json")):
        run([manisweep, "synth"] + shlex.split(synth_args) + ["--output", d], log)
    return d


def synth_mae(manisweep, dataset, mesh, views, sigma, log):
    out = mesh + ".evaluate.json"
    run([manisweep, "evaluate", "--mesh", mesh, "--ground-truth", os.path.join(dataset, "gt.ply"),
         "--input", os.path.join(dataset, "scene.h5"), "--sigma", str(sigma), "--json", out,
         "--camera"] + [str(v) for v in views], log)
    total = json.load(open(out))["meshes"][0]["total"]
    return {"mae_all": total["mae_all"], "mae": total["mae"], "coverage": total["coverage"]}


def measure(manisweep, scene, variant, args, log):
    """One initial manifold of scene under variant: time, vertices and the scene's figure."""
    name, kind, path = scene
    label, options = variant
    mesh = os.path.join(args.work, "meshes", f"{name}_{label}.ply")
    os.makedirs(os.path.dirname(mesh), exist_ok=True)
    model = os.path.join(path, "scene.h5") if kind == "synth" else os.path.join(path, "sparse")
    start = time.perf_counter()
    run([manisweep, "manifold", "--input", model, "--output", mesh] + shlex.split(options), log)
    row = {"scene": name, "variant": label, "options": options,
           "seconds": round(time.perf_counter() - start, 2)}
    if kind == "synth":
        row.update(synth_mae(manisweep, path, mesh, args.views, args.sigma, log))
    else:
        row["consistency"] = consistency(manisweep, path, [mesh], log)[0]["all"]
    figure = (f"MAE {row['mae_all']:.3f}" if kind == "synth" else f"{row['consistency']:.1f}%")
    print(f"initial_manifolds: {name} {label}: {figure} ({row['seconds']:.1f} s)", flush=True)
    return row


def table(result):
    scenes = list(dict.fromkeys(r["scene"] for r in result["rows"]))
    variants = list(dict.fromkeys(r["variant"] for r in result["rows"]))
    cell = {(r["scene"], r["variant"]): r for r in result["rows"]}

    def figure(r):
        if r is None:
            return "—"
        if "mae_all" not in r:
            return f"{r['consistency']:.1f}%"
        return f"{r['mae_all']:.{3 if r['mae_all'] >= 0.1 else 4}f} m"

    lines = [f"{result['machine']['cpu']}, commit {result['commit']}; synthetic scenes: closed "
             f"MAE from views {', '.join(map(str, result['views']))} (camera z, Σ = "
             f"{result['sigma']}); real sets: photo-consistency of all pixels", "",
             "| variant | options | " + " | ".join(scenes) + " |",
             "|---|---|" + "---|" * len(scenes)]
    for v in variants:
        options = next(r["options"] for r in result["rows"] if r["variant"] == v)
        lines.append(f"| {v} | `{options or '(defaults)'}` | " +
                     " | ".join(figure(cell.get((s, v))) for s in scenes) + " |")
    return "\n".join(lines)


def main():
    a = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    a.add_argument("--manisweep", default=os.path.join(ROOT, "build/app/manisweep"))
    a.add_argument("--scene", action="append", default=[],
                   help="NAME=SYNTH_ARGUMENTS or a real set's folder; repeatable")
    a.add_argument("--variant", action="append", default=[], metavar="LABEL=OPTIONS",
                   help="options for `manisweep manifold`; repeatable")
    a.add_argument("--views", type=int, nargs="+", default=[10, 40, 80])
    a.add_argument("--sigma", type=float, default=0.47)
    a.add_argument("--work", default="bench_results/initial_manifolds")
    args = parse_bench_args(a, table)
    if not (args.scene and args.variant):
        a.error("--scene and --variant are required")
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "log.txt")
    scenes = []
    for s in args.scene:
        if os.path.isdir(s):
            scenes.append((os.path.basename(os.path.normpath(s)), "real", s))
        else:
            name, synth_args = parse_pair(s, "scene")
            scenes.append((name, "synth", synth_dataset(args.manisweep, name, synth_args,
                                                        args.work, log)))
    variants = [parse_pair(v, "variant") for v in args.variant]
    result = provenance("initial_manifolds")
    result.update({"views": args.views, "sigma": args.sigma, "scenes": args.scene, "rows": []})
    for scene in scenes:
        for variant in variants:
            result["rows"].append(measure(args.manisweep, scene, variant, args, log))
    write_result(args.out, result, table)


if __name__ == "__main__":
    main()
