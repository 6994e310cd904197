#!/usr/bin/python3
"""What splitting a scene into tiles costs each tile, as one JSON (docs/design/scalability.md,
"Tiles").

Runs `tiles_bench` on a scene: the k-d layout, the exchange of points that makes every tile's
Delaunay stars exact, and per tile its own points, the other tiles' points it holds at the end,
and its cells. With --rays, also what counting the viewing rays costs each tile (checked
against the whole triangulation's counts); with --grow, growing O over the tiles and the
closed surface's check. A street is synthesised with `manisweep synth city --no-images`
(reused when WORK holds it already).

  bench/tile_figures.py --out docs/results/tiles_city4096.json --views 4096 --points 1000000 \\
      [--tiles 2 4 8] [--rays] [--grow] [--work /tmp/tile_figures] [--build build]
  bench/tile_figures.py --table docs/results/tiles_city4096.json
"""
import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from accuracy_variants import parse_bench_args, provenance, write_result  # noqa: E402
from peer_compare import timed  # noqa: E402


def table(result):
    lines = [f"{result['scene']}: {result['rows'][0]['scene_points']:,} points, "
             f"{result['rows'][0]['steiner_points']:,} Steiner points",
             "",
             "| tiles | exchange rounds | foreign points, all tiles | worst tile: foreign / own "
             "| largest star in a tile (cells) | exchange | colours | bench peak memory |",
             "|---|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        largest = max(t["largest_star_cells"] for t in r["per_tile"])
        lines.append(f"| {r['tiles']} | {r['rounds']} | {r['foreign_points']:,} | "
                     f"{r['worst_foreign_per_owned']:.3f} | {largest:,} | "
                     f"{r['seconds_exchange']:.0f} s | {r['colours']} | "
                     f"{r['peak_rss_bytes'] / 2**30:.2f} GiB |")
    if all("whole_ray_cell_steps" in r for r in result["rows"]):
        whole = result["rows"][0]
        lines += ["", f"Viewing rays: {whole['whole_rays']:,}; the whole triangulation's walk "
                  f"steps through {whole['whole_ray_cell_steps']:,} cells in "
                  f"{whole['whole_seconds_rays']:.0f} s (one thread).", "",
                  "| tiles | counts equal the whole's | rays walked, all tiles | cell steps, all "
                  "tiles / whole's | worst tile: cell steps / whole's | worst tile: counting |",
                  "|---|---|---|---|---|---|"]
        for r in result["rows"]:
            steps = [t["ray_cell_steps"] for t in r["per_tile"]]
            lines.append(f"| {r['tiles']} | {'yes' if r['ray_counts_equal_whole'] else 'NO'} | "
                         f"{sum(t['rays_walked'] for t in r['per_tile']):,} | "
                         f"{sum(steps) / r['whole_ray_cell_steps']:.2f} | "
                         f"{max(steps) / r['whole_ray_cell_steps']:.2f} | "
                         f"{max(t['seconds_rays'] for t in r['per_tile']):.0f} s |")
    if all("growing" in r for r in result["rows"]):
        lines += ["", "| tiles | cells in O | surface faces | closed 2-manifold | rounds | "
                  "growing (all tiles, one thread) |", "|---|---|---|---|---|---|"]
        for r in result["rows"]:
            g = r["growing"]
            lines.append(f"| {r['tiles']} | {g['outside_cells']:,} | {g['surface_faces']:,} | "
                         f"{'yes' if g['closed_manifold'] else 'NO'} | {g['rounds']} | "
                         f"{g['seconds_growing']:.0f} s |")
    return "\n".join(lines)


def main():
    a = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--views", type=int, default=4096)
    a.add_argument("--points", type=int, default=1000000)
    a.add_argument("--tiles", type=int, nargs="+", default=[2, 4, 8])
    a.add_argument("--rays", action="store_true", help="also count the rays per tile")
    a.add_argument("--grow", action="store_true", help="also grow O over the tiles")
    a.add_argument("--work", default="/tmp/tile_figures")
    a.add_argument("--build", default=os.path.join(ROOT, "build"))
    args = parse_bench_args(a, table)
    manisweep = os.path.join(args.build, "app", "manisweep")
    bench = os.path.join(args.build, "bench", "tiles_bench")
    scene = os.path.join(args.work, f"city_{args.views}_{args.points}")
    os.makedirs(args.work, exist_ok=True)
    if not os.path.exists(os.path.join(scene, "scene.h5")):
        subprocess.run([manisweep, "synth", "city", "--views", str(args.views), "--points",
                        str(args.points), "--no-images", "--output", scene], check=True)
    rows = []
    log = os.path.join(args.work, "tile_figures.log")
    for tiles in args.tiles:
        # One process per tile count, so that each peak memory is its own.
        path = os.path.join(args.work, f"tiles_{tiles}.json")
        extra = (["--rays"] if args.rays else []) + (["--grow", args.work] if args.grow else [])
        _, peak = timed([bench, os.path.join(scene, "scene.h5"), "--tiles", str(tiles),
                         "--json", path] + extra, log)
        with open(path) as f:
            row = json.load(f)[0]
        row["peak_rss_bytes"] = peak
        rows.append(row)
        print(f"{tiles} tiles: {row['foreign_points']:,} foreign points, "
              f"{row['seconds_exchange']:.0f} s", flush=True)
    result = {**provenance("tile_figures"),
              "scene": f"synth city --views {args.views} --points {args.points}",
              "rows": rows}
    write_result(args.out, result, table)


if __name__ == "__main__":
    main()
