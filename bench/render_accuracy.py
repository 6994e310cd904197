#!/usr/bin/env python3
"""Renders the JSON files of bench/accuracy_variants.py into one Markdown table.

    bench/render_accuracy.py [--mesh refined] docs/results/accuracy_*.json > table.md

One row per file (scene and configuration): the median and the worst MAE of a mesh over the
variants (the closed `final.ply`, or with --mesh refined the closed `refined.ply`; files without
it are left out), then every variant's MAE, and where the figures come from (machine, commit).
"""
import json
import sys


def options_of(result):
    """The options a file ran with; a file run with an earlier commit's defaults names the
    options that give them now."""
    options = " ".join(result.get("equivalent_options") or result.get("reconstruct_options") or [])
    return options or "defaults"


def main():
    args = sys.argv[1:]
    mesh = "final"
    if args[:1] == ["--mesh"]:
        mesh, args = args[1], args[2:]
    if not args:
        sys.exit("usage: render_accuracy.py [--mesh final|refined] RESULTS.json...")
    results = []
    for path in args:
        with open(path) as f:
            result = json.load(f)
        if mesh in result["summary"]:
            results.append(result)
    variants = []
    for r in results:
        for run in r["runs"]:
            key = (run["seed"], run["format"])
            if key not in variants:
                variants.append(key)
    header = ["scene", "configuration", "runs", f"{mesh}: median", f"{mesh}: worst"]
    header += [f"seed {s} {f}" for s, f in variants]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    configurations = [(r["scene"], options_of(r)) for r in results]
    for r, configuration in zip(results, configurations):
        by_variant = {(run["seed"], run["format"]): run for run in r["runs"]}
        cell = f"`{configuration[1]}` of `{r['commit']}`"
        if configurations.count(configuration) > 1:  # the same options ran other code
            cell += f" ({r['label']})"
        s = r["summary"][mesh]
        row = [r["scene"], cell, str(len(r["runs"])), f"{s['median']:.4f}",
               f"**{s['worst']:.4f}**"]
        for key in variants:
            run = by_variant.get(key)
            row.append(f"{run[mesh].get('mae_all', run[mesh]['mae']):.4f}" if run else "")
        print("| " + " | ".join(row) + " |")
    print()
    # Each file names its metric (the pyramids' Table 1, the street's three views).
    metrics = "; ".join(sorted({r["metric"] for r in results}))
    print(f"{metrics}; closed `{mesh}.ply`, 15 iterations, 2 workers; machines: " + ", ".join(
              sorted({f"{r['machine']['cpu']} ({r['machine']['cores']} cores)" for r in results}))
          + ".")


if __name__ == "__main__":
    main()
