"""What the scalability benchmarks share: their common arguments, running a logged command, a
free loopback port, writing their figures (OUT/STEM.json with the rows and how they were taken,
OUT/STEM.csv with the rows) and plotting them."""
import argparse
import csv
import json
import os
import socket
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from accuracy_variants import provenance  # noqa: E402


def argument_parser(doc):
    """The parser every scalability bench starts from: its docstring, --manisweep and --out."""
    parser = argparse.ArgumentParser(description=doc,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--manisweep", default=os.path.join(
        os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
        "build", "app", "manisweep"))
    parser.add_argument("--out", required=True)
    return parser


def run(cmd, log):
    print("+ " + " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, stdout=log, stderr=subprocess.STDOUT)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def write_figures(out, stem, setup, rows):
    """OUT/STEM.json: where and how it was taken (bench, machine, commit, date, command), `setup`
    (a dict) and "rows"; OUT/STEM.csv: the rows."""
    with open(os.path.join(out, f"{stem}.json"), "w") as f:
        json.dump({**provenance(f"scalability/{stem}"), **setup, "rows": rows}, f, indent=1)
    with open(os.path.join(out, f"{stem}.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)


def pyplot():
    """matplotlib's pyplot without a display, or an exit that says how to get it."""
    try:
        import matplotlib
    except ImportError:
        sys.exit(f"no plot: matplotlib is missing for {sys.executable} (deploy/setup.sh installs "
                 "Debian's python3-matplotlib for /usr/bin/python3); the figures are written")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt
