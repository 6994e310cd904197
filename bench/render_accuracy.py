#!/usr/bin/env python3
"""Renders the JSON files of bench/accuracy_variants.py into one Markdown table.

    bench/render_accuracy.py docs/results/accuracy_*.json > table.md

One row per file (scene and configuration): the median and the worst MAE of each mesh over
the variants, then every variant's final MAE, and where the figures come from (machine, commit).
"""
import json
import sys


def main():
    files = sys.argv[1:]
    if not files:
        sys.exit("usage: render_accuracy.py RESULTS.json...")
    results = []
    for path in files:
        with open(path) as f:
            results.append(json.load(f))
    variants = []
    for r in results:
        for run in r["runs"]:
            key = (run["seed"], run["format"])
            if key not in variants:
                variants.append(key)
    header = ["scene", "configuration", "runs", "final: median", "final: worst"]
    header += [f"seed {s} {f}" for s, f in variants]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for r in results:
        by_variant = {(run["seed"], run["format"]): run for run in r["runs"]}
        options = " ".join(r.get("reconstruct_options") or []) or "defaults"
        options = f"{options}` of `{r['commit']}"
        s = r["summary"]["final"]
        row = [r["scene"], f"`{options}`", str(len(r["runs"])), f"{s['median']:.4f}",
               f"**{s['worst']:.4f}**"]
        for key in variants:
            run = by_variant.get(key)
            row.append(f"{run['final'].get('mae_all', run['final']['mae']):.4f}" if run else "")
        print("| " + " | ".join(row) + " |")
    print()
    print("MAE of every ground-truth pixel from view 0 (camera z, Sigma 0.06 m), closed "
          "`final.ply`, 15 iterations, 2 workers; machines: " + ", ".join(
              sorted({f"{r['machine']['cpu']} ({r['machine']['cores']} cores)" for r in results}))
          + ".")


if __name__ == "__main__":
    main()
