#!/usr/bin/python3
"""The run report's cost and weight (docs/guides/report.md): for each run folder, `manisweep report`'s
wall time and peak memory, the page's size, and how long Chromium (headless) takes to load it,
with the page's own check (images decoded, script errors). Writes one JSON (machine, commit,
date, command) and prints the markdown table docs/guides/report.md shows.

  bench/report_pages.py --out docs/results/report_pages.json LABEL=RUN_DIR [LABEL=RUN_DIR ...]
  bench/report_pages.py --table docs/results/report_pages.json
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from accuracy_variants import print_table_if_asked, provenance, write_result  # noqa: E402


def measure(manisweep, chrome, label, run_dir, work):
    page = os.path.join(work, f"{label}.html")
    timing = os.path.join(work, f"{label}.time")
    r = subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", timing, manisweep, "report", run_dir,
                        "-o", page], capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"report {run_dir} failed: {r.stderr[-2000:]}")
    seconds, rss_kb = open(timing).read().split()[-2:]
    loads = []
    check = {}
    for _ in range(3):  # the median of three loads (a shared machine)
        d = subprocess.run([chrome, "--headless", "--no-sandbox", "--disable-gpu",
                            "--virtual-time-budget=10000", f"--user-data-dir={work}/chrome",
                            "--dump-dom", "file://" + os.path.abspath(page)],
                           capture_output=True, text=True).stdout
        m = re.search(r'data-report-check="([^"]*)"', d)
        check = dict(item.split("=") for item in m.group(1).split()) if m else {}
        loads.append(int(check.get("load_ms", -1)))
    summary = json.load(open(os.path.join(run_dir, "summary.json")))
    return {"label": label, "run": run_dir, "views": summary.get("scene", {}).get("views"),
            "report_seconds": float(seconds), "report_peak_rss_mb": int(rss_kb) / 1024,
            "page_mb": os.path.getsize(page) / 1e6, "images": int(check.get("images", -1)),
            "undecoded": int(check.get("undecoded", -1)), "errors": int(check.get("errors", -1)),
            "load_ms_median": sorted(loads)[1]}


def table(result):
    lines = ["| run | views | `manisweep report` | its peak memory | page | images | "
             "Chromium load (median of 3) | undecoded / script errors |",
             "|---|---|---|---|---|---|---|---|"]
    for r in result["runs"]:
        lines.append(f"| {r['label']} | {r['views']} | {r['report_seconds']:.1f} s | "
                     f"{r['report_peak_rss_mb']:.0f} MB | {r['page_mb']:.1f} MB | {r['images']} | "
                     f"{r['load_ms_median'] / 1000:.2f} s | {r['undecoded']} / {r['errors']} |")
    m = result["machine"]
    lines.append(f"\n{m['cpu']}, {m['cores']} cores; `{result['command']}`")
    return "\n".join(lines)


def main():
    a = argparse.ArgumentParser(description=__doc__)
    a.add_argument("--manisweep", default=os.path.join(ROOT, "build/app/manisweep"))
    a.add_argument("--out", help="JSON to write")
    a.add_argument("--table", help="print the table of this JSON and exit")
    a.add_argument("runs", nargs="*", help="LABEL=RUN_DIR")
    args = a.parse_args()
    if print_table_if_asked(args.table, table):
        return 0
    chrome = shutil.which("chromium") or shutil.which("chromium-browser")
    if not chrome or not args.out or not args.runs:
        a.error("needs chromium, --out and at least one LABEL=RUN_DIR")
    with tempfile.TemporaryDirectory() as work:
        runs = [measure(args.manisweep, chrome, *spec.split("=", 1), work) for spec in args.runs]
    result = {
        **provenance("report_pages"),
        "runs": runs,
    }
    write_result(args.out, result, table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
