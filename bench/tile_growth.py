#!/usr/bin/python3
"""Growing O over tiles, against one coordinator's order, as one JSON
(docs/design/scalability.md, "Growing in tiles").

For each seed, a street (`manisweep synth city --no-images`); on it `tiles_bench` checks the
tiles' ray counts against the whole triangulation's, grows O over 1, 2, 4 and 8 tiles in colour
phases (with the default bands of weight, and with one band for comparison) and writes the
closed surface; `manisweep evaluate` measures each against the ground truth from views 10, 30
and 50 (Sigma 0.47 m, the accuracy goal's). One tile is the untiled order.

  bench/tile_growth.py --out docs/results/tiles_growth_city60.json [--seeds 1 2 3 4] \\
      [--views 60] [--points 0] [--bands 1.25 0] [--tiles 1 2 4 8] [--work /tmp/tile_growth]
  bench/tile_growth.py --table docs/results/tiles_growth_city60.json
"""
import argparse
import json
import os
import statistics
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from accuracy_variants import parse_bench_args, provenance, run, write_result  # noqa: E402
from peer_compare import timed  # noqa: E402

VIEWS = ["10", "30", "50"]
SIGMA = "0.47"


def evaluate(manisweep, dataset, meshes, out_json, log):
    """MAE of each mesh over VIEWS, in the order given."""
    cmd = [manisweep, "evaluate", "--ground-truth", os.path.join(dataset, "gt.ply"), "--input",
           os.path.join(dataset, "scene.h5"), "--camera", *VIEWS, "--sigma", SIGMA, "--json",
           out_json]
    for mesh in meshes:
        cmd += ["--mesh", mesh]
    run(cmd, log)
    with open(out_json) as f:
        return [m["total"]["mae"] for m in json.load(f)["meshes"]]


def band_label(band):
    return "one band" if band == 0 else f"bands of {band:g}x"


def table(result):
    tiles = sorted({r["tiles"] for r in result["rows"]})
    lines = [f"{result['scene']}, seeds {', '.join(str(s) for s in result['seeds'])}: initial "
             "closed mesh's MAE (m) per seed, and its ratio to one tile's", "",
             "| growing | " + " | ".join(f"{t} tile{'s' if t > 1 else ''}" for t in tiles)
             + " |", "|---" * (len(tiles) + 1) + "|"]
    for band in result["bands"]:
        cells = []
        for t in tiles:
            rows = [r for r in result["rows"] if r["band"] == band and r["tiles"] == t]
            maes = " / ".join(f"{r['mae']:.3f}" for r in rows)
            ratios = [r["mae"] / r["untiled_mae"] for r in rows]
            cells.append(f"{maes} (ratio median {statistics.median(ratios):.2f}, "
                         f"range {min(ratios):.2f}–{max(ratios):.2f})" if t > 1 else maes)
        lines.append(f"| {band_label(band)} | " + " | ".join(cells) + " |")
    lines += ["", "| growing | tiles | rounds (median) | closed 2-manifold | ray counts = whole's |",
              "|---|---|---|---|---|"]
    for band in result["bands"]:
        for t in tiles:
            rows = [r for r in result["rows"] if r["band"] == band and r["tiles"] == t]
            lines.append(f"| {band_label(band)} | {t} | "
                         f"{statistics.median(r['rounds'] for r in rows):g} | "
                         f"{sum(r['closed_manifold'] for r in rows)} of {len(rows)} | "
                         f"{sum(r['ray_counts_equal_whole'] for r in rows)} of {len(rows)} |")
    return "\n".join(lines)


def main():
    a = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    a.add_argument("--views", type=int, default=60)
    a.add_argument("--points", type=int, default=0, help="0: the synth default")
    a.add_argument("--bands", type=float, nargs="+", default=[1.25, 0])
    a.add_argument("--tiles", type=int, nargs="+", default=[1, 2, 4, 8])
    a.add_argument("--work", default="/tmp/tile_growth")
    a.add_argument("--build", default=os.path.join(ROOT, "build"))
    args = parse_bench_args(a, table)
    manisweep = os.path.join(args.build, "app", "manisweep")
    bench = os.path.join(args.build, "bench", "tiles_bench")
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "tile_growth.log")
    rows = []
    for seed in args.seeds:
        dataset = os.path.join(args.work, f"city{args.views}-{seed}")
        if not os.path.exists(os.path.join(dataset, "scene.h5")):
            run([manisweep, "synth", "city", "--views", str(args.views), "--points",
                 str(args.points), "--seed", str(seed), "--no-images", "--output", dataset], log)
        for band in args.bands:
            out = os.path.join(dataset, f"band{band:g}")
            os.makedirs(out, exist_ok=True)
            rows_json = os.path.join(out, "tiles.json")
            _, peak = timed([bench, os.path.join(dataset, "scene.h5"), "--tiles",
                             *[str(t) for t in args.tiles], "--rays", "--grow", out, "--band",
                             str(band), "--json", rows_json], log)
            with open(rows_json) as f:
                bench_rows = json.load(f)
            maes = evaluate(manisweep, dataset, [r["growing"]["mesh"] for r in bench_rows],
                            os.path.join(out, "evaluate.json"), log)
            untiled = maes[[r["tiles"] for r in bench_rows].index(1)] if 1 in args.tiles else None
            for r, mae in zip(bench_rows, maes):
                g = r["growing"]
                rows.append({"seed": seed, "band": band, "tiles": r["tiles"], "mae": mae,
                             "untiled_mae": untiled, "outside_cells": g["outside_cells"],
                             "surface_faces": g["surface_faces"],
                             "closed_manifold": g["closed_manifold"], "rounds": g["rounds"],
                             "labels_read": g["labels_read"],
                             "ray_counts_equal_whole": r["ray_counts_equal_whole"],
                             "seconds_counting": g["seconds_counting"],
                             "seconds_growing": g["seconds_growing"], "bench_peak_rss": peak})
            print(f"seed {seed}, {band_label(band)}: MAE "
                  + ", ".join(f"{r['tiles']} tiles {m:.3f}" for r, m in zip(bench_rows, maes)),
                  flush=True)
    result = {**provenance("tile_growth"),
              "scene": f"synth city --views {args.views} --no-images"
                       + (f" --points {args.points}" if args.points else ""),
              "seeds": args.seeds, "bands": args.bands, "views": VIEWS, "sigma": float(SIGMA),
              "rows": rows}
    write_result(args.out, result, table)


if __name__ == "__main__":
    main()
